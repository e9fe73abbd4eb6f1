"""What the referee needs from a world: the world itself (play mode, clock, score, robots) and
the trainer-style moves of robots and the ball that the rules make, as rcssserver3d makes them.

:class:`GameHost` holds one world; ``robocup-gym serve``'s host
(:class:`robocup_gym.server.worldhost.WorldHost`) is one that rebuilds its world as robots come
and go, and the soccer environments use it as it is.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["GameHost"]


class GameHost:
    """The world the rules act on (:attr:`world`: a :class:`~robocup_gym.sim.senses.Senses`
    world of either Nao engine) and the moves they make."""

    def __init__(self, world: object | None = None) -> None:
        self.world = world

    def teleport(
        self,
        index: int,
        pos: Sequence[float] | None = None,
        *,
        heading_deg: float | None = None,
        rot_deg: Sequence[float] | None = None,
    ) -> None:
        """Move robot ``index`` rigidly as rcssserver3d moves an agent: torso centre to ``pos``
        (x, y, z) with the orientation kept (``MoveAgent``), or turned upright to face
        ``heading_deg`` (``MoveAndRotateAgent``), or turned about the torso centre to the
        orientation ``rot_deg`` (``RotateAgent``); every velocity zeroed, joint angles and
        motor targets kept, and a robot that was asleep (ODE's auto-disable: resting) stays
        asleep where it is put, hanging there until its first non-zero joint velocity
        (the world's ``move_robot``). A value that is not finite changes nothing."""
        values = [*(pos or ()), *(rot_deg or ())]
        if heading_deg is not None:
            values.append(heading_deg)
        if not all(math.isfinite(float(v)) for v in values):
            return
        self.world.move_robot(index, pos, heading_deg=heading_deg, rot_deg=rot_deg)

    def shift(self, index: int, dx: float, dy: float) -> None:
        """Translate robot ``index`` by (dx, dy), keeping its height and orientation."""
        p = self.world.torso_position(index)
        self.teleport(index, (p[0] + dx, p[1] + dy, p[2]))

    def ball_touchers(self) -> set[int]:
        """Robot indices with a contact with the ball in the last physics step."""
        return self.world.ball_touchers()

    def ball_position(self) -> np.ndarray:
        """Ball centre (a copy) from the world."""
        return self.world.ball_position()

    def ball_pos_vel(self) -> tuple[list[float], list[float]]:
        """Ball position and linear velocity as lists of floats (cheap per-cycle checks)."""
        w = self.world
        return w.ball_position().tolist(), w.ball_velocity().tolist()

    def ball_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ball (position, linear velocity, angular velocity) from the world."""
        w = self.world
        return w.ball_position(), w.ball_velocity(), w.ball_angular_velocity()

    def set_ball(
        self,
        pos: Sequence[float] | None = None,
        vel: Sequence[float] | None = None,
    ) -> None:
        """Trainer-style ball placement: ``pos`` keeps the velocity unless ``vel`` is given;
        ``vel`` sets the linear velocity and zeroes the angular one."""
        p, v, w = self.ball_state()
        new_p = p if pos is None else np.asarray(pos, float)
        if vel is not None:
            v, w = np.asarray(vel, float), np.zeros(3)
        if not (np.isfinite(new_p).all() and np.isfinite(v).all()):
            return
        self.world.place_ball(new_p, v, w)

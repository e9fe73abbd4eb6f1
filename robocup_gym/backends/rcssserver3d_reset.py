"""Episode resets on a real rcssserver3d, through trainer commands.

The real server cannot set joint angles, so an episode reset (the backend's ``reset_episode``)
holds the robot in the air (trainer ``move`` to the start x/y/heading, ``hover_height`` above its
standing height) while every joint is driven to its start angle at the fastest speed the server
allows (a dead-beat velocity controller that accounts for the one-cycle command delay, clipped to
each joint's maximum speed); then one trainer frame puts the robot down at its standing height,
places the ball, sets the play mode and game time 0, and the backend steps until the monitor and
the percept show the new state. Cycles and milliseconds of every reset are in the backend's
``last_reset`` (:class:`ResetStats`).

A joint that sits on one of its stops cannot be driven off it: rcssserver3d takes a joint's new
velocity only while the joint is strictly inside its limits and otherwise keeps the old one
(reference §8.3), so a joint that the last command pushed onto a stop (a hip yaw after a fall, say)
stays there for as long as that robot lives. The reset notices such a joint (on a stop, not moving
although commanded, for :data:`PINNED_CYCLES` cycles), stops waiting for it, reports it in
:attr:`ResetStats.pinned` and logs a warning once per joint.

:class:`ServerReset` is a part of
:class:`~robocup_gym.backends.rcssserver3d_backend.Rcssserver3dBackend`.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from robocup_gym.backends.base import BackendError, EpisodeSetup, RobotPose
from robocup_gym.backends.rcssserver3d_monitor import FROZEN_CLOCK_MODES, TIME_TOLERANCE_S
from robocup_gym.protocol import trainer as tc
from robocup_gym.protocol.constants import PLAY_MODES
from robocup_gym.sim.kinematics import resting_torso_height
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import Perception

log = logging.getLogger("robocup_gym.backends.rcssserver3d")

RESET_PLAY_MODE = "BeforeKickOff"
"""The play mode while a reset drives the joints: the game is paused, so the referee's
self-collision rule (reference §9.7) releases every frozen joint and freezes none, and the
episode starts without what the last one left frozen or barred from freezing for 3 s."""

WAKE_RAD_S = 1e-4
"""Joint velocity sent with the reset's placement frame, rad/s: the smallest non-zero value of
the 4-decimal wire format, to wake the robot's bodies (see ``reset_episode``)."""

PINNED_CYCLES = 5
"""Cycles a joint must sit on a stop without moving, although commanded, to count as pinned."""

_STOP_TOLERANCE_DEG = 0.011
"""How close to a stop a perceived angle must be to count as on it (``HJ`` has 2 decimals)."""


@dataclass
class ResetStats:
    """How one :meth:`Rcssserver3dBackend.reset_episode` went."""

    cycles: int
    """Server cycles the reset took in all."""
    joint_cycles: int
    """Cycles spent driving the joints to the start pose (robot held in the air)."""
    settle_cycles: int
    """Cycles after the final trainer frame until the new state was visible."""
    ms: float
    """Wall-clock duration, ms."""
    max_joint_error_deg: float
    """Largest |start angle − perceived angle| in the returned perception, degrees."""
    converged: bool
    """Every joint the server lets move (all but :attr:`pinned`) reached the tolerance within
    ``reset_max_cycles``."""
    pinned: tuple[str, ...] = ()
    """Joints (perceptor names) that sit on a stop the server will not let them leave (see
    the module docstring); the reset did not wait for them."""


class ServerReset:
    """The episode reset of :class:`~robocup_gym.backends.rcssserver3d_backend.Rcssserver3dBackend`
    (its links, monitor tracker and options are the backend's)."""

    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        """Start an episode through trainer commands (see the module docstring).

        Unlike the embedded world this runs server cycles: the joints are driven to their start
        angles as fast as the joint speed limits allow (robot held in the air), then the robot and
        ball are placed and the play mode and game time set. The cycles the placement takes to
        show count as settle cycles. :attr:`last_reset` has the cycles and milliseconds. ``seed``
        is ignored (the server cannot be seeded).
        """
        pose, ball_pos, ball_vel, play_mode = (
            start.pose,
            start.ball_pos,
            start.ball_vel,
            start.play_mode,
        )
        if play_mode not in PLAY_MODES:
            raise ValueError(f"unknown play mode {play_mode!r}; valid: {', '.join(PLAY_MODES)}")
        if self._closed:
            raise BackendError("the backend is closed")
        self._relaunch_if_dead()
        t0 = time.perf_counter()
        if pose.quat is not None and not self.places_any_orientation:
            raise BackendError(
                "this rcssserver3d places robots upright only (the trainer's move sets a "
                "position and a heading, and it ignores the SPL fork's (rot …)); a start pose "
                "with a full orientation (quat) needs the SPL fork or an in-process engine"
            )
        target = self._start_angles(pose.joint_angles_deg)
        # a joint on a stop from the last episode cannot be driven off it: start with a new robot
        q = np.asarray(self._last.joint_angles_deg, dtype=float) if self._last else target
        lo, hi = self._ranges[:, 0], self._ranges[:, 1]
        on_stop = (q >= hi - _STOP_TOLERANCE_DEG) | (q <= lo + _STOP_TOLERANCE_DEG)
        respawned = bool((on_stop & (np.abs(target - q) > self.reset_tolerance_deg)).any())
        if respawned:
            self._respawn()
        z = float(pose.z) if pose.z is not None else self._standing_z(target)
        # held upright while the joints move: high enough that the feet of the upright robot
        # clear the ground even when the start is lower (a robot lying down)
        hover_z = max(z, self._standing_z(target)) + self.hover_height
        yaw = float(pose.heading_deg) - 90.0  # the trainer's move takes the model's raw yaw
        team = self._team
        assert self.unum is not None
        hover = tc.agent_move(self.unum, team, (pose.x, pose.y, hover_z), yaw)
        # the joints are driven with the game paused: the referee then starts no foul and frees
        # every joint its self-collision rule froze (in the last episode, or as the joints pass
        # through the body now), so that an episode starts as fresh as in-process; the episode's
        # play mode comes with the placement
        first = tc.play_mode(RESET_PLAY_MODE) + hover
        bpos = [float(v) for v in ball_pos]
        bvel = [float(v) for v in ball_vel]
        if len(bpos) != 3 or len(bvel) != 3:
            raise ValueError("ball_pos and ball_vel need 3 numbers (x, y, z)")

        # 1. hold the robot in the air, drive the joints to the start angles
        p = self._last
        assert p is not None
        tol = self.reset_tolerance_deg
        gain = self.reset_gain
        hovered = False
        joint_cycles = 0
        stuck = np.zeros(self._n, dtype=int)  # cycles on a stop without moving, commanded
        q_before = None
        while True:
            q = np.asarray(p.joint_angles_deg, dtype=float)
            q = np.where(np.isfinite(q), q, target)  # never command from a NaN reading
            # the command sent last acts in the server's next physics step, before ours does
            predicted = q + np.degrees(self._targets * CYCLE_S)
            err = target - predicted
            # a joint on a stop that should leave it: wait until it moves or counts as pinned
            off = target - q
            on_stop = (q >= hi - _STOP_TOLERANCE_DEG) | (q <= lo + _STOP_TOLERANCE_DEG)
            on_stop &= np.abs(off) > tol
            if q_before is not None:  # (the controller below keeps commanding it off the stop)
                still = np.abs(q - q_before) < _STOP_TOLERANCE_DEG
                stuck = np.where(on_stop & still, stuck + 1, 0)
            q_before = q
            pinned = stuck >= PINNED_CYCLES
            if pinned.any() and not respawned:
                # a joint that the last episode's command drove onto a stop during the first
                # cycles: a new robot, and the drive starts again (once)
                self._respawn()
                respawned = True
                p, joint_cycles, hovered, q_before = self._last, 0, False, None
                stuck[:] = 0
                continue
            done = bool(np.abs(np.where(pinned, 0.0, err)).max() <= tol)
            done = done and not (on_stop & ~pinned).any()
            # done once the joints are there with their motors at rest (the last command 0), as
            # the in-process engines place a robot
            if (done and hovered and not self._targets.any()) or (
                joint_cycles >= self.reset_max_cycles
            ):
                break
            v = np.clip(gain * np.radians(err) / CYCLE_S, -self._vmax, self._vmax)
            if done:
                v[:] = 0.0
            p = self._exchange(
                self._velocity_text(v), first if joint_cycles == 0 else hover, wait=False
            )
            joint_cycles += 1
            s = self._tracker.newest()
            if (
                s is not None
                and s.torso is not None
                and s.torso[2, 3] > hover_z - 0.5 * self.hover_height
            ):
                hovered = True
        if not done:
            log.warning(
                "reset: joints not at their start angles after %d cycles (largest error %.1f deg)",
                joint_cycles,
                float(np.abs(err).max()),
            )

        # 2. put robot and ball in place, clock and play mode; stop the joints
        if pose.quat is None:
            place = tc.agent_move(self.unum, team, (pose.x, pose.y, z), yaw)
        else:  # the fork's rot turns the robot (joints as driven) about its torso centre
            rot = tc.rot_from_quat(pose.quat)
            place = tc.agent(self.unum, team, move=(pose.x, pose.y, z, yaw), rot=rot)
        # a ball that starts moving is put down at rest, and given its velocity in the last
        # cycle of the reset (below), so that it has not rolled on by the first observation
        moving = any(bvel)
        rest = [0.0, 0.0, 0.0]
        final = (
            tc.play_mode(play_mode)
            + place
            + tc.ball(bpos, rest if moving else bvel)
            + tc.set_time(0.0)
        )
        # the two cycles after the placement get the smallest non-zero joint velocities the wire
        # carries (1e-4 rad/s: 2e-6 rad a cycle): a non-zero command wakes the joint's body, so
        # the robot is awake once it is put down, as the in-process engines place it, instead of
        # hanging asleep where the hover's idle cycles and the move left it (ODE's auto-disable).
        # Measured on rcssserver3d 0.7.3: a wake in the placement's own cycle or the next is
        # undone by the move; in the second it holds (both feet then carry ~22.5 N, as
        # in-process)
        zero = self._velocity_text(np.zeros(self._n))
        p = self._exchange(zero, final, wait=False)
        wake = self._velocity_text(np.full(self._n, WAKE_RAD_S))
        p = self._exchange(wake, wait=False)
        p = self._exchange(wake, wait=False)
        settle = 3
        deadline = time.monotonic() + self.reset_timeout
        while not self._reset_visible(p, pose, z):
            # wait (a little) for the monitor frame of this very cycle before running another:
            # the wait is bounded by the wall clock, never by how many cycles were polled
            self._sync_monitor(p)
            if self._reset_visible(p, pose, z):
                break
            if time.monotonic() > deadline:
                self._fail(
                    f"the reset did not show within {self.reset_timeout:.1f} s ({settle} cycles) "
                    "after the trainer commands (is the monitor port that of the same server?)"
                )
            p = self._exchange(self._velocity_text(np.zeros(self._n)), wait=False)
            settle += 1
        if moving:
            # a trainer command takes effect after the physics of the cycle it arrives in: the
            # ball leaves its start with its velocity in the first step, as in-process
            p = self._exchange(self._velocity_text(np.zeros(self._n)), tc.ball(bpos, bvel))
            settle += 1
        self._tracker.restart_velocities(
            bvel, p.game.game_time, p.game.play_mode not in FROZEN_CLOCK_MODES
        )
        p.ground_truth = self._ground_truth(p)
        self._last = p
        ms = (time.perf_counter() - t0) * 1e3
        off_now = np.abs(target - np.asarray(p.joint_angles_deg, dtype=float))
        err_now = float(off_now.max())
        # a joint counted as pinned that did leave its stop in the end (a slow release) is not
        pinned &= off_now > tol
        pinned_names = tuple(n for n, k in zip(self._perceptor_names, pinned, strict=True) if k)
        new_pins = set(pinned_names) - self._pins_reported
        if new_pins:
            self._pins_reported |= new_pins
            log.warning(
                "reset: %s sit(s) on a joint stop; rcssserver3d ignores velocity commands for a "
                "joint that is not strictly inside its limits (reference §8.3), so it stays there",
                ", ".join(sorted(new_pins)),
            )
        converged = done
        self.last_reset = ResetStats(
            cycles=joint_cycles + settle,
            joint_cycles=joint_cycles,
            settle_cycles=settle,
            ms=ms,
            max_joint_error_deg=err_now,
            converged=converged,
            pinned=pinned_names,
        )
        self.resets += 1
        log.debug("reset %d: %s", self.resets, self.last_reset)
        return p, settle

    @property
    def _team(self) -> str:
        """The side as the trainer's commands name it (``Left``/``Right``)."""
        return "Left" if self.side == "left" else "Right"

    @property
    def places_any_orientation(self) -> bool:
        """Whether this server's trainer turns robots (the SPL fork's ``(rot rx ry rz)``;
        upstream 0.7.3 ignores it): found out once, by turning the robot while it is held in
        the air and reading its orientation back from the monitor stream (a few cycles)."""
        if self._rot is None:
            self._rot = self._probe_rot()
        return self._rot

    def _probe_rot(self) -> bool:
        self._relaunch_if_dead()
        assert self.unum is not None
        team = self._team
        zero = self._velocity_text(np.zeros(self._n))
        high = (0.0, 0.0, 1.5)
        p = self._exchange(
            zero, tc.agent(self.unum, team, pos=high, rot=(0.0, 40.0, 0.0)), wait=False
        )
        for _ in range(3):
            p = self._exchange(zero, wait=False)
        self._sync_monitor(p)
        s = self._tracker.newest()
        if s is None or s.torso is None:
            raise BackendError("no monitor frame shows the robot (is the monitor port right?)")
        up_z = float(s.torso[2, 2])  # world z of the torso's up axis: cos 40° when turned
        self._exchange(zero, tc.agent_move(self.unum, team, high, -90.0), wait=False)
        return up_z < math.cos(math.radians(20.0))

    def _reset_visible(self, p: Perception, pose: RobotPose, z: float) -> bool:
        """Has the final trainer frame taken effect in the cycle ``p`` describes?"""
        running = p.game.play_mode not in FROZEN_CLOCK_MODES
        s = self._tracker.select(p.game.game_time, running)
        if s is None or s.torso is None:
            return False
        if (
            running
            and abs(s.game_time - p.game.game_time)
            > (self.monitor_interval - 1) * CYCLE_S + TIME_TOLERANCE_S
        ):
            return False  # the frame is not the percept's cycle
        tx, ty, tz = s.torso[:3, 3]
        return bool(tz < z + 0.5 * self.hover_height and math.hypot(tx - pose.x, ty - pose.y) < 0.1)

    def _start_angles(self, given: np.ndarray | Mapping[str, float] | None) -> np.ndarray:
        out = np.zeros(self._n)
        if given is None:
            pass
        elif isinstance(given, Mapping):
            index = {}
            for i, j in enumerate(self._model.joints):
                for alias in (j.effector, j.perceptor, j.nao_name, j.manual_name):
                    index[alias] = i
            for name, v in given.items():
                if name not in index:
                    raise KeyError(
                        f"unknown joint {name!r} for robot type {self.robot_type}; valid effector "
                        f"names: {', '.join(self._model.effector_names)}"
                    )
                out[index[name]] = float(v)
        else:
            arr = np.asarray(given, dtype=float)
            if arr.shape != (self._n,):
                raise ValueError(f"joint_angles_deg must have shape ({self._n},), got {arr.shape}")
            out[:] = arr
        if not np.isfinite(out).all():
            raise ValueError("joint_angles_deg must be finite")
        # keep targets strictly inside the stops (the server ignores commands at a stop), and
        # farther from a stop than the tolerance, so that a joint left on that stop is clearly
        # not at its target (it is either driven off the stop or counted as pinned)
        margin = max(0.05, 2.0 * self.reset_tolerance_deg)
        return np.clip(out, self._ranges[:, 0] + margin, self._ranges[:, 1] - margin)

    def _standing_z(self, angles_deg: np.ndarray) -> float:
        """Torso-centre height at which the lowest point of the upright robot in this pose
        touches the ground."""
        key = tuple(np.round(angles_deg, 2).tolist())
        z = self._stand_cache.get(key)
        if z is None:
            z = resting_torso_height(self.robot_type, np.asarray(angles_deg, float))
            if len(self._stand_cache) > 256:
                self._stand_cache.clear()
            self._stand_cache[key] = z
        return z

"""The embedded :class:`~robocup_gym.sim.engines.mujoco.world.World` behind the server, with a
changing robot set.

A ``World`` compiles its MuJoCo model once, for a fixed list of robots. Agents of the server
connect, load robots of any type (``scene``) and disconnect at any time, so :class:`WorldHost`
**rebuilds the World with state transfer** whenever the set of robots changes: the new World gets
the robots in connection order, and everything that was already there — ball, every surviving
robot's root and joint positions/velocities (matched by joint name), motor targets, team, uniform
number, sensor state, vision phase and calibration, simulation time, cycle counter, game state and
random generator — is copied over. A rebuild costs a model compilation (~20–50 ms for a few
robots); it happens only on ``scene`` and on disconnect/kill, and all changes of one cycle are
merged into one rebuild. Parked robots were rejected: every parked Nao would cost physics time in
every step.

The host also recovers from a diverged simulation (:meth:`recover`): the World is reset, each robot
is put back at its home position (its sideline slot after ``init``) and the clocks, game state and
teams are restored.
"""

from __future__ import annotations

import copy
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.memory import release_free_memory
from robocup_gym.sim.vision import VisionConfig

log = logging.getLogger("robocup_gym.server")

BALL_RADIUS = 0.042
PRE_INIT_POS = (0.0, -1.0, 1.5)
"""Where a robot appears after ``scene`` (torso centre, unrotated model: facing +y), as in the
real server; it then falls to the ground."""


@dataclass
class Slot:
    """One robot of the world: whose it is and its type."""

    key: int
    """The owner (the server's agent client id)."""
    robot_type: int
    team: str | None = None
    """``"left"``/``"right"`` once initialised (colours of a rebuilt model)."""
    home: tuple[float, float, float, float] | None = None
    """(x, y, z, heading°) to return to after a divergence reset; ``None`` = pre-init spot."""


class WorldHost:
    """Owns the current World and the mapping agent ↔ robot index.

    Args:
        vision: ``See`` settings passed to every World.
        physics: MuJoCo settings (``None`` = World default).
        seed: Seeds the server's random generator (vision noise, beam noise, calibration).
    """

    def __init__(
        self,
        vision: VisionConfig | None = None,
        physics: object | None = None,
        seed: int | None = None,
    ) -> None:
        self.vision = vision or VisionConfig()
        self.physics = physics
        self.rng = np.random.default_rng(seed)
        self.slots: list[Slot] = []
        self._index: dict[int, int] = {}
        self.world = self._new_world([])
        self.rebuilds = 0
        self.divergences = 0
        self._joint_layout: dict[str, list[tuple[str, int, int, int, int]]] = {}
        self._geom_robot: list[int] = []
        """Robot index of every geom of the current World's model (-1: not a robot's)."""
        self._ball_geom = 0
        self._refresh_maps()

    # ------------------------------------------------------------------ lookups
    def index(self, key: int) -> int | None:
        """Robot index of owner ``key`` in the current World, or ``None``."""
        return self._index.get(key)

    def slot(self, key: int) -> Slot | None:
        i = self._index.get(key)
        return None if i is None else self.slots[i]

    @property
    def n_robots(self) -> int:
        return len(self.slots)

    # ------------------------------------------------------------------ rebuild
    def _new_world(self, slots: Sequence[Slot]) -> World:
        return World(
            robot_types=[s.robot_type for s in slots],
            teams=[s.team for s in slots],
            physics=self.physics,  # type: ignore[arg-type]
            dead_time_cycles=0,
            vision=self.vision,
            seed=None,
        )

    def change_robots(self, add: Sequence[tuple[int, int]], remove: Sequence[int]) -> list[int]:
        """Add robots ``(key, type)`` and remove those of the keys in ``remove`` in one rebuild.

        New robots appear at the pre-init spot (several new ones side by side, 1 m apart in x).
        Returns the keys that were added. If the World cannot be built with the new robots (e.g.
        MuJoCo runs out of memory), the additions are dropped (logged) and only the removals are
        done.

        Raises:
            Exception: only if even the removal-only rebuild fails (the old World is kept).
        """
        remove_set = set(remove)
        keep = [s for s in self.slots if s.key not in remove_set]
        new = [Slot(key, int(t)) for key, t in add if key not in self._index]
        if not new and len(keep) == len(self.slots):
            return []
        try:
            self._rebuild(keep + new, new)
            release_free_memory()  # the old world is gone now
            return [s.key for s in new]
        except Exception as exc:
            if not new:
                raise
            log.error(
                "could not build the world with %d new robot(s) (%s); they are not created",
                len(new),
                exc,
            )
            if len(keep) != len(self.slots):
                self._rebuild(keep, [])
            return []

    def _rebuild(self, slots: list[Slot], new: list[Slot]) -> None:
        old = self.world
        old_index = dict(self._index)
        world = self._new_world(slots)
        world.rng = self.rng
        # world clocks and game state
        world.time = old.time
        world.cycle = old.cycle
        world.game = old.game
        m_old, d_old = old.model, old.data
        m_new, d_new = world.model, world.data
        # ball
        self._copy_joint_group(m_old, d_old, m_new, d_new, "ball", "ball")
        new_layout = _joint_layout(m_new, world)
        old_layout = self._joint_layout
        for j, s in enumerate(slots):
            i = old_index.get(s.key)
            r_new = world.robots[j]
            if i is None:
                continue
            r_old = old.robots[i]
            world.import_robot_state(j, old.export_robot_state(i))
            src = {name: (qa, qn, da, dn) for name, qa, qn, da, dn in old_layout[r_old.prefix]}
            for name, qa, qn, da, dn in new_layout[r_new.prefix]:
                got = src.get(name)
                if got is None or got[1] != qn or got[3] != dn:
                    continue
                d_new.qpos[qa : qa + qn] = d_old.qpos[got[0] : got[0] + qn]
                d_new.qvel[da : da + dn] = d_old.qvel[got[2] : got[2] + dn]
        self.world = world
        self.slots = slots
        self._index = {s.key: j for j, s in enumerate(slots)}
        self._joint_layout = new_layout
        for k, s in enumerate(new):
            j = self._index[s.key]
            r = world.robots[j]
            r.calibration = self.rng.uniform(-0.005, 0.005, 3)
            r.perception_counter = 0
            x, y, z = PRE_INIT_POS
            self._place_pre_init(j, x + 1.0 * k, y, z)
        world.forward()
        self._refresh_maps()
        self.rebuilds += 1

    def _place_pre_init(self, index: int, x: float, y: float, z: float) -> None:
        n = len(self.world.robots[index].model.joints)
        self.world.place_robot(index, x, y, z=z, heading_deg=90.0, joint_angles_deg=np.zeros(n))

    @staticmethod
    def _copy_joint_group(m_old, d_old, m_new, d_new, old_name: str, new_name: str) -> None:
        jo, jn = m_old.joint(old_name).id, m_new.joint(new_name).id
        qo, qn = int(m_old.jnt_qposadr[jo]), int(m_new.jnt_qposadr[jn])
        do, dn = int(m_old.jnt_dofadr[jo]), int(m_new.jnt_dofadr[jn])
        d_new.qpos[qn : qn + 7] = d_old.qpos[qo : qo + 7]
        d_new.qvel[dn : dn + 6] = d_old.qvel[do : do + 6]

    def _refresh_maps(self) -> None:
        world = self.world
        m = world.model
        if not self._joint_layout:
            self._joint_layout = _joint_layout(m, world)
        geom_robot = [-1] * m.ngeom
        for r in world.robots:
            for g in r.robot_geoms:
                geom_robot[g] = r.index
        self._geom_robot = geom_robot
        self._ball_geom = m.geom("ball").id

    # ------------------------------------------------------------------ divergence
    def recover(self) -> None:
        """Reset a diverged World and put everything back where it belongs (logged by caller).

        Clocks, game state, teams, uniform numbers and motor-free robots at their home positions
        (sideline slot or pre-init spot); the ball goes to the centre spot.
        """
        w = self.world
        keep_time, keep_cycle, keep_game = w.time, w.cycle, w.game
        keep = ("team", "team_name", "unum", "announce_team", "perception_counter")
        keep += ("calibration", "heard", "hear_capacity")
        saved = [{f: copy.copy(getattr(r, f)) for f in keep} for r in w.robots]
        w.reset()
        w.rng = self.rng
        w.time, w.cycle, w.game = keep_time, keep_cycle, keep_game
        for j, (r, s) in enumerate(zip(w.robots, self.slots, strict=True)):
            for f, v in saved[j].items():
                setattr(r, f, v)
            if s.home is None:
                x, y, z = PRE_INIT_POS
                self._place_pre_init(j, x, y, z)
            else:
                hx, hy, hz, heading = s.home
                w.place_robot(j, hx, hy, z=hz, heading_deg=heading)
        w.place_ball((0.0, 0.0, BALL_RADIUS))
        self.divergences += 1

    def sane(self) -> bool:
        """False if the state is finite but absurd (a body 100 m away, a joint turned 1000 rad):
        an instability the World's own check did not catch."""
        d = self.world.data
        return bool(np.abs(d.qpos).max(initial=0.0) < 1e3 and np.abs(d.xpos).max() < 100.0)

    # ------------------------------------------------------------------ helpers for the rules
    def teleport(
        self,
        index: int,
        pos: Sequence[float],
        *,
        heading_deg: float | None = None,
        quat: Sequence[float] | None = None,
    ) -> None:
        """Move robot ``index`` rigidly: torso centre to ``pos`` (x, y, z), orientation kept
        (or upright with ``heading_deg``, or ``quat``), joint angles and motor targets kept,
        every velocity zeroed (SimSpark's ``MoveAgent`` / ``MoveAndRotateAgent``).

        A robot whose motors are all at rest (every target 0) is left asleep where it was put,
        as on rcssserver3d: ODE's auto-disable keeps a resting robot's bodies disabled through
        a move, so it hangs there (e.g. 2 mm above the floor: accelerometer 9.81, gyro 0, no
        foot contact) until its first non-zero joint velocity (fixtures README)."""
        w = self.world
        r = w.robots[index]
        x, y, z = (float(v) for v in pos)
        if not all(math.isfinite(v) for v in (x, y, z)):
            return
        targets = r.targets.copy()
        asleep = not np.any(targets)
        if heading_deg is not None:
            w.place_robot(index, x, y, z=z, heading_deg=heading_deg, asleep=asleep)
        else:
            a = r.qpos_root
            q = w.data.qpos[a + 3 : a + 7].copy() if quat is None else np.asarray(quat, float)
            w.place_robot(index, x, y, z=z, quat=q, asleep=asleep)
        r.targets[:] = targets

    def shift(self, index: int, dx: float, dy: float) -> None:
        """Translate robot ``index`` by (dx, dy), keeping its height and orientation."""
        p = self.world.torso_position(index)
        self.teleport(index, (p[0] + dx, p[1] + dy, p[2]))

    def ball_touchers(self) -> set[int]:
        """Robot indices with a contact with the ball after the last physics step."""
        d = self.world.data
        ncon = d.ncon
        out: set[int] = set()
        if ncon == 0:
            return out
        ball = self._ball_geom
        geom_robot = self._geom_robot
        for g1, g2 in d.contact.geom[:ncon].tolist():  # a few pairs: plain Python is fastest
            if g1 == ball:
                i = geom_robot[g2]
            elif g2 == ball:
                i = geom_robot[g1]
            else:
                continue
            if i >= 0:
                out.add(i)
        return out

    def ball_position(self) -> np.ndarray:
        """Ball centre (a copy) from the World's data."""
        return self.world.ball_position()

    def ball_pos_vel(self) -> tuple[list[float], list[float]]:
        """Ball position and linear velocity as lists of floats (cheap per-cycle checks)."""
        w = self.world
        return w.ball_position().tolist(), w.ball_velocity().tolist()

    def ball_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ball (position, linear velocity, angular velocity) from the World's data."""
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


def _joint_layout(m, world: World) -> dict[str, list[tuple[str, int, int, int, int]]]:
    """Per robot prefix: (joint name without prefix, qpos adr, qpos n, dof adr, dof n)."""
    sizes = {
        int(mujoco.mjtJoint.mjJNT_FREE): (7, 6),
        int(mujoco.mjtJoint.mjJNT_BALL): (4, 3),
        int(mujoco.mjtJoint.mjJNT_SLIDE): (1, 1),
        int(mujoco.mjtJoint.mjJNT_HINGE): (1, 1),
    }
    prefixes = [r.prefix for r in world.robots]
    out: dict[str, list[tuple[str, int, int, int, int]]] = {p: [] for p in prefixes}
    for j in range(m.njnt):
        name = m.joint(j).name
        for p in prefixes:
            if name.startswith(p):
                qn, dn = sizes[int(m.jnt_type[j])]
                out[p].append((name[len(p) :], int(m.jnt_qposadr[j]), qn, int(m.jnt_dofadr[j]), dn))
                break
    return out

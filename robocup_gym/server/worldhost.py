"""The embedded world behind the server (on either physics engine), with a changing robot set.

A world is built once for a fixed list of robots (MuJoCo compiles a model for it; ODE creates
its bodies and the table of geom pairs that can touch). Agents of the server connect, load robots
of any type (``scene``) and disconnect at any time, so :class:`WorldHost` **rebuilds the world
with state transfer** whenever the set of robots changes: the new world gets the robots in
connection order, and everything that was already there — ball, every surviving robot's pose,
velocities, motor targets and agent state (the world's ``export_robot_state`` /
``import_robot_state``: team, uniform number, sensor state, vision phase and calibration),
simulation time, cycle counter, game state and random generator — is copied over. A rebuild
costs ~5–50 ms for a few robots (0.2 s with 22 on ODE); it happens only on ``scene`` and on
disconnect/kill, and all changes of one cycle are merged into one rebuild. Parked robots were
rejected: every parked Nao would cost physics time in every step.

The host also recovers from a diverged simulation (:meth:`recover`): a fresh world is built,
each robot is put back at its home position (its sideline slot after ``init``) and the clocks,
game state and teams are restored.

Nothing here depends on the engine: the world is made by :func:`robocup_gym.sim.make_world`.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from robocup_gym.sim import make_world
from robocup_gym.sim.game_host import GameHost
from robocup_gym.sim.memory import release_free_memory
from robocup_gym.sim.physics import BALL_RADIUS
from robocup_gym.sim.vision import VisionConfig

log = logging.getLogger("robocup_gym.server")

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


class WorldHost(GameHost):
    """Owns the current world and the mapping agent ↔ robot index.

    Args:
        vision: ``See`` settings passed to every world.
        physics: MuJoCo settings (``None`` = the world's default; only with ``engine="mujoco"``).
        seed: Seeds the server's random generator (vision noise, beam noise, calibration).
        engine: ``"ode"`` (SimSpark's own step, the default) or ``"mujoco"``.
        self_collisions: Every world runs the self-collision rule
            (:mod:`robocup_gym.sim.self_collision`).
    """

    def __init__(
        self,
        vision: VisionConfig | None = None,
        physics: object | None = None,
        seed: int | None = None,
        engine: str = "ode",
        self_collisions: bool = True,
    ) -> None:
        if physics is not None and engine != "mujoco":
            raise ValueError("physics settings are MuJoCo's; they need engine='mujoco'")
        self.vision = vision or VisionConfig()
        self.physics = physics
        self.engine = engine
        self.self_collisions = bool(self_collisions)
        self.rng = np.random.default_rng(seed)
        self.slots: list[Slot] = []
        self._index: dict[int, int] = {}
        self.world = self._new_world([])
        self.rebuilds = 0
        self.divergences = 0

    # ------------------------------------------------------------------ lookups
    def index(self, key: int) -> int | None:
        """Robot index of owner ``key`` in the current world, or ``None``."""
        return self._index.get(key)

    def slot(self, key: int) -> Slot | None:
        i = self._index.get(key)
        return None if i is None else self.slots[i]

    @property
    def n_robots(self) -> int:
        return len(self.slots)

    # ------------------------------------------------------------------ rebuild
    def _new_world(self, slots: Sequence[Slot]):
        options: dict = {"dead_time_cycles": 0, "vision": self.vision, "seed": None}
        if self.engine == "mujoco":  # team colours of the rendered model, its physics settings
            options.update(teams=[s.team for s in slots], physics=self.physics)
        world = make_world([s.robot_type for s in slots], engine=self.engine, **options)
        world.self_collision_rule = self.self_collisions
        return world

    def change_robots(self, add: Sequence[tuple[int, int]], remove: Sequence[int]) -> list[int]:
        """Add robots ``(key, type)`` and remove those of the keys in ``remove`` in one rebuild.

        New robots appear at the pre-init spot (several new ones side by side, 1 m apart in x).
        Returns the keys that were added. If the world cannot be built with the new robots (e.g.
        MuJoCo runs out of memory), the additions are dropped (logged) and only the removals are
        done.

        Raises:
            Exception: only if even the removal-only rebuild fails (the old world is kept).
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
        world.place_ball(old.ball_position(), old.ball_velocity(), old.ball_angular_velocity())
        for j, s in enumerate(slots):
            i = old_index.get(s.key)
            if i is not None:
                world.import_robot_state(j, old.export_robot_state(i))
        self.world = world
        self.slots = slots
        self._index = {s.key: j for j, s in enumerate(slots)}
        for k, s in enumerate(new):
            j = self._index[s.key]
            r = world.robots[j]
            r.calibration = self.rng.uniform(-0.005, 0.005, 3)
            r.perception_counter = 0
            x, y, z = PRE_INIT_POS
            self._place_pre_init(j, x + 1.0 * k, y, z)
        world.forward()
        old.close()
        self.rebuilds += 1

    def _place_pre_init(self, index: int, x: float, y: float, z: float) -> None:
        n = len(self.world.robots[index].model.joints)
        self.world.place_robot(index, x, y, z=z, heading_deg=90.0, joint_angles_deg=np.zeros(n))

    # ------------------------------------------------------------------ divergence
    def recover(self) -> None:
        """Replace a diverged world by a fresh one and put everything back where it belongs
        (logged by the caller): clocks, game state, teams, uniform numbers and the agents' state
        (hearing, vision phase, calibration) are kept; every robot is put at its home position
        (sideline slot or pre-init spot) with its motors at rest; the ball goes to the centre
        spot."""
        old = self.world
        world = self._new_world(self.slots)
        world.rng = self.rng
        world.time, world.cycle, world.game = old.time, old.cycle, old.game
        keep = ("team", "team_name", "unum", "announce_team", "perception_counter")
        keep += ("calibration", "heard", "hear_capacity")
        for r_old, r_new in zip(old.robots, world.robots, strict=True):
            for f in keep:
                setattr(r_new, f, getattr(r_old, f))
        self.world = world
        for j, s in enumerate(self.slots):
            if s.home is None:
                x, y, z = PRE_INIT_POS
                self._place_pre_init(j, x, y, z)
            else:
                hx, hy, hz, heading = s.home
                world.place_robot(j, hx, hy, z=hz, heading_deg=heading)
        world.place_ball((0.0, 0.0, BALL_RADIUS))
        old.close()
        self.divergences += 1

    def sane(self) -> bool:
        """False if the state is finite but absurd (a body 100 m away): an instability the
        world's own check did not catch."""
        return bool(np.abs(self.world.body_positions()).max(initial=0.0) < 100.0)

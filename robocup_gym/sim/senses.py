"""What a robot senses and says, the same over every physics engine.

SimSpark's perceptors and its hear/say effector are defined on the world's state, not on the
physics engine that produced it: the game state (``GS``), hearing (reference §4.8), vision (``See``,
reference §4.7, :func:`robocup_gym.sim.vision.see`) and the assembly of one
:class:`~robocup_gym.types.Perception`. :class:`Senses` implements them once; a world on an
engine (:class:`robocup_gym.sim.engines.mujoco.world.World` on MuJoCo,
:class:`robocup_gym.sim.engines.ode.OdeWorld` on
ODE) mixes it in and supplies a few readings of its state:

============================  ==============================================================
engine hook                   what it returns
============================  ==============================================================
``gyro(i)``                   torso angular velocity, torso frame, deg/s
``accelerometer(i)``          the ``ACC`` reading, torso frame, m/s²
``joint_angles_deg(i)``       joint angles, canonical order, degrees
``force_sensors(i)``          ``FRP`` readings by name (foot frame)
``ground_truth(i)``           exact ball and torso state (world frame)
``ball_position()``           ball centre, world, m
``torso_position(i)``         torso centre, world, m
``_head_pose(i)``             head centre (world, m) and rotation matrix (columns = head axes)
``_part_positions(i)``        world positions of :data:`~robocup_gym.sim.vision.PLAYER_PARTS`
``place_robot(i, x, y, …)``   teleport a robot (``beam`` uses it)
``motor_targets(i)``          the active joint velocity targets, rad/s (kept through a beam)
``set_motor_targets(i, v)``   restore them
============================  ==============================================================

and the state the mixin keeps: ``robots`` (each an :class:`AgentState`), ``game``
(:class:`~robocup_gym.types.GameState`), ``time`` (s), ``vision_config`` and ``rng``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.sim.referee import BEAM_MODES, PAUSED_MODES
from robocup_gym.sim.referee_fouls import FOULS_PAUSED_MODES
from robocup_gym.sim.self_collision import SelfCollisions
from robocup_gym.sim.vision import CALIBRATION_ERROR_M, Observer, see_many
from robocup_gym.types import GameState, HeardMessage, Perception, Vision

__all__ = ["HEARING_RANGE_M", "PAUSED_MODES", "SAY_MAX_CHARS", "AgentState", "Senses"]

"""Play modes in which the game clock stands still."""
SAY_MAX_CHARS = 20
"""Longest ``say`` message, characters (reference §4.8)."""
HEARING_RANGE_M = 50.0
"""Farthest a ``say`` message is heard, m."""


@dataclass
class AgentState:
    """What the world keeps of a robot as an agent, whatever the engine: its team and number,
    what it has heard, when it next sees, its vision calibration offset."""

    team: str | None = None
    """Team side ``"left"``/``"right"``."""
    team_name: str | None = None
    unum: int | None = None
    announce_team: bool = False
    """True until the next GS carries unum/team (sent once after init)."""
    perception_counter: int = 0
    """Cycles since the world's start/reset (vision comes every ``interval``-th)."""
    calibration: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """This robot's fixed vision calibration offset, m (reference §4.7)."""
    heard: list[HeardMessage] = field(default_factory=list)
    hear_capacity: dict[str, int] = field(default_factory=lambda: {"team": 2, "opp": 2})

    # an engine's robot state subclasses this and has ``model`` (its NaoModel)
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Perceptor names (canonical order)."""
        return self.model.perceptor_names  # type: ignore[attr-defined]

    @property
    def effector_names(self) -> tuple[str, ...]:
        """Effector names (canonical order)."""
        return self.model.effector_names  # type: ignore[attr-defined]


class Senses:
    """Game state, hearing, vision and perception over any engine (see the module docstring for
    what the engine supplies)."""

    # ------------------------------------------------------------------ robots
    @property
    def n_robots(self) -> int:
        """Number of robots in the world."""
        return len(self.robots)

    def robot(self, index: int):
        """The robot with index ``index`` (its engine's robot state, an :class:`AgentState`).

        Raises:
            IndexError: naming the valid range.
        """
        if not 0 <= index < len(self.robots):
            raise IndexError(f"robot index {index} out of range 0..{len(self.robots) - 1}")
        return self.robots[index]

    # ------------------------------------------------------------------ state of the game
    def set_game(
        self,
        *,
        play_mode: str | None = None,
        game_time: float | None = None,
        score_left: int | None = None,
        score_right: int | None = None,
    ) -> None:
        """Set play mode (wire name, e.g. ``"PlayOn"``), game clock (s) and scores instantly."""
        if play_mode is not None:
            self.game.play_mode = play_mode
        if game_time is not None:
            self.game.game_time = float(game_time)
        if score_left is not None:
            self.game.score_left = int(score_left)
        if score_right is not None:
            self.game.score_right = int(score_right)

    def set_team(self, index: int, side: str, team_name: str, unum: int) -> None:
        """Give robot ``index`` its team (as ``init`` does): it is then seen by others, can hear,
        and the next GS carries ``unum``/``team`` once."""
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        r = self.robot(index)
        r.team, r.team_name, r.unum = side, team_name, int(unum)
        r.announce_team = True

    def _reset_senses(self) -> None:
        """Every robot's agent state as at the world's start (new calibration offsets drawn)."""
        for r in self.robots:
            r.perception_counter = 0
            r.heard.clear()
            r.hear_capacity = {"team": 2, "opp": 2}
            r.calibration = self.rng.uniform(-CALIBRATION_ERROR_M, CALIBRATION_ERROR_M, 3)

    def _advance_clocks(self, dt: float) -> None:
        """After one cycle of ``dt`` seconds: world time, game clock (unless paused), every
        robot's perception counter, and the self-collision rule."""
        self.time = round(self.time + dt, 10)
        if self.game.play_mode not in PAUSED_MODES:
            self.game.game_time = round(self.game.game_time + dt, 10)
        for r in self.robots:
            r.perception_counter += 1
        self._self_collision_rule()

    # ------------------------------------------------------------------ self-collisions
    self_collision_rule: bool = True
    """Whether rcssserver3d's self-collision rule runs (:mod:`robocup_gym.sim.self_collision`):
    while the game is not paused, a robot's own colliding boxes freeze their joints for 1 s.
    The server always runs it; an environment's ``self_collisions`` option (``EnvConfig``,
    ``SoccerConfig``) and ``serve --no-rules`` set it."""

    @property
    def self_collisions(self) -> SelfCollisions:
        """The rule's state: which joints are frozen, the last cycle's collisions."""
        state = self.__dict__.get("_self_collisions")
        if state is None:
            state = self.__dict__["_self_collisions"] = SelfCollisions()
        return state

    def _self_collision_rule(self) -> None:
        """After a step: the rule, while the game runs; every joint released while it pauses."""
        state = self.self_collisions
        if not self.self_collision_rule or self.game.play_mode in FOULS_PAUSED_MODES:
            state.clear()
            return
        types = [r.model.robot_type.index for r in self.robots]
        state.update(self, types, self.game.game_time)

    def _frozen_to_zero(self, index: int, velocities: np.ndarray) -> np.ndarray:
        """Robot ``index``'s due command with every frozen joint's command (not NaN) replaced
        by 0 rad/s, as a disabled hinge effector takes it."""
        state = self.__dict__.get("_self_collisions")
        frozen = None if state is None else state.frozen(index)
        if frozen is None:
            return velocities
        return np.where(frozen & (velocities == velocities), 0.0, velocities)

    # ------------------------------------------------------------------ beam
    BEAM_MODES = BEAM_MODES
    """Play modes in which an agent's ``beam`` is applied (reference §9.4)."""
    BEAM_HEIGHT_M = 0.4
    """Torso centre height a beamed robot is put at, m (it then falls onto its feet)."""

    def _beam_pose(
        self, index: int, x: float, y: float, rot_deg: float
    ) -> tuple[float, float, float] | None:
        """Where SimSpark's ``beam`` to ``(x, y, rot_deg)`` in robot ``index``'s team frame puts
        its torso: world ``(x, y, heading_deg)``, with the reference's noise (§5) when vision
        noise is on, clamped to the own half; ``None`` when the beam is not applied (play mode, or
        a value that is not finite)."""
        if self.game.play_mode not in self.BEAM_MODES:
            return None
        if not all(math.isfinite(float(v)) for v in (x, y, rot_deg)):
            return None
        r = self.robot(index)
        if self.vision_config.noise:
            x += self.rng.uniform(-1, 1) * 0.05
            y += self.rng.uniform(-1, 1) * 0.05
            rot_deg += self.rng.uniform(-1, 1) * 10.0
        x = min(max(x, -15.0), 0.0)
        y = min(max(y, -10.0), 10.0)
        if r.team == "right":
            return -x, -y, rot_deg + 180.0
        return x, y, rot_deg

    def beam(self, index: int, x: float, y: float, rot_deg: float) -> bool:
        """SimSpark ``beam`` in the robot's team frame (reference §9.4): only in BeforeKickOff and
        the goal modes; adds the reference's noise (§5) when vision noise is on; torso at z = 0.4 m,
        upright, motor targets kept. Returns whether the beam was applied."""
        pose = self._beam_pose(index, x, y, rot_deg)
        if pose is None:
            return False
        self.move_robot(index, (pose[0], pose[1], self.BEAM_HEIGHT_M), heading_deg=pose[2])
        return True

    # ------------------------------------------------------------------ hear / say
    def say(self, index: int, message: str) -> None:
        """Broadcast ``message`` (≤ 20 printable characters, no spaces/parentheses) from robot
        ``index`` to every robot with a team within 50 m (reference §4.8); heard in the next
        percept."""
        r = self.robot(index)
        if not message or len(message) > SAY_MAX_CHARS or r.team is None:
            return
        if any(not (0x21 <= ord(c) <= 0x7E) or c in "()" for c in message):
            return
        src = self.torso_position(index)
        for k, other in enumerate(self.robots):
            if other.team is None:
                continue
            if other is r:
                other.heard.append(HeardMessage(r.team_name, self.game.game_time, None, message))
                continue
            delta = src[:2] - self.torso_position(k)[:2]
            if float(np.hypot(*delta)) > HEARING_RANGE_M:
                continue
            key = "team" if other.team == r.team else "opp"
            if other.hear_capacity[key] < 2:
                continue
            other.hear_capacity[key] -= 2
            if other.team == "right":
                delta = -delta
            direction = math.degrees(math.atan2(delta[1], delta[0]))
            other.heard.append(HeardMessage(r.team_name, self.game.game_time, direction, message))

    # ------------------------------------------------------------------ perception
    def perceive_all(
        self, indices: Sequence[int], *, ground_truth: bool = True
    ) -> list[Perception]:
        """:meth:`perceive` of each robot in ``indices``, in that order (the same perceptions,
        noise included, as calling it robot after robot), with the visions of every robot that
        sees in this cycle computed together (:func:`~robocup_gym.sim.vision.see_many`)."""
        interval = self.vision_config.interval
        seeing = [
            i for i in indices if (c := self.robot(i).perception_counter) % interval == 0 and c > 0
        ]
        visions = dict(zip(seeing, self._visions(seeing), strict=True)) if seeing else {}
        return [
            self.perceive(i, vision=i in visions, ground_truth=ground_truth, _vision=visions.get(i))
            for i in indices
        ]

    def perceive(
        self,
        index: int = 0,
        *,
        vision: bool | None = None,
        ground_truth: bool = True,
        _vision: Vision | None = None,
    ) -> Perception:
        """Robot ``index``'s perception of the current state, as rcssserver3d would send it.

        Vision (``See``) is included every ``vision.interval``-th cycle (or when ``vision`` is
        forced True/False). GS carries unum/team once after :meth:`set_team`. Messages heard since
        the last call are returned and cleared. Ground truth is attached unless ``ground_truth``
        is False (the server, which does not send it, saves the work).
        """
        r = self.robot(index)
        g = self.game
        game = GameState(
            play_mode=g.play_mode,
            game_time=g.game_time,
            score_left=g.score_left,
            score_right=g.score_right,
        )
        if r.announce_team:
            game.unum, game.team_side = r.unum, r.team
            r.announce_team = False
        if vision is None:
            vision = (
                r.perception_counter % self.vision_config.interval == 0 and r.perception_counter > 0
            )
        vis = (_vision if _vision is not None else self.vision(index)) if vision else None
        heard = r.heard
        r.heard = []
        for k in r.hear_capacity:
            r.hear_capacity[k] = min(2, r.hear_capacity[k] + 1)
        return Perception(
            time=self.time,
            game=game,
            gyro=self.gyro(index),
            accel=self.accelerometer(index),
            joint_names=r.joint_names,
            joint_angles_deg=self.joint_angles_deg(index),
            force_sensors=self.force_sensors(index),
            vision=vis,
            heard=heard,
            ground_truth=self.ground_truth(index) if ground_truth else None,
        )

    def _seen_players(self) -> list:
        """``(team name, unum, visible parts' world positions)`` of every robot with a team."""
        return [
            (o.team_name, o.unum, self._part_positions(k))
            for k, o in enumerate(self.robots)
            if o.team_name is not None and o.unum is not None
        ]

    def vision(self, index: int = 0):
        """The ``See`` percept of robot ``index`` for the current state (ignores the interval)."""
        return self._visions([index])[0]

    def _visions(self, indices: Sequence[int]) -> list[Vision]:
        """The ``See`` percepts of robots ``indices`` for the current state, computed together
        (:func:`~robocup_gym.sim.vision.see_many`; the noise drawn robot after robot)."""
        observers = []
        for i in indices:
            head_pos, head_rot = self._head_pose(i)
            r = self.robot(i)
            observers.append(Observer(head_pos, head_rot, r.calibration, r.team == "right"))
        return see_many(
            observers,
            ball_pos=self.ball_position(),
            players=self._seen_players(),
            rng=self.rng,
            config=self.vision_config,
        )

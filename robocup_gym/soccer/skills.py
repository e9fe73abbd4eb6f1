"""Skills as actions: every player walks at a commanded velocity with the shipped walk policy,
kicks with the scripted kick, and gets up with the shipped get-up policy when it has fallen.

Each skill is the single-agent task it was trained in (Walk, GetUp), run on the player's robot
in the game through :class:`PlayerBackend` (which never moves or steps the world: the game does)
with the exported policy's recorded options, so a skill sees exactly what it saw in training.
Every cycle, the observations of all players in the same skill go through the policy in one
batched inference. A robot of type 4 (toes: observations the policies were not trained with)
plays the skills' reference motions alone (the walk's gait, the get-up's script), which is what a
zero action of the policy plays.

The kick is rcssserver3d's scripted kick D (the fixture ``kick_D.json``: 25 cycles of open-loop
right hip and knee velocities; from a robot standing straight 0.2 m behind the ball it moves the
ball 2.3 m), until a learnt kick ships; it kicks with the right foot in the direction the robot
faces, then the robot usually falls and gets up.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, EpisodeSetup
from robocup_gym.envs.observations import heading_frame, in_heading_frame, up_z
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim.fidelity import load_data
from robocup_gym.sim.rotations import quat_multiply, yaw_quat
from robocup_gym.types import AgentCommand, Perception

__all__ = [
    "KICK_CYCLES",
    "MAX_FORWARD_MPS",
    "MAX_SIDEWAYS_MPS",
    "MAX_TURN_DPS",
    "SKILL_ACTION_LABELS",
    "SKILL_ACTION_WHAT",
    "PlayerBackend",
    "PlayerSkills",
    "SkillSet",
    "checked_action",
    "facing_x",
]

MAX_FORWARD_MPS = 0.8
"""Forward speed of a walk action of +1, m/s (−1: backwards at the same speed)."""
MAX_SIDEWAYS_MPS = 0.3
"""Leftward speed of a walk action of +1, m/s."""
MAX_TURN_DPS = 30.0
"""Counter-clockwise turn rate of a walk action of +1, deg/s."""
SKILL_ACTION_LABELS = ("forward", "left", "turn", "kick")
"""A skill action: the walk's velocity command, each in [-1, 1] (scaled by the maxima above),
and a kick when the last value is above 0.5."""

SKILL_ACTION_WHAT = "a skill action: " + ", ".join(SKILL_ACTION_LABELS)
"""How error messages describe a skill action."""


def checked_action(agent: str, action: Any, labels: Sequence[str], what: str) -> np.ndarray:
    """``action`` of ``agent`` as floats clipped to [-1, 1], one value per label.

    Raises:
        ValueError: the wrong shape (naming ``what`` was expected) or a value that is not
            finite (naming its label).
    """
    a = np.asarray(action, dtype=float)
    if a.shape != (len(labels),):
        raise ValueError(f"{agent}: action of shape {a.shape}, expected ({len(labels)},) ({what})")
    if not np.isfinite(a).all():
        bad = int(np.flatnonzero(~np.isfinite(a))[0])
        raise ValueError(
            f"{agent}: action value {bad} ({labels[bad]}) is {a[bad]}; actions must be finite"
        )
    return np.clip(a, -1.0, 1.0)


_FALLEN_UP_Z = 0.5
"""A robot whose torso's up axis points less than 60° from the vertical (z below this) is down."""


@functools.cache
def _kick_blocks() -> tuple[tuple[int, tuple[tuple[str, float], ...]], ...]:
    spec = load_data("kick_D.json")
    out = []
    for block in spec["command_sequence"]:
        vel = tuple((name, float(v)) for name, v in block["velocities_rad_per_s"].items())
        if vel:  # the motion itself, without the recording's idle cycles before and after
            out.append((int(block["cycles"]), vel))
    out.append((KICK_FOLLOW_THROUGH_CYCLES, ()))
    return tuple(out)


@functools.cache
def kick_sequence(robot_type: int = 0) -> tuple[np.ndarray, ...]:
    """The scripted kick's joint velocities per cycle (rad/s, in the effector order of a Nao of
    ``robot_type``; every joint not in the script at 0)."""
    names = nao_model(robot_type).effector_names
    out = []
    for cycles, vel in _kick_blocks():
        v = dict(vel)
        row = np.array([v.get(n, 0.0) for n in names])
        row.flags.writeable = False
        out += [row] * cycles
    return tuple(out)


KICK_FOLLOW_THROUGH_CYCLES = 15
"""Cycles with the joints at rest after the kick's motion (the foot meets the ball 14 cycles
after the motion starts)."""
KICK_CYCLES = 25 + KICK_FOLLOW_THROUGH_CYCLES
"""Cycles of the scripted kick: its 25 cycles of motion and the follow-through."""


def facing_x(p: Perception) -> Perception:
    """``p`` with its ground truth turned about the vertical through the world's origin so that
    the robot faces +x: what a task trained from starts facing +x sees whichever way the player
    faces. Its pitch, roll, turn rate and velocities in its own frame are unchanged."""
    gt = p.ground_truth
    if gt is None:
        return p
    heading = heading_frame(gt.torso_quat)
    names = [n for n in _TURNED if getattr(gt, n) is not None]
    v = np.array([getattr(gt, n) for n in names], dtype=float)
    out = v.copy()
    out[:, 0], out[:, 1] = in_heading_frame(heading, v[:, 0], v[:, 1])  # all at once
    turned = _shallow_copy(gt)
    for n, row in zip(names, out, strict=True):
        setattr(turned, n, row)
    turned.torso_quat = quat_multiply(yaw_quat(-math.atan2(heading[1], heading[0])), gt.torso_quat)
    seen = _shallow_copy(p)
    seen.ground_truth = turned
    return seen


def _shallow_copy(obj: Any) -> Any:
    """``copy.copy`` of a plain object (its attributes in ``__dict__``), without its cost."""
    new = object.__new__(type(obj))
    new.__dict__.update(obj.__dict__)
    return new


_TURNED = ("ball_pos", "ball_vel", "torso_pos", "torso_vel", "torso_ang_vel")
"""The ground truth's world-frame vectors that :func:`facing_x` turns."""


class PlayerBackend(Backend):
    """A backend over one player of a running game (in-process, or a player connected to a
    server): the world is moved and stepped by the game, never by the task on top.
    :meth:`reset_episode` starts an episode where the player is (the perception given to
    :meth:`see`), counting a start's settle cycles as run. With ``turn_to_x`` the task sees the
    player as if it faced +x (:func:`facing_x`), as its training episodes started."""

    name = "game-player"

    def __init__(self, model: NaoModel, turn_to_x: bool = False) -> None:
        super().__init__(robot_type=model.robot_type.index, seed=None, vision=False)
        self._model = model
        self.turn_to_x = turn_to_x
        self._seen: Perception | None = None
        self._perception: Perception | None = None

    @property
    def robot_model(self) -> NaoModel:
        return self._model

    def see(self, p: Perception) -> None:
        """The player's perception of the current cycle (perceived once, by the game)."""
        self._seen, self._perception = p, None

    @property
    def perception(self) -> Perception | None:
        """The current cycle's perception as the task sees it (turned when first asked for:
        a player in another skill does not need it)."""
        if self._perception is None and self._seen is not None:
            self._perception = facing_x(self._seen) if self.turn_to_x else self._seen
        return self._perception

    def _place(self, start: EpisodeSetup) -> tuple[Perception, int]:
        if self.perception is None:
            raise RuntimeError("the player has not perceived anything yet")
        return self.perception, start.settle_cycles

    def step(self, command: AgentCommand) -> Perception:
        raise RuntimeError("a player's skill does not step the world; the game does")


@dataclass
class _Skill:
    env: Any
    """The task's environment (unwrapped) on the player's backend."""
    obs: np.ndarray | None = None


class PlayerSkills:
    """One player's walk and get-up tasks and what it is doing (``mode``: walk, kick, get-up)."""

    def __init__(
        self, model: NaoModel, index: int, walk: Any, getup: Any, walk_faces_x: bool = True
    ) -> None:
        self.index = index
        self.backend = PlayerBackend(model)
        """The player as it is (the get-up's)."""
        self.walk_backend = PlayerBackend(model, turn_to_x=walk_faces_x)
        """The player as the walk sees it: its observations of the torso's orientation are in
        the world frame, and it was trained facing +x (it walks askew facing the other way)."""
        self.walk = _Skill(walk(self.walk_backend))
        self.getup = _Skill(getup(self.backend))
        self.mode = "walk"
        self.kick_cycle = 0
        self.failed_getups = 0
        self.command = np.zeros(3)

    def see(self, p: Perception) -> None:
        """This cycle's perception, to both skills."""
        self.backend.see(p)
        self.walk_backend.see(p)

    def start(self, p: Perception, seed: int | None) -> None:
        """A new episode: walking on the spot."""
        self.see(p)
        self.command[:] = 0.0
        self.walk.obs, _ = self.walk.env.reset(seed=seed, options={"velocity_command": (0, 0, 0)})
        self.getup.env.reset(seed=None if seed is None else seed + 1000)
        self.mode = "walk"
        self.failed_getups = 0

    def fallen(self, p: Perception) -> bool:
        gt = p.ground_truth
        return gt is not None and up_z(gt.torso_quat) < _FALLEN_UP_Z

    def lying_side(self, p: Perception) -> str:
        """``front`` when the torso's forward axis points down, else ``back``."""
        w, x, y, z = (float(c) for c in p.ground_truth.torso_quat)
        forward_z = 2.0 * (y * z + w * x)
        return "front" if forward_z < 0.0 else "back"


class SkillSet:
    """The skills of a game's players (player ``k`` is the ``k``-th of ``robot_types``).

    Args:
        robot_types: The players' Nao types, in player order.
        walk, getup: Names of the shipped policies that walk and get up.
        self_collisions: Whether the world runs rcssserver3d's self-collision rule (a real
            server and ``serve`` always do). Then the get-up plays ``GetUp-v1``'s scripts
            alone, which keep clear of the rule; without it, the shipped get-up (a policy over
            the same scripts). From a game's falls (random headings, joints drawn with σ 10°) under
            the rule the scripts alone got up more often and sooner than the policy over them
            (46 and 43 of 60; docs/results.md).
        walk_faces_x: The walk sees each player as if it faced +x (:func:`facing_x`): it was
            trained facing +x and observes its torso's orientation in the world frame; facing
            −x it walks askew, hardly turns clockwise and falls walking sideways.
    """

    def __init__(
        self,
        robot_types: Sequence[int],
        walk: str = "walk",
        getup: str = "get-up",
        self_collisions: bool = False,
        walk_faces_x: bool = True,
    ) -> None:
        from robocup_gym.train.pretrained import pretrained_env, pretrained_policy

        self.robot_types = tuple(int(t) for t in robot_types)
        self.walk_policy = pretrained_policy(walk)
        self.getup_policy = pretrained_policy(getup)
        if len(kick_sequence()) != KICK_CYCLES:
            raise RuntimeError(f"the scripted kick has {len(kick_sequence())} cycles")
        self.players: list[PlayerSkills] = []
        self.uses_policy: dict[str, set[int]] = {"walk": set(), "get-up": set()}
        for index, t in enumerate(self.robot_types):
            made = {}
            for skill, policy, extra in (
                ("walk", self.walk_policy, {"command_change_steps": 0}),
                ("get-up", self.getup_policy, {"self_collisions": True} if self_collisions else {}),
            ):
                made[skill] = self._maker(pretrained_env, policy, skill, index, t, extra)
            self.players.append(
                PlayerSkills(nao_model(t), index, made["walk"], made["get-up"], walk_faces_x)
            )

    def _maker(self, pretrained_env, policy, skill: str, index: int, robot_type: int, extra):
        def make(backend: PlayerBackend):
            overrides = {"robot_type": robot_type, "wait_steps": 0, **extra}
            env = None
            # with the self-collision rule the get-up plays the scripts made for it alone
            if not extra.get("self_collisions"):
                try:
                    env = pretrained_env(policy, backend, overrides)
                    self.uses_policy[skill].add(index)
                except ValueError:  # another observation size (type 4)
                    pass
            if env is None:  # the reference motion alone
                from robocup_gym.train.pretrained import recorded_env_options
                from robocup_gym.train.tasks import make_env

                meta = policy.metadata
                options = {**recorded_env_options(meta), **overrides}
                env = make_env(meta["env_id"], backend=backend, env_kwargs=options)
            env = env.unwrapped
            env.rewarded = False  # a skill's reward is read by nobody
            return env

        return make

    # ------------------------------------------------------------------ the cycle
    def reset(self, perceptions: dict[int, Perception], seed: int | None = None) -> None:
        for k, s in enumerate(self.players):
            s.start(perceptions[s.index], None if seed is None else seed + k)

    def decide(self, index: int, action: np.ndarray) -> None:
        """Player ``index``'s skill action (checked and clipped by the caller): a walk command,
        or a kick (which runs to its end; a fallen player gets up first)."""
        s = self.players[index]
        s.command[:] = (
            action[0] * MAX_FORWARD_MPS,
            action[1] * MAX_SIDEWAYS_MPS,
            action[2] * MAX_TURN_DPS,
        )
        if s.mode == "walk":
            s.walk.env.velocity_command[:] = s.command
            if action[3] > 0.5:
                s.mode, s.kick_cycle = "kick", 0

    def commands(self) -> dict[int, AgentCommand]:
        """This cycle's joint command of every player (the policies batched)."""
        out: dict[int, AgentCommand] = {}
        for mode, policy in (("walk", self.walk_policy), ("get-up", self.getup_policy)):
            group = [s for s in self.players if s.mode == mode]
            if not group:
                continue
            skill = "walk" if mode == "walk" else "getup"
            trained = [s for s in group if s.index in self.uses_policy[mode]]
            actions = {}
            if trained:
                batch = np.stack([getattr(s, skill).obs for s in trained])
                for s, a in zip(trained, policy(batch), strict=True):
                    actions[s.index] = a
            for s in group:
                env = getattr(s, skill).env
                a = actions.get(s.index)
                if a is None:
                    a = np.zeros(env.action_space.shape, np.float32)
                out[s.index] = env.act(a)
        for s, t in zip(self.players, self.robot_types, strict=True):
            if s.mode == "kick":
                out[s.index] = AgentCommand(kick_sequence(t)[s.kick_cycle])
        return out

    def observe(self, perceptions: dict[int, Perception]) -> None:
        """After the cycle: every skill sees its player's perception; a player that fell gets
        up, one that is up again walks, a kick that ended walks."""
        for s in self.players:
            p = perceptions[s.index]
            s.see(p)
            if s.mode == "kick":
                s.kick_cycle += 1
                if s.kick_cycle >= KICK_CYCLES:
                    self._walk_again(s)
                continue
            skill, seen = (s.walk, s.walk_backend) if s.mode == "walk" else (s.getup, s.backend)
            obs, _, terminated, truncated, info = skill.env.observe_step(seen.perception)
            skill.obs = obs
            if s.mode == "walk":
                if s.fallen(p):
                    s.mode = "get-up"
                    s.getup.obs, _ = s.getup.env.reset(options={"start_side": s.lying_side(p)})
                elif terminated or truncated:
                    self._walk_again(s)
            elif info.get("success") or terminated or truncated:
                if s.fallen(p):  # not up in time: try again, from the other side the next time
                    s.failed_getups += 1
                    side = s.lying_side(p)
                    if s.failed_getups % 2 == 0:
                        side = "back" if side == "front" else "front"
                    s.getup.obs, _ = s.getup.env.reset(options={"start_side": side})
                else:
                    s.failed_getups = 0
                    self._walk_again(s)

    def _walk_again(self, s: PlayerSkills) -> None:
        if s.fallen(s.backend.perception):
            s.mode = "get-up"
            side = s.lying_side(s.backend.perception)
            s.getup.obs, _ = s.getup.env.reset(options={"start_side": side})
            return
        s.mode = "walk"
        command = tuple(float(v) for v in s.command)
        s.walk.obs, _ = s.walk.env.reset(options={"velocity_command": command})

    def modes(self) -> list[str]:
        return [s.mode for s in self.players]

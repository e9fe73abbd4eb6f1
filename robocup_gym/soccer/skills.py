"""Skills as actions: every player walks at a commanded velocity with the shipped walk policy,
plays motion skills (the scripted kick) when told, and gets up with the shipped get-up policy
when it has fallen.

A skill action is the walk's velocity command (``forward``, ``left``, ``turn``) and one value
per motion skill of the game (``SoccerConfig.skills``, by default ``("kick",)``) and one per
parameter it takes: a start value above 0.5 starts that motion (the first such in order) with
its parameters' values if the player is walking; the motion runs to its end, then the player
walks again. Motion skills are registered by name
(:func:`robocup_gym.soccer.motions.register_motion_skill`): a skill registered becomes an action
of every game that lists it, with no change to the environment.

Each skill is the single-agent task it was trained in (Walk, GetUp), run on the player's robot
in the game through :class:`PlayerBackend` (which never moves or steps the world: the game does)
with the exported policy's recorded options, so a skill sees exactly what it saw in training.
Every cycle, the observations of all players in the same skill go through the policy in one
batched inference. A robot of type 4 (toes: observations the policies were not trained with)
plays the skills' reference motions alone (the walk's gait, the get-up's script), which is what a
zero action of the policy plays.

The motion skills (the kick: rcssserver3d's scripted kick D) are in
:mod:`robocup_gym.soccer.motions`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_gym.backends.base import Backend, EpisodeSetup
from robocup_gym.envs.observations import heading_frame, in_heading_frame, up_z
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.sim.rotations import quat_multiply, yaw_quat
from robocup_gym.soccer.motions import (
    KICK_CYCLES,
    WALK_ACTION_LABELS,
    Motion,
    MotionSkill,
    checked_motion_skills,
    motion_skill,
)
from robocup_gym.types import AgentCommand, Perception, float_array

__all__ = [
    "DEFAULT_MOTION_SKILLS",
    "DEFAULT_WALK",
    "KICK_CYCLES",
    "MAX_FORWARD_MPS",
    "MAX_SIDEWAYS_MPS",
    "MAX_TURN_DPS",
    "SKILL_ACTION_LABELS",
    "SKILL_ACTION_WHAT",
    "WALK_ACTION_LABELS",
    "PlayerBackend",
    "PlayerSkills",
    "SkillSet",
    "checked_action",
    "facing_x",
    "fit_skill_action",
    "fit_skill_actions",
    "game_skill_labels",
    "runs_a_command_loop",
    "skill_action_labels",
    "skill_action_what",
    "skills_of_teams",
    "walk_of_teams",
]

MAX_FORWARD_MPS = 0.8
"""Forward speed of a walk action of +1, m/s (−1: backwards at the same speed)."""
MAX_SIDEWAYS_MPS = 0.3
"""Leftward speed of a walk action of +1, m/s."""
MAX_TURN_DPS = 30.0
"""Counter-clockwise turn rate of a walk action of +1, deg/s."""
DEFAULT_MOTION_SKILLS = ("kick",)
"""The motion skills of a game unless it says otherwise (``SoccerConfig.skills``)."""
DEFAULT_WALK = "game-walk"
"""The shipped walk of a game's skill actions unless it says otherwise (``SoccerConfig.walk``)."""


def skill_action_labels(motions: Sequence[str] = DEFAULT_MOTION_SKILLS) -> tuple[str, ...]:
    """The values of a skill action with the registered motion skills ``motions``: the
    walk's, then each motion's (:attr:`MotionSkill.labels`: its start value, above 0.5 to
    start it, and its parameters)."""
    return (*WALK_ACTION_LABELS, *(label for m in motions for label in motion_skill(m).labels))


def skill_action_what(motions: Sequence[str] = DEFAULT_MOTION_SKILLS) -> str:
    """How error messages describe a skill action with the motion skills ``motions``."""
    return "a skill action: " + ", ".join(skill_action_labels(motions))


def skills_of_teams(*teams: Any) -> tuple[str, ...]:
    """The motion skills a game of ``teams`` plays: those a learnt team was trained with
    (its ``options["skills"]``), :data:`DEFAULT_MOTION_SKILLS` when no team says.

    Raises:
        ValueError: two teams trained with different motion skills.
    """
    said = {
        tuple(options["skills"])
        for options in (getattr(t, "options", None) for t in teams)
        if isinstance(options, dict) and "skills" in options
    }
    if len(said) > 1:
        raise ValueError(
            f"the teams were trained with different motion skills ({sorted(said)}); a game "
            "plays one set"
        )
    return said.pop() if said else DEFAULT_MOTION_SKILLS


def walk_of_teams(*teams: Any, asked: str | None = None) -> str:
    """The shipped walk a game of ``teams`` plays with: the one its learnt teams were trained
    with (their ``options["walk"]``; :data:`DEFAULT_WALK` for one that does not record it),
    else ``asked``, else :data:`DEFAULT_WALK`. A policy acts on what its walk does with its
    commands: under another walk it plays another game.

    Raises:
        ValueError: two teams trained with different walks, or ``asked`` is not the walk a
            learnt team was trained with.
    """
    said = {
        str(options.get("walk", DEFAULT_WALK))
        for options in (getattr(t, "options", None) for t in teams)
        if isinstance(options, dict)
    }
    if len(said) > 1:
        raise ValueError(
            f"the teams were trained with different walks ({sorted(said)}); a game plays one"
        )
    if said and asked is not None and asked not in said:
        raise ValueError(
            f"the walk {asked!r} was asked, but a team was trained with {said.pop()!r}; a "
            "team plays with the walk it was trained with"
        )
    return said.pop() if said else (DEFAULT_WALK if asked is None else asked)


def game_skill_labels(game: Any) -> tuple[str, ...]:
    """The values of a skill action in ``game`` (an environment or a team on a server: its
    ``skill_action_labels``; :data:`SKILL_ACTION_LABELS` for one that does not say)."""
    return tuple(getattr(game, "skill_action_labels", SKILL_ACTION_LABELS))


def fit_skill_actions(actions: Mapping[str, Any], game: Any) -> dict[str, np.ndarray]:
    """Skill actions of the default layout, by agent, as the skill actions of ``game``
    (:func:`fit_skill_action` with :func:`game_skill_labels`)."""
    labels = game_skill_labels(game)
    return {agent: fit_skill_action(a, labels) for agent, a in actions.items()}


def fit_skill_action(action: Any, labels: Sequence[str]) -> np.ndarray:
    """A skill action of the default layout (:data:`SKILL_ACTION_LABELS`, what the scripted
    teams decide) as one with ``labels``: the walk's values kept, each motion's value taken
    from the action where it has one (the kick), else −1 (not started)."""
    a = np.asarray(action, dtype=float)
    if tuple(labels) == SKILL_ACTION_LABELS:
        return a
    value = dict(zip(SKILL_ACTION_LABELS, a, strict=True))
    return np.array([value.get(name, -1.0) for name in labels])


def checked_action(agent: str, action: Any, labels: Sequence[str], what: str) -> np.ndarray:
    """``action`` of ``agent`` as floats clipped to [-1, 1], one value per label.

    Raises:
        ValueError: not numbers or the wrong shape (naming ``what`` was expected), or a value
            that is not finite (naming its label).
    """
    a = float_array(action)
    if a is None:
        shown = repr(action) if len(repr(action)) <= 60 else repr(action)[:57] + "..."
        raise ValueError(f"{agent}: action must be numbers ({what}), got {shown}")
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


SKILL_ACTION_LABELS = skill_action_labels()
"""A skill action of a game with the default motion skills: the walk's velocity command and a
kick when the last value is above 0.5."""

SKILL_ACTION_WHAT = skill_action_what()
"""How error messages describe a skill action with the default motion skills."""


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
    """One player's walk and get-up tasks and what it is doing (``mode``: ``walk``, ``get-up``
    or the name of the motion skill it plays, ``motion``)."""

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
        self.motion: Motion | None = None
        self.steered = False
        """Whether its motion still steers the walk (its ``walk_command`` has not yet returned
        ``None``)."""
        self.failed_getups = 0
        self.command = np.zeros(3)

    def play(self, name: str, motion: Motion) -> None:
        """Start ``motion`` (of the motion skill ``name``); one with ``walk_command`` steers the
        walk first."""
        self.mode, self.motion = name, motion
        self.steered = callable(getattr(motion, "walk_command", None))

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
        self.motion = None
        self.steered = False
        self.failed_getups = 0

    def fallen(self, p: Perception) -> bool:
        gt = p.ground_truth
        return gt is not None and up_z(gt.torso_quat) < _FALLEN_UP_Z

    def lying_side(self, p: Perception) -> str:
        """``front`` when the torso's forward axis points down, else ``back``."""
        w, x, y, z = (float(c) for c in p.ground_truth.torso_quat)
        forward_z = 2.0 * (y * z + w * x)
        return "front" if forward_z < 0.0 else "back"


def runs_a_command_loop(walk: str) -> bool:
    """Whether the shipped walk ``walk`` runs Walk's command loop (its recorded
    ``command_feedback_gain`` is above 0): it holds the torso's real heading, so it must see
    the players as they face (``walk_faces_x`` off).

    Raises:
        ValueError: no shipped policy of that name (the message lists them).
    """
    from robocup_gym.train.pretrained import describe

    return bool(describe(walk).get("env_config", {}).get("command_feedback_gain"))


class SkillSet:
    """The skills of a game's players (player ``k`` is the ``k``-th of ``robot_types``).

    Args:
        robot_types: The players' Nao types, in player order.
        walk, getup: Names of the shipped policies that walk and get up. The game walks with
            ``game-walk`` (a 3 Hz walk: up to 0.8 m/s forward, 0.3 m/s sideways, 45°/s), the
            walk the scripted team's play and the game's figures are measured with; the
            omnidirectional ``walk`` (faster, and turning 60°/s) plays the ball differently,
            which the scripted team is not tuned to; it runs with ``walk_faces_x=False``. A
            player whose Nao type has a walk of its own under that name
            (:func:`~robocup_gym.train.pretrained.pretrained_types`) walks with it.
        motions: The registered motion skills (:func:`register_motion_skill`) the players
            can start, in the order of their values in a skill action (:attr:`action_labels`).
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
        walk: str = DEFAULT_WALK,
        getup: str = "get-up",
        self_collisions: bool = False,
        walk_faces_x: bool = True,
        motions: Sequence[str] = DEFAULT_MOTION_SKILLS,
    ) -> None:
        from robocup_gym.train.onnx_policy import OnnxPolicy
        from robocup_gym.train.pretrained import (
            describe,
            pretrained_env,
            pretrained_names,
            pretrained_path,
            pretrained_policy,
        )
        from robocup_gym.train.tasks import task_name

        self.robot_types = tuple(int(t) for t in robot_types)
        self.motions = {name: motion_skill(name) for name in checked_motion_skills(motions)}
        self.action_labels = skill_action_labels(tuple(self.motions))
        """The values of a skill action of this game."""
        self.action_what = skill_action_what(tuple(self.motions))
        """How error messages describe a skill action of this game."""
        self.walk_policy = pretrained_policy(walk)
        """The walk's shared policy (the one of every type without its own)."""
        if task_name(self.walk_policy.metadata.get("env_id", "")) != "walk":
            walks = [n for n in pretrained_names() if task_name(describe(n)["env_id"]) == "walk"]
            raise ValueError(
                f"{walk!r} is not a walk (a policy of the Walk task, which follows a walking "
                f"command); the shipped walks: {', '.join(walks)}"
            )
        loaded = {self.walk_policy.path: self.walk_policy}
        self.walk_policies: dict[int, OnnxPolicy] = {}
        """The policy each Nao type of the game walks with (a type's own where one ships)."""
        for t in sorted(set(self.robot_types)):
            path = pretrained_path(walk, t)
            if path not in loaded:
                loaded[path] = OnnxPolicy(path)
            self.walk_policies[t] = loaded[path]
        if walk_faces_x and runs_a_command_loop(walk):
            raise ValueError(
                f"the walk {walk!r} runs a command loop that holds the torso's heading, which "
                "walk_faces_x hides from it (every player seen facing +x): use walk_faces_x="
                "False (a walk trained turning through every heading needs no turned view)"
            )
        self.getup_policy = pretrained_policy(getup)
        self.players: list[PlayerSkills] = []
        self.uses_policy: dict[str, set[int]] = {"walk": set(), "get-up": set()}
        for index, t in enumerate(self.robot_types):
            made = {}
            for skill, policy, extra in (
                ("walk", self.walk_policies[t], {"command_change_steps": 0}),
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
        """Player ``index``'s skill action (:attr:`action_labels`; checked and clipped by the
        caller): a walk command, or a motion skill started (the first whose value is above
        0.5), which runs to its end; a fallen player gets up first. A motion that still steers
        the walk (``walk_command``) goes on while the action starts it again (its new
        parameters unused) and stops for any other action."""
        s = self.players[index]
        s.command[:] = (
            action[0] * MAX_FORWARD_MPS,
            action[1] * MAX_SIDEWAYS_MPS,
            action[2] * MAX_TURN_DPS,
        )
        asked = self._asked_motion(action)
        if s.steered and (asked is None or asked[0].name != s.mode):
            s.mode, s.motion, s.steered = "walk", None, False
        if s.mode == "walk":
            s.walk.env.velocity_command[:] = s.command
            if asked is not None:
                skill, values = asked
                s.play(skill.name, skill.start(self.robot_types[index], *values))

    def _policy(self, mode: str, index: int):
        """The policy player ``index`` plays in ``mode`` (``walk`` or ``get-up``)."""
        if mode == "walk":
            return self.walk_policies[self.robot_types[index]]
        return self.getup_policy

    def _asked_motion(self, action: np.ndarray) -> tuple[MotionSkill, list[float]] | None:
        """The motion skill ``action`` starts (the first whose value is above 0.5) and its
        parameters' values, or ``None``."""
        at = len(WALK_ACTION_LABELS)
        for skill in self.motions.values():
            if action[at] > 0.5:
                return skill, [float(v) for v in action[at + 1 : at + len(skill.labels)]]
            at += len(skill.labels)
        return None

    def commands(self) -> dict[int, AgentCommand]:
        """This cycle's joint command of every player (the policies batched)."""
        out: dict[int, AgentCommand] = {}
        for s in self.players:  # motions that steer the walk: this cycle's walking command
            if s.motion is not None and s.steered:
                command = s.motion.walk_command(s.backend.perception)
                s.steered = command is not None
                if s.steered:
                    s.walk.env.velocity_command[:] = command
        for mode in ("walk", "get-up"):
            group = [s for s in self.players if s.mode == mode or (mode == "walk" and s.steered)]
            if not group:
                continue
            skill = "walk" if mode == "walk" else "getup"
            batches: dict[Any, list[PlayerSkills]] = {}  # each policy's players, one batch
            for s in group:
                if s.index in self.uses_policy[mode]:
                    batches.setdefault(self._policy(mode, s.index), []).append(s)
            actions = {}
            for policy, trained in batches.items():
                batch = np.stack([getattr(s, skill).obs for s in trained])
                for s, a in zip(trained, policy(batch), strict=True):
                    actions[s.index] = a
            for s in group:
                env = getattr(s, skill).env
                a = actions.get(s.index)
                if a is None:
                    a = np.zeros(env.action_space.shape, np.float32)
                out[s.index] = env.act(a)
        for s in self.players:
            if s.motion is not None and not s.steered:
                out[s.index] = AgentCommand(self._motion_command(s))
        return out

    def _motion_command(self, s: PlayerSkills) -> np.ndarray:
        """The joint velocities of player ``s``'s motion this cycle, checked.

        Raises:
            ValueError: not one finite velocity per joint of the player's robot (naming the
                motion skill and the player).
        """
        v = np.asarray(s.motion.command(s.backend.perception), dtype=float)
        n = len(s.backend.robot_model.joints)
        if v.shape != (n,) or not np.isfinite(v).all():
            raise ValueError(
                f"motion skill {s.mode!r} of player {s.index}: its command must be {n} finite "
                f"joint velocities (rad/s), got {v.shape} values"
                + ("" if v.shape != (n,) else f" with {int((~np.isfinite(v)).sum())} not finite")
            )
        return v

    def observe(self, perceptions: dict[int, Perception]) -> None:
        """After the cycle: every skill sees its player's perception; a player that fell gets
        up, one that is up again walks, a motion that ended walks."""
        for s in self.players:
            p = perceptions[s.index]
            s.see(p)
            if s.motion is not None:
                if s.steered:  # it walked this cycle
                    obs, _, terminated, truncated, _ = s.walk.env.observe_step(
                        s.walk_backend.perception
                    )
                    s.walk.obs = obs
                    if s.fallen(p):
                        s.motion, s.steered = None, False
                        self._walk_again(s)  # gets up
                        continue
                    if terminated or truncated:  # the walk's episode length: walk on
                        command = tuple(float(v) for v in s.walk.env.velocity_command)
                        s.walk.obs, _ = s.walk.env.reset(options={"velocity_command": command})
                if s.motion.done:
                    s.motion, s.steered = None, False
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

"""One team's view of a soccer scenario: the players of one side act, one observation and one
action each (uniform-number order), and the other side is played by an opponent team chosen
at every reset. This is what a team policy trains on (one policy shared by the team's players:
:mod:`robocup_gym.train.selfplay`).

Scenarios by name (:data:`TEAM_SCENARIOS`):

===============  ===========================  ======================  =======================
name             scenario                     the learning team       the opponent
===============  ===========================  ======================  =======================
``penalty``      :mod:`.penalty_v1`           the striker (left)      the goalkeeper
``keepaway``     :mod:`.keepaway_v1`          the two attackers       the defender
``game-NvN``     :mod:`.game_v1`, N a side    left or right, drawn    the other side
                 (N = 1–11)                   at every reset
===============  ===========================  ======================  =======================

Observations are the scenario's per player (:mod:`robocup_gym.soccer.observations`) in the
team's own frame, so a policy plays either side unchanged; actions are the scenario's (skill
actions by default here: :data:`TEAM_DEFAULTS`), or, with ``plays``, skill actions or the ball
played along a direction (:mod:`robocup_gym.soccer.ball_play`), or, with ``over_scripted``,
residuals over the scripted team's skill actions
(:class:`~robocup_gym.soccer.scripted.OverScripted`). Rewards are the scenario's, per player.
When a game ends, ``infos[0]["game"]`` holds its result: ``opponent`` (its name), ``side``,
``goals_for``, ``goals_against`` and ``end`` (why it ended), and every player's info holds
``episode`` (``r``: its return, ``l``: steps, ``t``: wall-clock seconds), as
Stable-Baselines3's ``Monitor`` writes it.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from robocup_gym.soccer.ball_play import PLAY_ACTION_LABELS, BallPlay
from robocup_gym.soccer.skills import fit_skill_actions

__all__ = [
    "TEAM_DEFAULTS",
    "TEAM_OPTIONS",
    "TEAM_SCENARIOS",
    "TeamActions",
    "TeamView",
    "scenario_options",
    "team_actions",
    "team_scenario",
]

TEAM_SCENARIOS = ("penalty", "keepaway", "game-NvN")
"""The scenario names a team trains on (``game-2v2``, ``game-3v3``, … for ``game-NvN``)."""

TEAM_DEFAULTS: dict[str, Any] = {
    "actions": "skills",
    "privileged": True,
    "ball_progress": 0.1,
    "plays": False,
    "over_scripted": False,
}
"""Options a team scenario starts from, over the scenario's own: skill actions, the privileged
observations (own and ball position and velocity from ground truth) and a small reward for
moving the ball toward the opponent goal (0.1 per metre; a goal pays 1). ``plays``: the team
acts with ``plays`` actions (:data:`~robocup_gym.soccer.ball_play.PLAY_ACTION_LABELS`: a skill
action, or the ball played along a direction), which
:class:`~robocup_gym.soccer.ball_play.BallPlay` turns into skill actions; the scenario itself
takes skill actions. ``over_scripted``: the team acts with residuals over the scripted team
(:class:`~robocup_gym.soccer.scripted.OverScripted`: each player's action is added to the
scripted team's skill action for it; a zero action plays the scripted team)."""

TEAM_OPTIONS = ("plays", "over_scripted")
"""The options of the learning team, not of the scenario's environment."""

_GAME = re.compile(r"^game-(\d+)v(\d+)$")

TeamActions = Callable[[Any, list[str], dict[str, np.ndarray]], dict[str, np.ndarray]]
"""``(game, agents, actions) → skill actions``: what turns a team's own actions into the
game's skill actions (:func:`team_actions`)."""


def team_actions(options: Mapping[str, Any]) -> TeamActions | None:
    """What turns the actions of a team with the team options ``options`` into skill actions:
    ``plays`` actions through :class:`~robocup_gym.soccer.ball_play.BallPlay`, residuals over
    the scripted team (``over_scripted``) through
    :class:`~robocup_gym.soccer.scripted.OverScripted`; ``None`` for a team that acts with
    skill actions. Each call makes a new one (they remember the players' dribbles)."""
    if options.get("plays"):
        plays = BallPlay()

        def played(game: Any, agents: list[str], actions: dict[str, np.ndarray]):
            return fit_skill_actions(plays.skill_actions(game.team_view(agents), actions), game)

        return played
    if options.get("over_scripted"):
        from robocup_gym.soccer.scripted import OverScripted

        return OverScripted().skill_actions
    return None


Opponents = Callable[[np.random.Generator], Any]
"""Called at every reset with the game's random generator; returns the opponent team: a
callable ``team(env, agents, obs) → {agent: action}`` with a ``name``."""


def team_scenario(name: str) -> tuple[type, str, dict[str, Any]]:
    """``(scenario environment class, learning side, the scenario's options)`` of a team
    scenario name: the side is ``"left"``, or ``"either"`` (drawn at every reset).

    Raises:
        ValueError: an unknown name (the message lists the known ones).
    """
    from robocup_gym.soccer import game_v1, keepaway_v1, penalty_v1

    key = str(name).strip().lower().replace("_", "-")
    if key == "penalty":
        return penalty_v1.PenaltyEnv, "left", {"start_noise": penalty_v1.SPREAD_M}
    if key == "keepaway":
        return keepaway_v1.KeepawayEnv, "left", {}
    m = _GAME.match(key)
    if m:
        left, right = int(m.group(1)), int(m.group(2))
        if left != right or not 1 <= left <= 11:
            raise ValueError(f"{name!r}: a game is N against N with N = 1-11 (game-2v2)")
        # types 0-3 in turn (type 4 observes two more joints: another policy input size)
        types = tuple(k % 4 for k in range(left))
        return game_v1.GameEnv, "either", {"left_types": types, "right_types": types}
    raise ValueError(
        f"unknown team scenario {name!r}; scenarios: penalty, keepaway, game-NvN "
        "(game-1v1 … game-11v11)"
    )


def scenario_options(name: str, options: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Every option of team scenario ``name``: :data:`TEAM_DEFAULTS`, the scenario's own, then
    ``options``; checked without building a game (an unknown option or a bad value: a
    ``ValueError`` naming it)."""
    from robocup_gym.soccer.env import SoccerConfig

    cls, _, own = team_scenario(name)
    merged = {**TEAM_DEFAULTS, **own, **dict(options or {})}
    extra = _scenario_keywords(cls)
    try:
        config = SoccerConfig.with_options(
            cls.default_config,
            {k: v for k, v in merged.items() if k not in extra and k not in TEAM_OPTIONS},
        )
    except TypeError as exc:  # an unknown option
        raise ValueError(f"{name}: {exc}") from None
    for key in TEAM_OPTIONS:
        if not isinstance(merged[key], bool):
            raise ValueError(f"{name}: {key} must be true or false, got {merged[key]!r}")
    if merged["plays"] and merged["over_scripted"]:
        raise ValueError(
            f"{name}: plays and over_scripted are two kinds of team action; choose one"
        )
    out = {k: v for k, v in merged.items() if k in extra or k in TEAM_OPTIONS}
    for field, value in config.__dict__.items():
        out[field] = list(value) if isinstance(value, tuple) else value
    return out


def _scenario_keywords(cls: type) -> set[str]:
    """The keywords a scenario's class takes beyond the :class:`SoccerConfig` fields
    (``start_noise``, ``area``, …)."""
    import inspect

    params = inspect.signature(cls.__init__).parameters
    return {
        p
        for p, v in params.items()
        if p not in ("self", "render_mode", "render_size", "options")
        and v.kind not in (v.VAR_KEYWORD, v.VAR_POSITIONAL)
    }


class TeamView:
    """Team scenario ``scenario`` (:data:`TEAM_SCENARIOS`) seen by its learning team, against
    the team ``opponents(rng)`` returns at every reset; ``options`` are the scenario's
    (:func:`scenario_options`)."""

    render_mode = None

    def __init__(
        self,
        scenario: str,
        opponents: Opponents,
        options: Mapping[str, Any] | None = None,
        seed: int | None = None,
    ) -> None:
        cls, self.side_rule, _ = team_scenario(scenario)
        self.scenario = scenario
        opts = scenario_options(scenario, options)
        for key in ("left_types", "right_types"):
            opts[key] = tuple(opts[key])
        self.options = opts
        self.env = cls(**{k: v for k, v in opts.items() if k not in TEAM_OPTIONS})
        self.to_skills = team_actions(opts)
        """Turns the team's actions into skill actions (``None``: it acts with them)."""
        self.opponents = opponents
        self._rng = np.random.default_rng(seed)
        c = self.env.config
        sizes = {len(c.left_types), len(c.right_types)}
        if self.side_rule == "either" and len(sizes) != 1:
            raise ValueError("a team that plays either side needs teams of the same size")
        self.seats = len(c.left_types)
        first = self.env.possible_agents[0]
        self.observation_space: gym.spaces.Box = self.env.observation_space(first)
        self.action_space: gym.spaces.Box = self.env.action_space(first)
        if opts["plays"]:
            self.action_space = gym.spaces.Box(-1.0, 1.0, (len(PLAY_ACTION_LABELS),), np.float32)
        for agent in self.env.possible_agents:
            if self.env.observation_space(agent).shape != self.observation_space.shape:
                raise ValueError(
                    f"{scenario}: the players' observations differ in size (robot types "
                    f"{c.left_types} and {c.right_types}: type 4 has two more joints); one "
                    "policy takes one size: use types 0-3"
                )
        self.observation_labels: list[str] = self.env.observation_labels(first)
        """One label per observation value
        (:func:`~robocup_gym.soccer.observations.observation_labels`); every value comes
        scaled to [-1, 1] by its fixed range."""
        self.side = "left"
        self.opponent: Any = None
        self._obs: dict[str, np.ndarray] = {}
        self._return = np.zeros(self.seats)
        self._length = 0
        self._t0 = time.perf_counter()

    # ------------------------------------------------------------------ names
    def agents_of(self, side: str) -> list[str]:
        """The agents of ``side`` in uniform-number order."""
        return [a for a in self.env.possible_agents if a.startswith(side + "_")]

    @property
    def mine(self) -> list[str]:
        return self.agents_of(self.side)

    @property
    def theirs(self) -> list[str]:
        return self.agents_of("right" if self.side == "left" else "left")

    # ------------------------------------------------------------------ the API
    def reset(self, seed: int | None = None) -> tuple[np.ndarray, list[dict[str, Any]]]:
        """A new game against a newly drawn opponent: ``(obs (seats, n), infos)``."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        if self.side_rule == "either":
            self.side = "left" if self._rng.random() < 0.5 else "right"
        self.opponent = self.opponents(self._rng)
        game_seed = int(self._rng.integers(2**31))
        self._obs, infos = self.env.reset(seed=game_seed)
        self._return[:] = 0.0
        self._length = 0
        self._t0 = time.perf_counter()
        return self._stack(self._obs, self.mine), [dict(infos[a]) for a in self.mine]

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, bool, bool, list[dict[str, Any]]]:
        """One step of the game with the team's ``actions`` (seats, action size) and the
        opponent's: ``(obs, rewards (seats,), terminated, truncated, infos)``."""
        actions = np.asarray(actions, dtype=np.float32)
        if actions.shape != (self.seats, *self.action_space.shape):
            raise ValueError(
                f"team actions of shape {actions.shape}, expected "
                f"({self.seats}, {self.action_space.shape[0]})"
            )
        mine, theirs = self.mine, self.theirs
        joint = dict(zip(mine, actions, strict=True))
        if self.to_skills is not None:
            joint = self.to_skills(self.env, mine, joint)
        theirs_obs = {a: self._obs[a] for a in theirs}
        joint.update(self.opponent(self.env, theirs, theirs_obs) if theirs else {})
        self._obs, rewards, terms, truncs, infos = self.env.step(joint)
        r = np.array([rewards[a] for a in mine], dtype=float)
        self._return += r
        self._length += 1
        terminated = any(terms.values())
        truncated = any(truncs.values()) and not terminated
        out_infos = [dict(infos[a]) for a in mine]
        if terminated or truncated:
            own, other = out_infos[0]["score"]
            out_infos[0]["game"] = {
                "opponent": getattr(self.opponent, "name", type(self.opponent).__name__),
                "side": self.side,
                "goals_for": int(own),
                "goals_against": int(other),
                "end": out_infos[0].get("end", "time"),
            }
            wall = round(time.perf_counter() - self._t0, 6)
            for k, info in enumerate(out_infos):
                info["episode"] = {"r": float(self._return[k]), "l": self._length, "t": wall}
        return self._stack(self._obs, mine), r, terminated, truncated, out_infos

    def get_wrapper_attr(self, name: str) -> Any:
        """An attribute, as a Gymnasium environment answers it (for vector environments)."""
        return getattr(self, name)

    def close(self) -> None:
        self.env.close()

    def _stack(self, obs: Mapping[str, np.ndarray], agents: list[str]) -> np.ndarray:
        return np.stack([np.asarray(obs[a], dtype=np.float32) for a in agents])

"""Training a team: one policy shared by the players of a team (parameter sharing), against
opponents drawn from a pool of the policy's earlier versions and the scripted team.

``robocup-gym train penalty|keepaway|game-2v2|game-3v3 …`` trains on a team scenario
(:mod:`robocup_gym.soccer.team_view`): every player of the learning team is one environment of
the vector environment (a game of N a side fills N), so Stable-Baselines3's PPO learns one
policy from all of them. The games run in worker processes, each a block of whole games
(:class:`SeatBlock`, the project's vectorisation: :mod:`robocup_gym.train.vecenv`).

The opponents (:class:`OpponentPool`, the run's ``selfplay`` settings, :class:`SelfPlaySettings`):

=====================  ========  ==========================================================
setting                default   meaning
=====================  ========  ==========================================================
``snapshot_every``     50,000    steps between snapshots of the policy into the pool
``pool_size``          10        the newest this many snapshots are drawn from
``scripted_share``     0.5       share of games against the scripted team (all of them
                                 while the pool is empty)
=====================  ========  ==========================================================

A game against the pool draws one of the newest ``pool_size`` snapshots uniformly; it plays
deterministically. In ``penalty`` and ``keepaway`` the learning team has one role (the striker,
the attackers) that its snapshots cannot swap, so the opponent there is always the scripted
team. Snapshots are files in the run folder (``opponents/policy-<steps>.pt``,
SB3's own policy format), read by the workers as they appear, so a resumed run continues with
its pool. Ratings (TrueSkill, from the ``trueskill`` library) of the learning policy
(``current``), the scripted team and every snapshot are updated with every finished game,
saved in ``opponents/ratings.json``, and logged to TensorBoard (``selfplay/*``) and to
``progress.csv`` with the goals for and against (:data:`SELFPLAY_FIELDS`).
"""

from __future__ import annotations

import json
import os
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.train.vecenv import EnvBlock
from robocup_gym.types import is_number, reject_unknown_fields

__all__ = [
    "SELFPLAY_FIELDS",
    "OpponentPool",
    "Ratings",
    "SeatBlock",
    "SelfPlayCallback",
    "SelfPlaySettings",
    "TeamFactory",
    "make_team_vec_env",
    "snapshot_policy",
]

SNAPSHOT_PREFIX = "policy-"
SCRIPTED = "scripted"
CURRENT = "current"


@dataclass(frozen=True)
class SelfPlaySettings:
    """How a team run draws its opponents (the module docstring's table)."""

    snapshot_every: int = 50_000
    pool_size: int = 10
    scripted_share: float = 0.5

    def __post_init__(self) -> None:
        for name in ("snapshot_every", "pool_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"selfplay {name} must be a positive integer, got {value!r}")
        share = self.scripted_share
        if not (is_number(share) and 0.0 <= share <= 1.0):
            raise ValueError(f"selfplay scripted_share must be within 0 and 1, got {share!r}")

    @classmethod
    def of(cls, data: Mapping[str, Any] | None) -> SelfPlaySettings:
        """The settings with ``data`` over the defaults.

        Raises:
            ValueError: an unknown setting (naming the known ones) or a bad value.
        """
        reject_unknown_fields(cls, data or {}, "selfplay setting", "settings")
        return cls(**dict(data or {}))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


# ---------------------------------------------------------------------------- the pool
def snapshot_steps(path: Path) -> int:
    """The training steps in a snapshot's name (``policy-50000.pt`` → 50000)."""
    return int(path.stem[len(SNAPSHOT_PREFIX) :])


def snapshots(pool_dir: str | os.PathLike) -> list[Path]:
    """The pool's snapshots, oldest first."""
    d = Path(pool_dir)
    if not d.is_dir():
        return []
    found = d.glob(f"{SNAPSHOT_PREFIX}*.pt")
    found = [p for p in found if p.stem[len(SNAPSHOT_PREFIX) :].isdigit()]
    return sorted(found, key=snapshot_steps)


def snapshot_policy(policy: Any, pool_dir: str | os.PathLike, steps: int) -> Path:
    """Save ``policy`` (an SB3 policy) into the pool as ``policy-<steps>.pt``; written to a
    temporary name first, so that a worker never reads half a file."""
    d = Path(pool_dir)
    d.mkdir(parents=True, exist_ok=True)
    path = d / f"{SNAPSHOT_PREFIX}{int(steps)}.pt"
    tmp = d / f".{path.name}.tmp"
    policy.save(str(tmp))
    os.replace(tmp, path)
    return path


class OpponentPool:
    """Draws a game's opponent: the scripted team with probability ``scripted_share`` (always
    while the pool is empty), else one of the newest ``pool_size`` snapshots in ``pool_dir``,
    uniformly. Picklable; each worker keeps the snapshots it has loaded."""

    def __init__(
        self,
        pool_dir: str | os.PathLike | None,
        settings: SelfPlaySettings,
        team_options: Mapping[str, Any] | None = None,
    ) -> None:
        self.pool_dir = None if pool_dir is None else str(pool_dir)
        self.settings = settings
        self.team_options = dict(team_options or {})
        """The learning team's own options (``plays``, ``over_scripted``), which its snapshots
        play with."""
        self._loaded: dict[str, Any] = {}
        self._scripted: Any = None

    def __getstate__(self) -> dict[str, Any]:
        return {
            "pool_dir": self.pool_dir,
            "settings": self.settings,
            "team_options": self.team_options,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["pool_dir"], state["settings"], state.get("team_options"))

    def __call__(self, rng: np.random.Generator) -> Any:
        pool = [] if self.pool_dir is None else snapshots(self.pool_dir)
        pool = pool[-self.settings.pool_size :]
        if not pool or rng.random() < self.settings.scripted_share:
            if self._scripted is None:
                from robocup_gym.soccer.scripted import ScriptedTeam

                self._scripted = ScriptedTeam()
            return self._scripted
        path = pool[int(rng.integers(len(pool)))]
        team = self._loaded.get(path.name)
        if team is None:
            from robocup_gym.soccer.learnt import PolicyTeam

            team = PolicyTeam.from_policy_file(path, name=path.stem, options=self.team_options)
            self._loaded = {path.name: team, **dict(list(self._loaded.items())[-15:])}
        return team


# ---------------------------------------------------------------------------- vectorisation
class TeamFactory:
    """Picklable constructor of one team game (:class:`~robocup_gym.soccer.team_view.TeamView`)
    for a worker; ``seats``: its players (environments of the vector environment)."""

    def __init__(
        self,
        scenario: str,
        options: Mapping[str, Any],
        opponents: OpponentPool,
        seed: int | None,
    ) -> None:
        from robocup_gym.soccer.team_view import scenario_options

        self.scenario = scenario
        self.options = dict(options)
        self.opponents = opponents
        self.seed = seed
        resolved = scenario_options(scenario, self.options)
        self.seats = len(resolved["left_types"])

    def __call__(self) -> Any:
        from robocup_gym.soccer.team_view import TeamView

        return TeamView(self.scenario, self.opponents, self.options, seed=self.seed)


class SeatBlock(EnvBlock):
    """A block of team games: game ``g`` fills environments ``g·seats … g·seats + seats − 1``
    (its players in uniform-number order). Same semantics as :class:`EnvBlock` (auto-reset with
    ``terminal_observation``, errors naming the game), also for whole rollouts."""

    @staticmethod
    def seats_of(env_fns: Sequence[Callable[[], Any]]) -> int:
        seats = {int(getattr(f, "seats", 1)) for f in env_fns}
        if len(seats) != 1:
            raise ValueError(f"the games of one vector environment differ in size: {seats}")
        return seats.pop()

    what = "game"

    def _make(self, fn: Callable[[], Any]) -> Any:
        return fn()

    def _step(self, data: Any) -> tuple:
        s = self.seats
        obs_rows, rewards, dones, infos, reset_infos = [], [], [], [], []
        for g, game in enumerate(self.envs):
            self._current = g
            obs, r, terminated, truncated, info = game.step(data[g * s : (g + 1) * s])
            done = terminated or truncated
            resets: list[dict[str, Any]] = [{} for _ in range(s)]
            for k in range(s):
                info[k]["TimeLimit.truncated"] = truncated and not terminated
                if done:
                    info[k]["terminal_observation"] = obs[k]
            if done:
                obs, resets = game.reset()
            obs_rows.append(obs)
            rewards.append(r)
            dones += [done] * s
            infos += info
            reset_infos += resets
        return (
            np.concatenate(obs_rows),
            np.concatenate(rewards),
            np.array(dones, dtype=bool),
            infos,
            reset_infos,
        )

    def _reset(self, data: Any) -> list:
        out = []
        for g, game in enumerate(self.envs):
            self._current = g
            obs, infos = game.reset(seed=data[g * self.seats][0])  # the game's first player's
            out += list(zip(obs, infos, strict=True))
        return out


def make_team_vec_env(
    scenario: str,
    n_games: int,
    *,
    options: Mapping[str, Any] | None = None,
    pool: OpponentPool | None = None,
    seed: int | None = 0,
    kind: str = "auto",
    n_workers: int = 0,
    start_method: str = "",
    ray_address: str = "",
    ray_start_timeout_s: float = 60.0,
):
    """A vector environment of ``n_games`` games of team scenario ``scenario``, one environment
    per player of the learning team (game ``i`` seeded with ``seed + i``). ``kind``: ``"dummy"``
    (in this process), ``"subproc"`` or ``"auto"`` (worker processes, ``n_workers``: 0 = one
    per CPU core, at most one per game), or ``"ray"`` (Ray actors, on the cluster at
    ``ray_address`` or an embedded Ray; each hosts whole games).

    Raises:
        ValueError: an unknown scenario or option.
    """
    from robocup_gym.soccer.team_view import TEAM_OPTIONS, scenario_options, team_scenario
    from robocup_gym.train.vecenv import block_vec_env

    pool = pool or OpponentPool(None, SelfPlaySettings())
    resolved = scenario_options(scenario, options)
    own = {k: resolved[k] for k in TEAM_OPTIONS}  # the snapshots act as the team does
    if team_scenario(scenario)[1] != "either":
        # the learning team has one role (the striker, the attackers): its earlier versions
        # cannot play the other, so the opponent is the scripted team
        pool = OpponentPool(None, pool.settings)
    else:
        pool = OpponentPool(pool.pool_dir, pool.settings, own)
    factories = [
        TeamFactory(scenario, options or {}, pool, None if seed is None else seed + i)
        for i in range(n_games)
    ]
    return block_vec_env(
        factories,
        kind=kind,
        n_workers=n_workers,
        start_method=start_method,
        ray_address=ray_address,
        ray_start_timeout_s=ray_start_timeout_s,
        block_class=SeatBlock,
    )


# ---------------------------------------------------------------------------- ratings
class Ratings:
    """TrueSkill ratings (the ``trueskill`` library) by player name, one game at a time."""

    def __init__(self, draw_probability: float = 0.3) -> None:
        import trueskill

        self._env = trueskill.TrueSkill(draw_probability=draw_probability)
        self.ratings: dict[str, Any] = {}

    def __getitem__(self, name: str) -> Any:
        if name not in self.ratings:
            self.ratings[name] = self._env.create_rating()
        return self.ratings[name]

    def record(self, a: str, b: str, goals_a: int, goals_b: int) -> None:
        """A game of ``a`` against ``b`` that ended ``goals_a`` : ``goals_b``."""
        ranks = [0, 0] if goals_a == goals_b else ([0, 1] if goals_a > goals_b else [1, 0])
        (ra,), (rb,) = self._env.rate([(self[a],), (self[b],)], ranks=ranks)
        self.ratings[a], self.ratings[b] = ra, rb

    def copy_rating(self, source: str, target: str) -> None:
        self.ratings[target] = self[source]

    def to_dict(self) -> dict[str, dict[str, float]]:
        return {n: {"mu": r.mu, "sigma": r.sigma} for n, r in sorted(self.ratings.items())}

    def load(self, data: Mapping[str, Mapping[str, float]]) -> None:
        """Ratings as :meth:`to_dict` gave them."""
        for name, r in data.items():
            self.ratings[name] = self._env.create_rating(mu=float(r["mu"]), sigma=float(r["sigma"]))

    def conservative(self, name: str) -> float:
        """μ − 3σ: a rating the player exceeds with 99.7 % confidence."""
        r = self[name]
        return float(r.mu - 3.0 * r.sigma)


# ---------------------------------------------------------------------------- the callback
SELFPLAY_FIELDS = (
    "games",
    "goals_for_mean",
    "goals_against_mean",
    "goal_difference_vs_scripted",
    "win_rate_vs_scripted",
    "rating_mu",
    "rating_sigma",
    "scripted_rating_mu",
    "pool_size",
)
"""The columns a team run adds to ``progress.csv`` (means over the recent games)."""


def _callback_base():
    from stable_baselines3.common.callbacks import BaseCallback

    return BaseCallback


class SelfPlayCallback(_callback_base()):  # type: ignore[misc]
    """Snapshots the policy into the pool every ``settings.snapshot_every`` steps, rates every
    finished game, and logs the games' figures (:data:`SELFPLAY_FIELDS`)."""

    def __init__(
        self,
        pool_dir: str | os.PathLike,
        settings: SelfPlaySettings,
        window: int = 100,
        on_snapshot: Callable[[Path], None] | None = None,
    ) -> None:
        super().__init__()
        self.pool_dir = Path(pool_dir)
        self.settings = settings
        self.ratings = Ratings()
        self.recent: deque[tuple[str, int, int]] = deque(maxlen=window)
        self.games = 0
        self.on_snapshot = on_snapshot
        self._next_snapshot = 0

    @property
    def ratings_path(self) -> Path:
        return self.pool_dir / "ratings.json"

    def _on_training_start(self) -> None:
        self.pool_dir.mkdir(parents=True, exist_ok=True)
        if self.ratings_path.exists():  # a resumed run keeps its ratings
            saved = json.loads(self.ratings_path.read_text())
            self.ratings.load(saved["ratings"])
            self.games = int(saved["games"])
        every = self.settings.snapshot_every
        self._next_snapshot = (self.num_timesteps // every + 1) * every

    def _on_step(self) -> bool:
        for info in self.locals.get("infos") or ():
            game = info.get("game") if isinstance(info, dict) else None
            if game:
                self.record(game)
        if self.num_timesteps >= self._next_snapshot:
            self.snapshot()
        return True

    def record(self, game: Mapping[str, Any]) -> None:
        """One finished game: ``info["game"]`` of a
        :class:`~robocup_gym.soccer.team_view.TeamView`."""
        opponent = str(game["opponent"])
        gf, ga = int(game["goals_for"]), int(game["goals_against"])
        self.ratings.record(CURRENT, opponent, gf, ga)
        self.recent.append((opponent, gf, ga))
        self.games += 1

    def snapshot(self) -> Path:
        """The policy now, into the pool (with the current rating)."""
        join = getattr(self.model, "join_update", None)
        if join is not None:  # an update running in the background: never half of one
            join()
        path = snapshot_policy(self.model.policy, self.pool_dir, self.num_timesteps)
        self.ratings.copy_rating(CURRENT, path.stem)
        self._save_ratings()
        every = self.settings.snapshot_every
        self._next_snapshot = (self.num_timesteps // every + 1) * every
        if self.on_snapshot is not None:
            self.on_snapshot(path)
        return path

    def _save_ratings(self) -> None:
        data = {"games": self.games, "ratings": self.ratings.to_dict()}
        tmp = self.ratings_path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=1) + "\n")
        os.replace(tmp, self.ratings_path)

    def _on_rollout_end(self) -> None:
        for key, value in self.figures().items():
            if value is not None:
                self.logger.record(f"selfplay/{key}", value)
        self._save_ratings()

    def _on_training_end(self) -> None:
        self._save_ratings()

    def figures(self) -> dict[str, Any]:
        """The recent games' figures (:data:`SELFPLAY_FIELDS`; ``None`` where there is none)."""
        games = list(self.recent)
        vs = [(gf, ga) for o, gf, ga in games if o == SCRIPTED]
        current = self.ratings[CURRENT]
        return {
            "games": self.games,
            "goals_for_mean": _mean([gf for _, gf, _ in games]),
            "goals_against_mean": _mean([ga for _, _, ga in games]),
            "goal_difference_vs_scripted": _mean([gf - ga for gf, ga in vs]),
            "win_rate_vs_scripted": _mean([float(gf > ga) for gf, ga in vs]),
            "rating_mu": round(float(current.mu), 3),
            "rating_sigma": round(float(current.sigma), 3),
            "scripted_rating_mu": round(float(self.ratings[SCRIPTED].mu), 3),
            "pool_size": len(snapshots(self.pool_dir)),
        }


def _mean(values: Sequence[float]) -> float | None:
    return round(float(np.mean(values)), 4) if len(values) else None


def next_command(scenario: str, run: str | os.PathLike) -> str:
    """The command that plays a team run against the scripted team (keepaway: its learning
    curve; matches are games and penalties)."""
    from robocup_gym.soccer.team_view import team_scenario

    if scenario == "keepaway":
        return f"robocup-gym experiments team {run}"
    if scenario == "penalty":
        return f"robocup-gym match {run} scripted --scenario penalty"
    types = team_scenario(scenario)[2]["left_types"]
    out = f"robocup-gym match {run} scripted --players {len(types)}"
    if len(types) >= 5:  # the match's default types would include type 4
        out += " --types " + ",".join(map(str, types))
    return out


# ---------------------------------------------------------------------------- export
def team_description(options: Mapping[str, Any]) -> dict[str, Any]:
    """A team policy's observation and action layout for its export: the scenario options,
    one label per observation value and per action value."""
    from robocup_gym.robot.nao import nao_model
    from robocup_gym.soccer.ball_play import PLAY_ACTION_LABELS
    from robocup_gym.soccer.observations import observation_labels
    from robocup_gym.soccer.skills import DEFAULT_MOTION_SKILLS, skill_action_labels

    model = nao_model(int(options["left_types"][0]))
    mates, opponents = len(options["left_types"]) - 1, len(options["right_types"])
    labels = observation_labels(model, bool(options.get("privileged")), mates, opponents)
    return {
        "env_config": dict(options),
        "observation_labels": labels,
        "action_labels": list(
            PLAY_ACTION_LABELS
            if options.get("plays")
            else skill_action_labels(options.get("skills", DEFAULT_MOTION_SKILLS))
        ),
    }


def team_observations(
    scenario: str, options: Mapping[str, Any], steps: int = 64, seed: int = 0
) -> np.ndarray:
    """Observations of the learning team from a game in which it and its opponent play the
    scripted team (``steps`` steps; ``(steps × players, n)``): real inputs to check an export."""
    from robocup_gym.soccer.ball_play import as_play_action
    from robocup_gym.soccer.scripted import ScriptedTeam
    from robocup_gym.soccer.team_view import TeamView

    scripted = ScriptedTeam()
    view = TeamView(scenario, lambda rng: scripted, options, seed=seed)
    try:
        obs, _ = view.reset(seed=seed)
        rows = [obs]
        for _ in range(steps - 1):
            acts = scripted(view.env, view.mine)
            if view.options["plays"]:
                acts = {a: as_play_action(act) for a, act in acts.items()}
            elif view.options["over_scripted"]:  # no correction: the scripted team
                acts = {a: np.zeros_like(act) for a, act in acts.items()}
            obs, _, terminated, truncated, _ = view.step(np.stack([acts[a] for a in view.mine]))
            rows.append(obs)
            if terminated or truncated:
                obs, _ = view.reset()
        return np.concatenate(rows).astype(np.float32)
    finally:
        view.close()

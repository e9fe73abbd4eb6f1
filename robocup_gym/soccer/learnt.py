"""Teams played by a learnt policy: one policy shared by the team's players, each acting on its
own observation (:mod:`robocup_gym.soccer.observations`) with skill actions (or, for a team
trained with ``plays``, skill actions or the ball played along a direction:
:mod:`robocup_gym.soccer.ball_play`; with ``over_scripted``, residuals over the scripted team).

A :class:`PolicyTeam` comes from a team run's folder (``robocup-gym train game-2v2``), from its
ONNX export (``robocup-gym export RUN --onnx FILE``, or a shipped team as ``pretrained:NAME``),
or from a snapshot of the self-play pool. It plays deterministically.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from robocup_gym.soccer.team_view import team_actions

__all__ = ["PolicyTeam", "team_task_error"]


def team_task_error(what: str, task: str, options: Mapping[str, Any]) -> str | None:
    """Why a policy trained on ``task`` with ``options`` cannot play a team (``None``: it can)."""
    if not str(task).startswith("soccer/"):
        return (
            f"{what} was trained on {task!r}, not on a team scenario (robocup-gym train "
            "penalty|keepaway|game-2v2 …)"
        )
    if options.get("actions", "skills") != "skills":
        return f"{what} acts with {options.get('actions')!r} actions; a team plays skill actions"
    return None


class PolicyTeam:
    """A team played by ``act`` (observations ``(players, n)`` → skill actions), which takes
    ``obs_size`` values per player; ``options`` are the scenario options it was trained with."""

    def __init__(
        self,
        act: Callable[[np.ndarray], np.ndarray],
        obs_size: int,
        name: str,
        options: Mapping[str, Any] | None = None,
        task: str = "",
    ) -> None:
        self.act = act
        self.obs_size = int(obs_size)
        self.name = name
        self.options = dict(options or {})
        self.task = task
        """The team scenario it was trained on (``soccer/game-2v2``; empty if unknown)."""
        self._to_skills = team_actions(self.options)
        """Turns its actions into skill actions (``None``: it acts with skill actions)."""

    @property
    def privileged(self) -> bool:
        """Whether it observes the privileged part (ground truth)."""
        return bool(self.options.get("privileged", False))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_policy_file(
        cls,
        path: str | os.PathLike,
        name: str | None = None,
        options: Mapping[str, Any] | None = None,
    ) -> PolicyTeam:
        """A Stable-Baselines3 policy saved with ``policy.save`` (a self-play snapshot), trained
        with the scenario options ``options`` (``plays``, ``over_scripted``: how it acts)."""
        import torch
        from stable_baselines3.common.policies import ActorCriticPolicy

        torch.set_num_threads(1)
        policy = ActorCriticPolicy.load(str(path), device="cpu")
        policy.set_training_mode(False)

        def act(x: np.ndarray) -> np.ndarray:
            return policy.predict(x, deterministic=True)[0]

        return cls(act, policy.observation_space.shape[0], name or Path(path).stem, options)

    @classmethod
    def from_run(cls, run: str | os.PathLike) -> PolicyTeam:
        """The final policy of a team run's folder.

        Raises:
            ValueError: not a run, or a run of another kind of task.
        """
        from robocup_gym.train.run import load_model, load_run

        info = load_run(run)
        cfg = info.config
        options = cfg.env_options()
        error = team_task_error(f"run {info.path}", cfg.env_id, options)
        if error is not None:
            raise ValueError(error)
        model = load_model(info)
        model.policy.set_training_mode(False)

        def act(x: np.ndarray) -> np.ndarray:
            return model.predict(x, deterministic=True)[0]

        return cls(act, model.observation_space.shape[0], str(info.path), options, cfg.env_id)

    @classmethod
    def from_onnx(cls, path: str | os.PathLike, name: str | None = None) -> PolicyTeam:
        """An exported team policy (``robocup-gym export``).

        Raises:
            ValueError: not an exported policy, or one of another kind of task.
        """
        from robocup_gym.train.onnx_policy import OnnxPolicy

        policy = OnnxPolicy(path)
        meta = policy.metadata
        options = {**(meta.get("env_config") or {}), **(meta.get("env_kwargs") or {})}
        error = team_task_error(f"policy {path}", meta.get("env_id", "?"), options)
        if error is not None:
            raise ValueError(error)
        shape = int(meta["input"]["shape"][1])
        return cls(policy, shape, name or str(path), options, meta.get("env_id", ""))

    def check_fits(self, scenario: str, players: int, penalties: bool = True) -> None:
        """Raise ``ValueError`` if it was trained for another kind of match than ``scenario``
        (``game``, ``penalty``) with ``players`` a side (``penalties``: whether the command
        plays penalties too, so that the message may suggest it)."""
        if not self.task:
            return
        trained = self.task.split("/", 1)[-1]
        want = "penalty" if scenario == "penalty" else f"game-{players}v{players}"
        if trained != want:
            hint = "--scenario penalty" if trained == "penalty" and penalties else None
            if hint is None and trained.startswith("game-"):
                hint = f"--players {trained.split('-')[1].split('v')[0]}"
            raise ValueError(
                f"team {self.name} was trained on {trained}, this match is {want}"
                + (f" (play it with {hint})" if hint else "")
            )

    # ------------------------------------------------------------------ playing
    def __call__(
        self, env: Any, agents: list[str], obs: Mapping[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        if not agents:
            return {}
        if obs is None:
            raise ValueError(f"team {self.name} acts on its players' observations; none given")
        x = np.stack([np.asarray(obs[a], dtype=np.float32) for a in agents])
        if x.shape[1] > self.obs_size and not self.privileged:
            x = x[:, : self.obs_size]  # a game with the privileged part (last), which it lacks
        if x.shape[1] != self.obs_size:
            raise ValueError(
                f"team {self.name} observes {self.obs_size} values a player, the game gives "
                f"{x.shape[1]} (its robot types or observation options differ from training)"
            )
        actions = dict(zip(agents, np.asarray(self.act(x), dtype=float), strict=True))
        if self._to_skills is not None:  # plays actions, residuals: skill actions
            return self._to_skills(env, agents, actions)
        return actions

"""Run folders: what a training run leaves behind and how to load it back.

Layout of ``runs/<task>-<algo>-<YYYYmmdd-HHMMSS>/``::

    config.yaml          the exact TrainConfig (resolved hyperparameters included)
    model.zip            the final SB3 model (written when training ends or is interrupted)
    vecnormalize.pkl     observation statistics (only with normalize_obs: true)
    checkpoints/         model_<steps>_steps.zip every checkpoint_freq steps (+ replay buffer)
    tb/                  TensorBoard logs (tensorboard --logdir runs)
    progress.csv         learning curve: steps, wall-clock, mean return, ball Δx, fall rate
    evaluations.jsonl    periodic deterministic evaluations during training
    eval.json            the last ``robocup-gym eval`` result
"""

from __future__ import annotations

import csv
import os
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robocup_gym.train.algos import algo_class
from robocup_gym.train.config import TrainConfig

_CKPT = re.compile(r"model_(\d+)_steps\.zip$")


def curve_so_far(curve: Path) -> tuple[float, int]:
    """Wall-clock seconds and episodes of a run so far (the last row of its progress.csv;
    ``(0.0, 0)`` when there is none)."""
    if not curve.exists():
        return 0.0, 0
    last = None
    with curve.open() as f:
        for row in csv.DictReader(f):
            last = row
    if not last:
        return 0.0, 0
    try:
        wall = float(last["wall_s"])
    except (KeyError, TypeError, ValueError):
        wall = 0.0
    try:
        episodes = int(float(last["episodes"]))
    except (KeyError, TypeError, ValueError):
        episodes = 0
    return wall, episodes


def space_mismatch(a, b) -> tuple[str, tuple, tuple] | None:
    """The first of the observation and action spaces whose shapes differ between ``a`` and
    ``b`` (environments or models), as ``(name, a's shape, b's shape)``; ``None`` if both
    match."""
    for name in ("observation_space", "action_space"):
        sa, sb = getattr(a, name).shape, getattr(b, name).shape
        if sa != sb:
            return name, sa, sb
    return None


def new_run_dir(root: str | os.PathLike, task: str, algo: str) -> Path:
    """A fresh ``root/<task>-<algo>-<timestamp>`` folder (suffixed if it already exists)."""
    root = Path(root)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = root / f"{task}-{algo}-{stamp}"
    path, k = base, 1
    while path.exists():
        k += 1
        path = base.with_name(f"{base.name}-{k}")
    path.mkdir(parents=True)
    return path


def checkpoints(run: Path) -> list[tuple[int, Path]]:
    """``(steps, path)`` of the run's checkpoints, oldest first."""
    d = Path(run) / "checkpoints"
    out = []
    if d.is_dir():
        for p in d.iterdir():
            m = _CKPT.search(p.name)
            if m:
                out.append((int(m.group(1)), p))
    return sorted(out)


@dataclass
class RunInfo:
    path: Path
    config: TrainConfig

    @property
    def model_path(self) -> Path:
        """``model.zip``, or the newest checkpoint when training did not finish."""
        final = self.path / "model.zip"
        if final.exists():
            return final
        ckpts = checkpoints(self.path)
        if ckpts:
            return ckpts[-1][1]
        raise FileNotFoundError(f"{self.path} holds no model.zip and no checkpoint")

    def latest_model_path(self) -> Path:
        """The model with the most training: the newest of ``model.zip`` and the checkpoints."""
        candidates = [(p.stat().st_mtime, p) for _, p in checkpoints(self.path)]
        final = self.path / "model.zip"
        if final.exists():
            candidates.append((final.stat().st_mtime, final))
        if not candidates:
            raise FileNotFoundError(f"{self.path} holds no model.zip and no checkpoint")
        return max(candidates)[1]

    @property
    def vecnormalize_path(self) -> Path | None:
        for p in (self.path / "vecnormalize.pkl", self.path / "checkpoints" / "vecnormalize.pkl"):
            if p.exists():
                return p
        return None

    def obs_stats(self) -> tuple[np.ndarray, np.ndarray, float, float] | None:
        """``(mean, var, epsilon, clip_obs)`` of the saved VecNormalize, or ``None``."""
        p = self.vecnormalize_path
        if not self.config.normalize_obs or p is None:
            return None
        import pickle

        with p.open("rb") as f:
            vn = pickle.load(f)
        return (
            np.asarray(vn.obs_rms.mean, dtype=np.float64),
            np.asarray(vn.obs_rms.var, dtype=np.float64),
            float(vn.epsilon),
            float(vn.clip_obs),
        )

    def obs_normalizer(self) -> Callable[[np.ndarray], np.ndarray] | None:
        stats = self.obs_stats()
        if stats is None:
            return None
        mean, var, eps, clip = stats

        def normalize(obs: np.ndarray) -> np.ndarray:
            out = np.clip((obs - mean) / np.sqrt(var + eps), -clip, clip)
            return out.astype(np.float32)

        return normalize


def load_run(run: str | os.PathLike) -> RunInfo:
    """Read a run folder (its ``config.yaml``)."""
    path = Path(run)
    cfg_path = path / "config.yaml"
    if not cfg_path.exists():
        raise FileNotFoundError(f"{path} is not a run folder (no config.yaml)")
    return RunInfo(path=path, config=TrainConfig.load(cfg_path))


def load_model(info: RunInfo, checkpoint: str | os.PathLike | None = None, env=None):
    """The run's SB3 model (final model, or a given checkpoint), on the CPU.

    Raises:
        FileNotFoundError: naming the model or checkpoint file that is not there.
    """
    cls = algo_class(info.config.algo)
    path = Path(checkpoint) if checkpoint is not None else info.model_path
    if not path.is_file():  # (Stable-Baselines3 would look for the name with .zip added)
        what = "checkpoint" if checkpoint is not None else "the run's model"
        raise FileNotFoundError(f"{what} {path} does not exist")
    return cls.load(path, env=env, device="cpu")

"""Episodes of a policy on one environment, with a metrics record per episode."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from robocup_gym.train.metrics import episode_record

__all__ = ["run_episodes"]


def run_episodes(
    model,
    env,
    episodes: int,
    *,
    seed: int | None = 0,
    deterministic: bool = True,
    obs_normalizer: Callable[[np.ndarray], np.ndarray] | None = None,
    on_step: Callable[[Any], None] | None = None,
) -> list[dict[str, float]]:
    """Run ``episodes`` episodes of ``model`` on a single (non-vectorised) Gymnasium ``env``.

    Episode ``k`` is reset with ``seed + k``. ``on_step(env)`` is called after every reset and
    step (for video frames). Returns one metrics record per episode (see
    :func:`robocup_gym.train.metrics.episode_record`).
    """
    records = []
    for k in range(episodes):
        obs, info = env.reset(seed=None if seed is None else seed + k)
        if on_step is not None:
            on_step(env)
        ret, length, done = 0.0, 0, False
        while not done:
            o = obs_normalizer(obs) if obs_normalizer is not None else obs
            action, _ = model.predict(o, deterministic=deterministic)
            obs, reward, terminated, truncated, info = env.step(action)
            if on_step is not None:
                on_step(env)
            ret += float(reward)
            length += 1
            done = terminated or truncated
        records.append(episode_record(info, ret, length))
    return records

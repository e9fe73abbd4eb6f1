"""Overlapped PPO updates (``overlap_updates=True``): each rollout acts with the policy from
before the update that runs beside it (a lag of exactly one rollout), the buffer holds that
policy's log-probabilities and values, runs are reproducible, and a failing update is reported."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import torch as th
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback

from robocup_gym.train.pipelined import PipelinedPPO

from .train_helpers import small_pipelined_ppo, small_vec_env


def _flat(policy) -> np.ndarray:
    return th.cat([p.detach().flatten() for p in policy.parameters()]).numpy().copy()


class _Snapshots(BaseCallback):
    """At the end of every rollout (after the overlapped update joined): the learner's
    parameters, the parameters that acted in the rollout, and a check of the buffer's
    log-probabilities and values against the acting policy."""

    def __init__(self) -> None:
        super().__init__()
        self.learner: list[np.ndarray] = []
        self.acting: list[np.ndarray] = []
        self.logp_error: list[float] = []
        self.value_error: list[float] = []

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        model = self.model
        acting = model._rollout_policy()
        self.learner.append(_flat(model.policy))
        self.acting.append(_flat(acting))
        rb = model.rollout_buffer
        obs = th.as_tensor(rb.observations.reshape(-1, *rb.obs_shape))
        actions = th.as_tensor(rb.actions.reshape(-1, rb.action_dim))
        with th.no_grad():
            values, log_prob, _ = acting.evaluate_actions(obs, actions)
        self.logp_error.append(float(np.abs(log_prob.numpy() - rb.log_probs.flatten()).max()))
        self.value_error.append(float(np.abs(values.flatten().numpy() - rb.values.flatten()).max()))


def _learn(overlap: bool, rollouts: int = 4):
    venv = small_vec_env()
    try:
        model = small_pipelined_ppo(
            venv, n_epochs=2, learning_rate=1e-3, use_sde=True, overlap_updates=overlap
        )
        cb = _Snapshots()
        model.learn(16 * 4 * rollouts, callback=cb)
        return model, cb
    finally:
        venv.close()


def test_overlapped_rollouts_act_with_the_policy_from_before_the_running_update():
    model, cb = _learn(True)
    assert model.num_timesteps == 4 * 64
    assert model._update_thread is None  # the run's last update finished
    # rollout 0 and 1 act with the initial policy (update 0 runs beside rollout 1); from then
    # on rollout k acts with the learner's parameters from the end of rollout k - 1
    np.testing.assert_array_equal(cb.acting[0], cb.learner[0])
    for k in range(1, len(cb.acting)):
        np.testing.assert_array_equal(cb.acting[k], cb.learner[k - 1])
        assert not np.array_equal(cb.learner[k], cb.learner[k - 1]), "an update ran"
    # the buffer holds the acting policy's log-probabilities and values
    assert max(cb.logp_error) < 1e-4
    assert max(cb.value_error) < 1e-5


def test_without_overlap_every_rollout_acts_with_the_current_policy():
    _, cb = _learn(False, rollouts=3)
    for acting, learner in zip(cb.acting, cb.learner, strict=True):
        np.testing.assert_array_equal(acting, learner)
    assert max(cb.logp_error) < 1e-4


def test_overlapped_runs_are_reproducible():
    a, _ = _learn(True, rollouts=3)
    b, _ = _learn(True, rollouts=3)
    np.testing.assert_array_equal(_flat(a.policy), _flat(b.policy))


def test_a_failing_background_update_is_reported(monkeypatch):
    calls = {"n": 0}
    original = PPO.train

    def failing_train(self):
        calls["n"] += 1
        if calls["n"] == 2:
            raise FloatingPointError("loss is NaN")
        original(self)

    monkeypatch.setattr(PPO, "train", failing_train)
    with pytest.raises(RuntimeError, match="background PPO update failed") as info:
        _learn(True, rollouts=4)
    assert isinstance(info.value.__cause__, FloatingPointError)


def test_overlapped_model_saves_and_loads(tmp_path):
    model, _ = _learn(True, rollouts=2)
    model.save(tmp_path / "m.zip")
    loaded = PipelinedPPO.load(tmp_path / "m.zip", device="cpu")
    np.testing.assert_array_equal(_flat(loaded.policy), _flat(model.policy))
    assert loaded.overlap_updates is True

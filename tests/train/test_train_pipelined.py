"""Pipelined rollouts fill exactly the buffer that SB3's lock-step loop fills."""

from __future__ import annotations

import numpy as np
import pytest
import torch as th

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.callbacks import BaseCallback

from robocup_gym.train.pipelined import PipelinedPPO

# short episodes, so that a rollout crosses falls, time limits (bootstrapped) and auto-resets
from .train_helpers import small_pipelined_ppo, small_vec_env


class _Record(BaseCallback):
    """Keeps what every on_step saw."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[tuple] = []
        self.rollouts = 0

    def _on_step(self) -> bool:
        rewards = np.array(self.locals["rewards"], dtype=float).copy()
        dones = np.array(self.locals["dones"]).copy()
        n_ep = sum("episode" in i for i in self.locals["infos"])
        self.seen.append((self.num_timesteps, rewards, dones, n_ep))
        return True

    def _on_rollout_end(self) -> None:
        self.rollouts += 1


def _row_by_row(policy) -> None:
    """Make ``policy``'s forward pass evaluate one observation at a time (gSDE: with that
    environment's exploration matrix), so that its float32 results do not depend on how many
    environments are stepped together: the lock-step loop evaluates all four, the pipelined one
    each worker's two. Rounding differences of ~1e-6 in the actions would otherwise be amplified
    by the physics (ODE-like contacts switch on sub-micrometre depths) and hide what this test
    compares: which step, environment and policy each buffer row comes from."""
    forward = policy.forward
    dist = policy.action_dist

    def rows(obs, deterministic=False):
        mats = getattr(dist, "exploration_matrices", None)
        mat = getattr(dist, "exploration_mat", None)
        out = []
        try:
            for k in range(len(obs)):
                if mats is not None and len(obs) > 1:
                    dist.exploration_mat = mats[k] if len(mats) == len(obs) else mat
                out.append(forward(obs[k : k + 1], deterministic))
        finally:
            if mats is not None:
                dist.exploration_matrices, dist.exploration_mat = mats, mat
        return tuple(th.cat(parts) for parts in zip(*out, strict=True))

    policy.forward = rows


def _collect(
    pipelined: bool, use_sde: bool, rollouts: int = 2, workers: bool = False, rows: bool = True
):
    """Buffers of ``rollouts`` rollouts; ``workers``: the workers play them (their own copy of
    the policy, whose forward pass is not made row by row); ``rows``: the learner's policy
    evaluates one observation at a time."""
    venv = small_vec_env()
    try:
        model = small_pipelined_ppo(
            venv, use_sde=use_sde, pipeline_rollouts=pipelined, worker_rollouts=workers
        )
        if rows:
            _row_by_row(model._rollout_policy())
        assert model.can_pipeline(venv) == pipelined
        cb = _Record()
        model._setup_learn(16 * 4 * rollouts, cb)
        cb.init_callback(model)
        buffers = []
        for _ in range(rollouts):
            assert model.collect_rollouts(venv, cb, model.rollout_buffer, 16)
            rb = model.rollout_buffer
            buffers.append(
                {
                    k: getattr(rb, k).copy()
                    for k in (
                        "observations",
                        "actions",
                        "rewards",
                        "episode_starts",
                        "values",
                        "log_probs",
                        "advantages",
                        "returns",
                    )
                }
            )
        return buffers, cb, model
    finally:
        venv.close()


@pytest.mark.parametrize("use_sde", [True, False], ids=["gsde", "gaussian"])
def test_pipelined_rollout_matches_lockstep(use_sde):
    sync, cb_sync, m_sync = _collect(False, use_sde)
    pipe, cb_pipe, m_pipe = _collect(True, use_sde)
    assert cb_pipe.rollouts == cb_sync.rollouts == 2
    assert [s[0] for s in cb_pipe.seen] == [s[0] for s in cb_sync.seen]
    assert m_pipe.num_timesteps == m_sync.num_timesteps == 128
    # episodes ended and were counted the same way
    assert sum(s[3] for s in cb_pipe.seen) == sum(s[3] for s in cb_sync.seen) > 0
    assert len(m_pipe.ep_info_buffer) == len(m_sync.ep_info_buffer)
    # both start from the same reset
    np.testing.assert_array_equal(pipe[0]["observations"][0], sync[0]["observations"][0])
    for bs, bp in zip(sync, pipe, strict=True):
        assert bp["episode_starts"].any(), "the rollout should cross episode ends"
        if use_sde:  # same actions: gSDE noise is latent · M_i with the same matrices
            for key, a in bs.items():
                np.testing.assert_allclose(bp[key], a, rtol=1e-5, atol=1e-5, err_msg=key)
        else:  # noise drawn up front: other numbers, same distribution and bookkeeping
            assert np.isfinite(bp["log_probs"]).all()
            assert np.abs(bp["actions"]).max() > 0.0


@pytest.mark.parametrize("use_sde", [True, False], ids=["gsde", "gaussian"])
def test_rollouts_played_by_the_workers_are_the_learner_s_to_the_bit(use_sde):
    """Each worker computes its block's actions with a copy of the policy: the same numbers as
    the learner computing them block by block, so the same buffers and episodes."""
    learner, cb_l, m_l = _collect(True, use_sde, workers=False, rows=False)
    workers, cb_w, m_w = _collect(True, use_sde, workers=True, rows=False)
    assert [s[0] for s in cb_w.seen] == [s[0] for s in cb_l.seen]
    assert m_w.num_timesteps == m_l.num_timesteps == 128
    assert len(m_w.ep_info_buffer) == len(m_l.ep_info_buffer) > 0
    for bl, bw in zip(learner, workers, strict=True):
        assert bw["episode_starts"].any(), "the rollout should cross episode ends"
        for key, a in bl.items():
            np.testing.assert_array_equal(bw[key], a, err_msg=key)


@pytest.mark.parametrize("workers", [False, True], ids=["learner", "workers"])
def test_pipelined_runs_are_reproducible(workers):
    a, _, _ = _collect(True, False, rollouts=1, workers=workers)
    b, _, _ = _collect(True, False, rollouts=1, workers=workers)
    for key in a[0]:
        np.testing.assert_array_equal(a[0][key], b[0][key], err_msg=key)


def test_callback_can_stop_a_pipelined_rollout():
    class _Stop(BaseCallback):
        def _on_step(self) -> bool:
            return self.num_timesteps < 12

    venv = small_vec_env()
    try:
        model = PipelinedPPO("MlpPolicy", venv, n_steps=8, batch_size=16, seed=1, device="cpu")
        model.learn(64, callback=_Stop())
        assert model.num_timesteps == 12
        obs, *_ = venv.step(np.zeros((4, *venv.action_space.shape), dtype=np.float32))
        assert obs.shape[0] == 4  # the vector env is still usable (no worker left waiting)
    finally:
        venv.close()


@pytest.mark.parametrize("n", [1, 4])
@pytest.mark.parametrize(
    "kwargs",
    [
        {"use_sde": True},
        {"use_sde": False},
        {"use_sde": True, "policy_kwargs": {"net_arch": [32, 16], "activation_fn": th.nn.ReLU}},
        {"use_sde": False, "policy_kwargs": {"net_arch": {"pi": [16], "vf": [32, 32]}}},
    ],
    ids=["gsde", "gaussian", "gsde-relu", "gaussian-separate-nets"],
)
def test_block_forward_is_sb3_s_forward_pass_to_the_bit(kwargs, n):
    """The blocks' forward pass (its functional ops, no distribution objects) gives SB3's own
    actions, values and log-probabilities to the bit, for a batch of one and of several."""
    from stable_baselines3.common.utils import obs_as_tensor

    from robocup_gym.train import pipelined
    from robocup_gym.train.vecenv import make_vec_env

    venv = make_vec_env("RobocupGym/VelocityKick-v0", 1, kind="dummy")
    try:
        model = small_pipelined_ppo(venv, **kwargs)
    finally:
        venv.close()
    policy = model.policy
    policy.set_training_mode(False)
    with th.no_grad():
        policy.log_std.add_(-1.0)  # away from the initial zeros
    rng = np.random.default_rng(n)
    obs = rng.uniform(-1.0, 1.0, (n, *model.observation_space.shape)).astype(np.float32)
    mats = eps = None
    if kwargs["use_sde"]:
        policy.reset_noise(n)
        mats = policy.action_dist.exploration_matrices
    else:
        eps = th.as_tensor(rng.normal(size=(n, *model.action_space.shape)), dtype=th.float32)
    with th.no_grad():
        obs_tensor = obs_as_tensor(obs, "cpu")
        lean = pipelined._lean_forward(policy, obs_tensor, mats, eps)
        assert lean is not None, "the MLP policies training uses take the lean path"
        reference = pipelined._sb3_forward(policy, obs_tensor, mats, eps)
    for name, a, b in zip(("actions", "values", "log_probs"), lean, reference, strict=True):
        assert th.equal(a.reshape(b.shape), b), name

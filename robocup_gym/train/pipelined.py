"""PPO with pipelined rollouts: each worker steps its environments on its own clock.

Stable-Baselines3's PPO collects a rollout in lock-step: the policy computes actions for all
environments, every worker steps its block, the learner waits for the *slowest* worker, and
only then computes the next actions. With the paper's 16 environments on a 2-core machine this
leaves the cores idle a third of the time (measured, VelocityKick: a worker is busy 6.9 ms per
step on average, but the learner waits 10.7 ms, because episode ends — a reset plus 20 wait
cycles — make one worker's step much longer than the other's, and the policy's forward pass
runs while both workers wait).

:class:`PipelinedPPO` keeps each worker (:class:`~robocup_gym.train.vecenv.BlockVecEnv`
block) on its own clock. By default (``worker_rollouts``) each worker plays its block's whole
rollout with a copy of the policy: the learner sends the policy's weights and the rollout's noise
once, every worker steps its environments and computes their actions without waiting for anyone,
and sends the rollout back (one round trip per rollout, on local workers and on Ray actors
alike). With ``worker_rollouts=False`` the learner computes the actions: whenever a worker
returns a step, the policy computes that block's next actions at once and sends them back, while
the other workers are still stepping. Either way the rollout ends when every block has
``n_steps`` steps; the per-step callbacks then run in step order with what SB3 would have given
them, and the buffer, returns and advantages are the same, to the bit: a worker computes its
block's actions exactly as the learner would (the same block, the same noise, one torch thread).

What is, and is not, the same as SB3's loop:

* The policy is fixed during a rollout, so every action is drawn from the same distribution as
  in SB3. With gSDE (the paper's setting) the noise of environment ``i`` is
  ``latent · M_i`` with the rollout's per-environment matrix ``M_i`` — exactly SB3's action.
  With a plain Gaussian policy the rollout's noise is drawn up front (one ``randn`` of shape
  ``(n_steps, n_envs, action_dim)``) instead of step by step, so runs are just as
  reproducible but draw different numbers from the same seed than SB3's loop.
* Results never depend on which worker answers first (no random number is drawn during the
  rollout), so a run is reproducible from its seed.
* The callbacks' ``on_step`` runs after the rollout instead of between steps (progress bars and
  checkpoints then move once per rollout, ~1 s); a callback that stops training still stops it.

Any other setting (one worker, a wrapped vector env such as ``VecNormalize``, a non-Box action
space, gSDE with ``sde_sample_freq > 0``) uses SB3's own loop unchanged.

**Overlapped updates** (``overlap_updates=True``; off by default in this class, on by default
in ``robocup-gym train``, see :data:`robocup_gym.train.config.PPO_RUN_DEFAULTS`): PPO's update
(the gradient steps, ~40 % of a run's time on a 2-core machine) runs in a background thread while
the workers already collect the next rollout, with the policy as it was *before* that update (a
policy lag of one rollout, as in asynchronous PPO variants). The behaviour policy's
log-probabilities and values are stored with each step, so the next update's ratio and
advantages are computed against the policy that really acted (PPO's clipping then also bounds
the one-rollout lag). This is not the paper's schedule (``overlap_updates=False`` keeps that).
The update joins before the rollout's callbacks run, so checkpoints, evaluations and logs
always see a finished update, and the last update of a run is never overlapped. Results stay
reproducible from the seed (the join points are fixed; only the update thread draws the
minibatch permutations).
"""

from __future__ import annotations

import math
import threading

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.distributions import (
    DiagGaussianDistribution,
    StateDependentNoiseDistribution,
)
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.utils import obs_as_tensor
from torch import nn
from torch.nn import functional

from robocup_gym.train.vecenv import BlockVecEnv


class PipelinedPPO(PPO):
    """:class:`stable_baselines3.PPO` whose rollouts are pipelined per worker (module docstring).

    Args:
        pipeline_rollouts: ``False`` collects rollouts with SB3's lock-step loop.
        overlap_updates: run each update in the background while the next rollout is collected
            with the previous policy (module docstring; needs pipelined rollouts, else ignored).
        worker_rollouts: each worker plays its block's whole rollout with a copy of the policy
            (one round trip per rollout); ``False``: the learner computes every step's actions
            and sends them to the worker whose step came back (one round trip per step).
        value_warmup_steps: the updates within a run's first this many steps train the value
            network alone, the policy held as it is: a policy that starts from a trained one
            whose value network starts afresh (``--init-from pretrained:NAME``) is not moved
            by the advantages of a value network that has learnt nothing yet.
        *args, **kwargs: As :class:`stable_baselines3.PPO`.
    """

    def __init__(
        self,
        *args,
        pipeline_rollouts: bool = True,
        overlap_updates: bool = False,
        worker_rollouts: bool = True,
        value_warmup_steps: int = 0,
        **kwargs,
    ) -> None:
        if not (isinstance(value_warmup_steps, int) and value_warmup_steps >= 0):
            raise ValueError(f"value_warmup_steps must be an int >= 0, got {value_warmup_steps!r}")
        self.value_warmup_steps = value_warmup_steps
        self.pipeline_rollouts = pipeline_rollouts
        self.overlap_updates = overlap_updates
        self.worker_rollouts = worker_rollouts
        self._update_thread: threading.Thread | None = None
        self._update_error: BaseException | None = None
        self._behaviour = None
        super().__init__(*args, **kwargs)

    # ------------------------------------------------------------------ overlapped updates
    def _overlapping(self) -> bool:
        return bool(self.overlap_updates) and self.env is not None and self.can_pipeline(self.env)

    def _rollout_policy(self):
        """The policy that acts in the rollout being collected: a frozen copy of the policy
        from before the running update when updates overlap, else the policy itself."""
        if not self._overlapping():
            return self.policy
        if self._behaviour is None:
            # a second policy of the same architecture (its own optimizer is never used)
            params = self.policy._get_constructor_parameters()
            self._behaviour = type(self.policy)(**params).to(self.device)
            self._behaviour.load_state_dict(self.policy.state_dict())
        return self._behaviour

    def join_update(self) -> None:
        """Wait for a background update to finish; re-raise its exception, if any."""
        thread, self._update_thread = self._update_thread, None
        if thread is not None:
            thread.join()
        error, self._update_error = self._update_error, None
        if error is not None:
            raise RuntimeError("the background PPO update failed") from error

    def _update(self) -> None:
        """PPO's update (within ``value_warmup_steps``, the value network's alone)."""
        held = []
        if self.num_timesteps <= self.value_warmup_steps:
            held = [
                p
                for name, p in self.policy.named_parameters()
                if "value_net" not in name and p.requires_grad
            ]
        for p in held:
            p.requires_grad_(False)
        try:
            super().train()
        finally:
            for p in held:
                p.requires_grad_(True)

    def _background_update(self) -> None:
        try:
            self._update()
        except BaseException as e:  # re-raised by join_update in the learner's thread
            self._update_error = e

    def train(self) -> None:
        """PPO's update; in the background when updates overlap (except a run's last one)."""
        self.join_update()
        last = self.num_timesteps >= getattr(self, "_total_timesteps", 0)
        if not self._overlapping() or last:
            self._update()
            if self._behaviour is not None:
                self._behaviour.load_state_dict(self.policy.state_dict())
            return
        # the next rollout acts with the policy as it is now, while this update runs
        self._rollout_policy().load_state_dict(self.policy.state_dict())
        self._update_thread = threading.Thread(
            target=self._background_update, name="ppo-update", daemon=True
        )
        self._update_thread.start()

    def learn(self, *args, **kwargs):
        try:
            return super().learn(*args, **kwargs)
        finally:
            self.join_update()

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_behaviour", "_update_thread", "_update_error"]

    def save(self, *args, **kwargs) -> None:
        self.join_update()  # never save a half-applied update
        super().save(*args, **kwargs)

    def can_pipeline(self, env) -> bool:
        """Whether :meth:`collect_rollouts` pipelines this vector env (else SB3's loop)."""
        dist = self.policy.action_dist
        return (
            self.pipeline_rollouts
            and isinstance(env, BlockVecEnv)
            and len(env.blocks) > 1
            and isinstance(self.action_space, spaces.Box)
            and isinstance(self.observation_space, spaces.Box)
            and not self.policy.squash_output
            and (
                (isinstance(dist, StateDependentNoiseDistribution) and self.sde_sample_freq <= 0)
                or (isinstance(dist, DiagGaussianDistribution) and not self.use_sde)
            )
        )

    def collect_rollouts(self, env, callback, rollout_buffer, n_rollout_steps: int) -> bool:
        if not self.can_pipeline(env):
            return super().collect_rollouts(env, callback, rollout_buffer, n_rollout_steps)
        assert self._last_obs is not None, "No previous observation was provided"
        policy = self._rollout_policy()
        policy.set_training_mode(False)
        n_envs, steps = env.num_envs, n_rollout_steps
        eps = None
        if self.use_sde:
            policy.reset_noise(n_envs)
        else:
            eps = th.randn((steps, n_envs, *self.action_space.shape), device=self.device)
        callback.on_rollout_start()
        if self.worker_rollouts:
            mats = policy.action_dist.exploration_matrices if eps is None else None
            got = env.rollout(policy, steps, self._last_obs, eps, mats)
        else:
            got = self._rollout_by_learner(env, policy, steps, eps)
        obs, actions, clipped = got["obs"], got["actions"], got["clipped"]
        values, log_probs = th.as_tensor(got["values"]), th.as_tensor(got["log_probs"])
        rewards, dones, infos = got["rewards"], got["dones"], got["infos"]
        restarted = got.get("restarted")

        # Truncated episodes: bootstrap with the value of their last observation (SB3 #633).
        cut = [
            (t, i)
            for t in range(steps)
            for i in range(n_envs)
            if dones[t, i]
            and infos[t][i].get("terminal_observation") is not None
            and infos[t][i].get("TimeLimit.truncated", False)
        ]
        if cut:
            terminal = np.stack([infos[t][i]["terminal_observation"] for t, i in cut])
            with th.no_grad():
                tv = policy.predict_values(obs_as_tensor(terminal, self.device)).flatten()
            for (t, i), v in zip(cut, tv.cpu().numpy(), strict=True):
                rewards[t, i] += self.gamma * v

        # A background update (overlapped mode) finishes before the callbacks (checkpoints,
        # evaluations) see the model and before its buffer is refilled.
        self.join_update()
        rollout_buffer.reset()
        # Replay the steps in order: callbacks, episode statistics and the buffer, as SB3 does.
        episode_starts = self._last_episode_starts
        if restarted is not None and restarted.any():  # a lost actor's block started afresh
            episode_starts = np.where(restarted, True, episode_starts)
        for t in range(steps):
            self.num_timesteps += n_envs
            callback.update_locals(
                {
                    "actions": actions[t],
                    "clipped_actions": clipped[t],
                    "values": values[t],
                    "log_probs": log_probs[t],
                    "new_obs": obs[t + 1],
                    "rewards": rewards[t],
                    "dones": dones[t],
                    "infos": infos[t],
                    "n_steps": t,
                    "env": env,
                    "callback": callback,
                    "rollout_buffer": rollout_buffer,
                }
            )
            if not callback.on_step():
                self._last_obs = obs[t + 1]
                self._last_episode_starts = dones[t]
                return False
            self._update_info_buffer(infos[t], dones[t])
            rollout_buffer.add(
                obs[t], actions[t], rewards[t], episode_starts, values[t], log_probs[t]
            )
            episode_starts = dones[t]
        self._last_obs = obs[steps]
        self._last_episode_starts = dones[steps - 1]
        with th.no_grad():
            last_values = policy.predict_values(obs_as_tensor(obs[steps], self.device))
        rollout_buffer.compute_returns_and_advantage(last_values=last_values, dones=dones[-1])
        callback.update_locals({"new_obs": obs[steps], "dones": dones[-1], "values": last_values})
        callback.on_rollout_end()
        return True

    def _rollout_by_learner(self, env, policy, steps: int, eps: th.Tensor | None) -> dict:
        """The rollout with the learner computing every step's actions: whenever a worker
        returns a step, its block's next actions go out at once while the others still step.
        The same arrays as :meth:`~robocup_gym.train.vecenv.BlockVecEnv.rollout`."""
        n_envs = env.num_envs
        obs = np.empty((steps + 1, *np.shape(self._last_obs)), dtype=self._last_obs.dtype)
        obs[0] = self._last_obs
        actions = np.empty((steps, n_envs, *self.action_space.shape), dtype=np.float32)
        clipped = np.empty_like(actions)
        values = th.empty((steps, n_envs))
        log_probs = th.empty((steps, n_envs))
        rewards = np.empty((steps, n_envs))
        dones = np.empty((steps, n_envs), dtype=bool)
        infos: list[list] = [[None] * n_envs for _ in range(steps)]
        low, high = self.action_space.low, self.action_space.high
        blocks = env.blocks
        step_of = [0] * len(blocks)

        def act(w: int) -> None:
            t, b = step_of[w], blocks[w]
            with th.no_grad():
                a, v, lp = self._block_forward(
                    policy,
                    obs[t, b.start : b.stop],
                    b,
                    None if eps is None else eps[t, b.start : b.stop],
                )
            a = a.cpu().numpy()
            actions[t, b.start : b.stop] = a
            clipped[t, b.start : b.stop] = np.clip(a, low, high)
            values[t, b.start : b.stop] = v.flatten()
            log_probs[t, b.start : b.stop] = lp
            env.step_block_async(w, clipped[t, b.start : b.stop])

        for w in range(len(blocks)):
            act(w)
        running = list(range(len(blocks)))
        while running:
            for w in env.ready_blocks(running):
                t, b = step_of[w], blocks[w]
                o, r, d, info = env.step_block_wait(w)
                obs[t + 1, b.start : b.stop] = o
                rewards[t, b.start : b.stop] = r
                dones[t, b.start : b.stop] = d
                infos[t][b.start : b.stop] = info
                step_of[w] = t + 1
                if t + 1 < steps:
                    act(w)
                else:
                    running.remove(w)
        return {
            "obs": obs,
            "actions": actions,
            "clipped": clipped,
            "values": values,
            "log_probs": log_probs,
            "rewards": rewards,
            "dones": dones,
            "infos": infos,
        }

    def _block_forward(self, policy, obs: np.ndarray, block: range, eps: th.Tensor | None):
        """``(actions, values, log_probs)`` of one worker's environments (``block``) under
        ``policy``."""
        mats = None
        if eps is None:  # gSDE: this block's rows of the rollout's per-environment matrices
            mats = policy.action_dist.exploration_matrices[block.start : block.stop]
        return block_forward(policy, obs, self.device, mats, eps)


_LOG_SQRT_2PI = math.log(math.sqrt(2 * math.pi))
"""The constant of a Gaussian's log-density, as ``torch.distributions.Normal`` computes it."""


def _through(module: nn.Module, x: th.Tensor) -> th.Tensor:
    """``module(x)`` for the layers of an MLP (a ``Sequential`` of ``Linear`` and activations),
    with each linear layer and common activation applied as the functional op its module calls
    (the same numbers, without a module call's overhead per layer)."""
    for layer in module if isinstance(module, nn.Sequential) else (module,):
        kind = type(layer)
        if kind is nn.Linear:
            x = functional.linear(x, layer.weight, layer.bias)
        elif kind is nn.Tanh:
            x = th.tanh(x)
        elif kind is nn.ReLU:
            x = th.relu(x)
        else:
            x = layer(x)
    return x


def _lean_forward(policy, obs_tensor: th.Tensor, mats: th.Tensor | None, eps: th.Tensor | None):
    """:func:`block_forward` for an actor-critic MLP policy with a Gaussian or gSDE action
    distribution without squashing: SB3's ops in SB3's order on the policy's own tensors (the
    same numbers as ``policy(obs)``), without building its distribution objects; ``None`` for a
    policy of another kind."""
    if not isinstance(policy, ActorCriticPolicy):
        return None
    dist = policy.action_dist
    gsde = isinstance(dist, StateDependentNoiseDistribution)
    if gsde != (eps is None) or getattr(dist, "bijector", None) is not None:
        return None
    if not gsde and not isinstance(dist, DiagGaussianDistribution):
        return None
    extractor = policy.mlp_extractor
    features = policy.extract_features(obs_tensor)
    if policy.share_features_extractor:
        pi_features = vf_features = features
    else:
        pi_features, vf_features = features
    latent_pi = _through(extractor.policy_net, pi_features)
    latent_vf = _through(extractor.value_net, vf_features)
    values = _through(policy.value_net, latent_vf)
    mean = _through(policy.action_net, latent_pi)
    if gsde:
        latent = latent_pi if dist.learn_features else latent_pi.detach()
        std = th.sqrt(th.mm(latent**2, dist.get_std(policy.log_std) ** 2) + dist.epsilon)
        if len(latent) == 1:  # SB3 uses the single matrix for a batch of one
            noise = th.mm(latent, mats[0])
        else:
            noise = th.bmm(latent.unsqueeze(dim=1), mats).squeeze(dim=1)
        actions = mean + noise
    else:
        std = th.ones_like(mean) * policy.log_std.exp()
        actions = mean + std * eps
    log_prob = -((actions - mean) ** 2) / (2 * std**2) - std.log() - _LOG_SQRT_2PI
    return actions, values, log_prob.sum(dim=1)


def block_forward(policy, obs: np.ndarray, device, mats: th.Tensor | None, eps: th.Tensor | None):
    """``(actions, values, log_probs)`` of a block of environments under ``policy``: with gSDE
    (``eps`` None) the block's exploration matrices ``mats`` (one per environment), else the
    Gaussian noise ``eps`` drawn for them. The same numbers wherever it runs (the learner, or a
    Ray actor with a copy of the policy), and the same as SB3's forward pass
    (:func:`_lean_forward` for the MLP policies training uses)."""
    obs_tensor = obs_as_tensor(obs, device)
    lean = _lean_forward(policy, obs_tensor, mats, eps)
    return lean if lean is not None else _sb3_forward(policy, obs_tensor, mats, eps)


def _sb3_forward(policy, obs_tensor: th.Tensor, mats: th.Tensor | None, eps: th.Tensor | None):
    """:func:`block_forward` through SB3's own forward pass (any policy)."""
    if eps is None:
        dist = policy.action_dist
        saved = getattr(dist, "exploration_matrices", None), getattr(dist, "exploration_mat", None)
        if len(mats) == 1:  # SB3 uses the single matrix for a batch of one
            dist.exploration_mat = mats[0]
        else:
            dist.exploration_matrices = mats
        try:
            return policy(obs_tensor)
        finally:
            dist.exploration_matrices, dist.exploration_mat = saved
    distribution = policy.get_distribution(obs_tensor)
    normal = distribution.distribution
    a = normal.mean + normal.stddev * eps
    return a, policy.predict_values(obs_tensor), distribution.log_prob(a)

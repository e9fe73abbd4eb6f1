"""What the options of a PPO run cost per agent step, on the learner's side and the workers'.

A run's steps per second are bounded by the CPU its environment workers and its learner share
(``benchmarks/training_speed.py``). This measures the parts that the run's options change, each
against the default measured in the same run:

* the learner's update (``update_us_per_step``): one PPO update (``n_epochs`` passes over a
  rollout of ``n_steps`` × ``n_envs`` samples in minibatches of ``batch_size``) of the default
  task's policy (VelocityKick, the defaults of ``robocup-gym train``: gSDE, 2 × 256, fused Adam,
  one torch thread) on a rollout of random numbers of the right shapes (its cost does not
  depend on their values), then with one option changed at a time: ``batch_size`` 256, 512,
  1024; ``n_epochs`` 5; plain Gaussian noise instead of gSDE; two torch threads;
  ``torch.compile`` of the policy's ``evaluate_actions`` (the update's forward pass). Wall-clock
  µs of the update per agent step (one busy core; two with ``two_threads``) and
  ``<option>_vs_default`` (below 1: faster);
* the workers' block (``worker_agent_steps_per_s``): one worker's block of 1, 2, 4, 8 or 16
  environments stepped on one core with a fresh policy's actions (the episodes a run plays;
  ``training_speed.one_core_policy``), the policy's forward pass shared by the block;
* the bounds these put on ``train_vs_limit`` (``benchmarks/training_speed.py``: a run's steps/s
  over cores × one environment's under random actions on one core): every core busy and each
  agent step costing the default block's worker time plus the default update
  (``bound_train_vs_limit``), or the worker time alone (``bound_train_vs_limit_free_learner``);
* the traffic between learner and workers (``transfer_us_per_step``): one worker's round trip
  of a rollout through a pipe to another process (the policy's weights out, the rollout's arrays
  back, as the default schedule sends them: once per rollout), per agent step of that rollout.

A cheaper update is not a better run: fewer gradient steps per sample learn less per sample
(``benchmarks/learning.py`` measures that). Run it on a quiet machine.

    python benchmarks/training_options.py [--repeats 5] [--quick]

Prints one line per measure and, last, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np


def _shapes_env(env_id: str):
    """A Gymnasium environment with the task's spaces that simulates nothing (builds the
    model)."""
    import gymnasium as gym

    from robocup_gym.train.tasks import make_env

    env = make_env(env_id)
    obs_space, act_space = env.observation_space, env.action_space
    env.close()

    class Shapes(gym.Env):
        observation_space = obs_space
        action_space = act_space

        def reset(self, seed=None, options=None):
            return obs_space.sample(), {}

        def step(self, action):
            return obs_space.sample(), 0.0, False, False, {}

    return Shapes


def update_seconds(
    task: str, n_envs: int, repeats: int, threads: int = 1, compiled: bool = False, **over
) -> tuple[float, int]:
    """Seconds of one PPO update of ``task`` with the run's defaults and ``over`` (mean of
    ``repeats``, after one warm-up update) and the samples it learns from."""
    import torch
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import DummyVecEnv
    from training_speed import fresh_ppo

    from robocup_gym.train.tasks import resolve_task

    torch.set_num_threads(threads)
    venv = DummyVecEnv([_shapes_env(resolve_task(task))] * n_envs)
    model = fresh_ppo(task, venv, **over)
    model.set_logger(configure(None, [""]))
    buf = model.rollout_buffer
    rng = np.random.default_rng(0)
    buf.observations[:] = rng.uniform(-1.0, 1.0, buf.observations.shape)
    buf.actions[:] = rng.uniform(-1.0, 1.0, buf.actions.shape)
    buf.values[:] = rng.normal(size=buf.values.shape)
    buf.log_probs[:] = rng.normal(-5.0, 1.0, size=buf.log_probs.shape)
    buf.advantages[:] = rng.normal(size=buf.advantages.shape)
    buf.returns[:] = rng.normal(size=buf.returns.shape)
    buf.full = True
    if compiled:
        model.policy.evaluate_actions = torch.compile(model.policy.evaluate_actions)
    model.train()  # warm-up (and compilation)
    t0 = time.perf_counter()
    for _ in range(repeats):
        model.train()
    seconds = (time.perf_counter() - t0) / repeats
    venv.close()
    torch.set_num_threads(1)
    return seconds, buf.buffer_size * buf.n_envs


OPTIONS: dict[str, dict] = {
    "default": {},
    "batch_size_256": {"batch_size": 256},
    "batch_size_512": {"batch_size": 512},
    "batch_size_1024": {"batch_size": 1024},
    "n_epochs_5": {"n_epochs": 5},
    "no_gsde": {"use_sde": False},
    "two_threads": {"threads": 2},
    "torch_compile": {"compiled": True},
}
"""The measured variants: keyword arguments of :func:`update_seconds` over the defaults."""


def _echo(conn) -> None:
    """The other end of :func:`transfer_seconds`: send back what comes in, until ``None``."""
    while (msg := conn.recv()) is not None:
        conn.send(msg)


def transfer_seconds(task: str, block: int, n_steps: int, repeats: int) -> float:
    """Seconds of one worker's round trip of a rollout of ``task`` through a pipe to another
    process: the policy's weights (its ``state_dict``) out, then the rollout's arrays for
    ``block`` environments and ``n_steps`` steps back (mean of ``repeats``)."""
    import multiprocessing as mp

    from stable_baselines3.common.vec_env import DummyVecEnv
    from training_speed import fresh_ppo

    from robocup_gym.train.tasks import resolve_task

    venv = DummyVecEnv([_shapes_env(resolve_task(task))])
    model = fresh_ppo(task, venv)
    venv.close()
    state = {k: v.detach().cpu() for k, v in model.policy.state_dict().items()}
    n_obs = model.observation_space.shape[0]
    n_act = model.action_space.shape[0]
    f32 = np.float32
    arrays = {
        "obs": np.zeros((n_steps + 1, block, n_obs), f32),
        "actions": np.zeros((n_steps, block, n_act), f32),
        "clipped": np.zeros((n_steps, block, n_act), f32),
        "values": np.zeros((n_steps, block), f32),
        "log_probs": np.zeros((n_steps, block), f32),
        "rewards": np.zeros((n_steps, block), f32),
        "dones": np.zeros((n_steps, block), bool),
    }
    ctx = mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn")
    here, there = ctx.Pipe()
    child = ctx.Process(target=_echo, args=(there,), daemon=True)
    child.start()
    try:
        here.send(state)  # warm-up
        here.recv()
        t0 = time.perf_counter()
        for _ in range(repeats):
            here.send(state)
            here.recv()
            here.send(arrays)
            here.recv()
        # each round trip carries both directions twice: half of it is one rollout's traffic
        seconds = (time.perf_counter() - t0) / repeats / 2.0
    finally:
        here.send(None)
        child.join(10)
        if child.is_alive():
            child.kill()
    return seconds


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--task", default="velocity-kick")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="one update each, no compile")
    args = parser.parse_args(argv)
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.tasks import resolve_task

    env_id = resolve_task(args.task)
    n_envs = TrainConfig(task=args.task).n_envs
    repeats = 1 if args.quick else args.repeats
    options = {k: v for k, v in OPTIONS.items() if not (args.quick and k == "torch_compile")}
    cores = os.cpu_count() or 1
    out: dict = {"task": args.task, "cores": cores, "n_envs": n_envs, "repeats": repeats}
    per_step: dict[str, float] = {}
    for name, over in options.items():
        seconds, samples = update_seconds(args.task, n_envs, repeats, **over)
        per_step[name] = seconds / samples * 1e6
        print(
            f"{name:>16s}: {seconds * 1e3:7.1f} ms per update of {samples} samples, "
            f"{per_step[name]:6.1f} µs per agent step"
        )
    out["update_us_per_step"] = {k: round(v, 1) for k, v in per_step.items()}
    out.update({f"{k}_vs_default": round(v / per_step["default"], 3) for k, v in per_step.items()})
    from training_speed import one_core, one_core_policy

    steps = 500 if args.quick else 4_000
    random_rate = one_core(env_id, steps)
    out["env_agent_steps_per_s_one_core"] = round(random_rate, 1)
    print(f"   random actions: {random_rate:7.1f} agent steps/s on one core (the limit's unit)")
    blocks = {}
    for block in (1, 2, 4, 8, 16):
        blocks[str(block)] = round(one_core_policy(args.task, block, steps), 1)
        print(f"   block of {block:2d}: {blocks[str(block)]:7.1f} agent steps/s on one core")
    out["worker_agent_steps_per_s"] = blocks
    block = max(1, n_envs // cores)
    n_steps = TrainConfig(task=args.task).resolved_algo_kwargs()["n_steps"]
    transfer = transfer_seconds(args.task, block, n_steps, max(3, repeats))
    out["transfer_us_per_step"] = round(transfer / (block * n_steps) * 1e6, 2)
    print(
        f"        transfer: {transfer * 1e3:6.2f} ms per rollout of {block} × {n_steps} steps, "
        f"{out['transfer_us_per_step']} µs per agent step"
    )
    # what no schedule can beat: every core busy, each agent step costing its worker's share
    # and the update's (bound_train_vs_limit), or its worker's share alone (a free learner)
    worker_s = 1.0 / blocks[str(block)]
    update_s = per_step["default"] * 1e-6
    out["bound_train_vs_limit"] = round(1.0 / (worker_s + update_s) / random_rate, 3)
    out["bound_train_vs_limit_free_learner"] = round(1.0 / worker_s / random_rate, 3)
    print(
        f"  bounds: train_vs_limit <= {out['bound_train_vs_limit']} "
        f"({out['bound_train_vs_limit_free_learner']} with an update that cost nothing)"
    )
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

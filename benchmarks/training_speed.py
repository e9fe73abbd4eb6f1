"""How close does training come to the machine's limit? One run measures:

* ``env_agent_steps_per_s_one_core``: one environment of the task, random actions, in this
  process (agent steps; the wait cycles after an episode count in the time);
* ``vec_steps_per_s``: the ``n_envs`` environments as ``robocup-gym train`` builds them (one
  worker process per core), random actions, no learner;
* ``train_steps_per_s``: a PPO run of ``--timesteps`` steps with the defaults of
  ``robocup-gym train`` (the whole run, set-up excluded);
* ``train_vs_limit``: ``train_steps_per_s / (cores × env_agent_steps_per_s_one_core)``, and
  ``vec_vs_limit`` likewise;
* ``env_agent_steps_per_s_one_core_policy``: one worker's block of environments (``n_envs /
  cores``) stepped in this process with the actions of a fresh policy of the run's defaults:
  the episodes training plays, which end, reset and wait at another rate than under random
  actions (more often, on VelocityKick: each end costs a reset and 20 wait cycles), so this is
  the rate one core can give a run; ``train_vs_policy_limit`` = train / (cores × that);
* where the training run's time went, from CPU times: ``learner_cpu_share`` (the learner
  process: policy forward passes, updates, the vector environment's plumbing),
  ``workers_cpu_share`` (everything else the machine did: the environment workers, on a quiet
  machine), ``idle_share`` (cores × wall − both), each a share of cores × wall (Linux).

With ``--ray`` the same PPO run also goes through Ray actors (:mod:`robocup_gym.train.ray_vecenv`):
``ray_train_steps_per_s`` on an embedded Ray over this machine's cores and ``ray_vs_local``
against ``train_steps_per_s``; then ``ray_nodes``: the run on a Ray cluster of 1, 2 and 4
simulated nodes on this machine (``ray.cluster_utils.Cluster``; the nodes share its cores, so
this shows the overhead of more nodes, not a speed-up), each node ``max(1, cores // nodes)`` CPUs
and one actor per CPU.

    python benchmarks/training_speed.py [--task velocity-kick] [--timesteps 61440] [--quick] [--ray]

Prints one line per measure and, last, one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import tempfile
import time

import numpy as np


def _cpu(who: int) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def _machine_busy_s() -> float | None:
    """CPU seconds every core of the machine has been busy since boot (Linux ``/proc/stat``);
    ``None`` elsewhere. The environment workers are started by a fork server, not by this
    process, so their CPU time is the machine's minus the learner's (run on a quiet machine)."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()[1:]
    except OSError:
        return None
    user, nice, system, _idle, _iowait, irq, softirq, steal = (int(v) for v in fields[:8])
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def one_core(env_id: str, steps: int, seed: int = 0) -> float:
    from robocup_gym.train.tasks import make_env

    env = make_env(env_id)
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, env.action_space.shape))
        if terminated or truncated:
            env.reset()
    dt = time.perf_counter() - t0
    env.close()
    return steps / dt


def fresh_ppo(task: str, venv, seed: int = 0, **over):
    """The PPO model a run of ``task`` starts from (the hyperparameters of ``robocup-gym
    train``, ``over`` replacing some), on ``venv``, on the CPU."""
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.pipelined import PipelinedPPO

    kwargs = TrainConfig(task=task).resolved_algo_kwargs()
    kwargs.pop("overlap_updates", None)
    kwargs.update(over)
    return PipelinedPPO("MlpPolicy", venv, seed=seed, device="cpu", **kwargs)


def one_core_policy(task: str, n_envs: int, steps: int, seed: int = 0) -> float:
    """Agent steps per second of a block of ``n_envs`` environments of ``task`` stepped in this
    process with the actions of a fresh PPO policy (the run's defaults, its exploration noise):
    the episodes a run plays at its start, which end (fall, time limit; then a reset and the
    wait cycles) at another rate than under random actions."""
    import cloudpickle
    import torch

    from robocup_gym.train.tasks import resolve_task
    from robocup_gym.train.vecenv import EnvBlock, env_factories, make_vec_env

    torch.set_num_threads(1)
    env_id = resolve_task(task)
    template = make_vec_env(env_id, 1, seed=seed, kind="dummy")
    model = fresh_ppo(task, template, seed)
    template.close()
    policy = model.policy
    mats = None
    if model.use_sde:
        policy.reset_noise(n_envs)
        mats = policy.action_dist.exploration_matrices
    block = EnvBlock(env_factories(env_id, n_envs, seed=seed))
    obs = np.stack([o for o, _ in block.handle("reset", [(None, None)] * n_envs)])
    spec = cloudpickle.dumps((type(policy), policy._get_constructor_parameters()))
    per_call = max(1, steps // n_envs // 4)
    rng = torch.Generator().manual_seed(seed)
    t0 = time.perf_counter()
    for _ in range(4):
        eps = None
        if mats is None:
            eps = torch.randn((per_call, n_envs, *policy.action_space.shape), generator=rng)
        got = block.handle("rollout", ("p", spec, policy.state_dict(), per_call, obs, eps, mats))
        if not isinstance(got, dict):
            raise RuntimeError(got.message)
        obs = got["obs"][-1]
    dt = time.perf_counter() - t0
    block.close()
    return 4 * per_call * n_envs / dt


def vectorised(env_id: str, n_envs: int, steps: int) -> float:
    from robocup_gym.train.vecenv import make_vec_env

    venv = make_vec_env(env_id, n_envs, seed=0)
    try:
        rng = np.random.default_rng(0)
        venv.reset()
        shape = (n_envs, *venv.action_space.shape)
        t0 = time.perf_counter()
        for _ in range(steps // n_envs):
            venv.step(rng.uniform(-1, 1, shape))
        return (steps // n_envs) * n_envs / (time.perf_counter() - t0)
    finally:
        venv.close()


def training(task: str, timesteps: int, **placement) -> dict:
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.trainer import train

    cfg = TrainConfig(
        task=task,
        timesteps=timesteps,
        eval_freq=0,
        checkpoint_freq=0,
        checkpoint_every_s=0,
        **placement,
    )
    self0, busy0 = _cpu(resource.RUSAGE_SELF), _machine_busy_s()
    with tempfile.TemporaryDirectory() as out:
        result = train(cfg, out=out, progress=False)
    learner = _cpu(resource.RUSAGE_SELF) - self0
    busy1 = _machine_busy_s()
    workers = None if busy0 is None or busy1 is None else max(0.0, busy1 - busy0 - learner)
    return {
        "wall_s": result.wall_s,
        "steps_per_s": result.steps_per_s,
        "learner_cpu_s": learner,
        "workers_cpu_s": workers,
    }


def on_cluster(task: str, timesteps: int, nodes: int, cores: int) -> float:
    """``train_steps_per_s`` of the run on Ray actors over ``nodes`` simulated nodes."""
    import ray
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    per_node = max(1, cores // nodes)
    for _ in range(nodes):
        cluster.add_node(num_cpus=per_node)
    cluster.wait_for_nodes()
    ray.init(address=cluster.address, include_dashboard=False, logging_level="ERROR")
    try:
        return training(task, timesteps, vec_env="ray")["steps_per_s"]
    finally:
        ray.shutdown()
        cluster.shutdown()


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--task", default="velocity-kick")
    parser.add_argument("--timesteps", type=int, default=61_440)
    parser.add_argument("--quick", action="store_true", help="short measurements")
    parser.add_argument("--ray", action="store_true", help="also the run on Ray actors")
    args = parser.parse_args(argv)
    from robocup_gym.train.config import TrainConfig
    from robocup_gym.train.tasks import resolve_task

    cfg = TrainConfig(task=args.task)
    env_id = resolve_task(args.task)
    cores = os.cpu_count() or 1
    steps = 500 if args.quick else 5_000
    timesteps = 4_096 if args.quick else args.timesteps
    one = one_core(env_id, steps)
    per_worker = max(1, cfg.n_envs // cores)
    one_policy = one_core_policy(args.task, per_worker, steps)
    vec = vectorised(env_id, cfg.n_envs, steps * 2)
    run = training(args.task, timesteps)
    limit = cores * one
    capacity = cores * run["wall_s"]
    out = {
        "task": args.task,
        "cores": cores,
        "n_envs": cfg.n_envs,
        "env_agent_steps_per_s_one_core": round(one, 1),
        "vec_steps_per_s": round(vec, 1),
        "vec_vs_limit": round(vec / limit, 3),
        "train_steps_per_s": round(run["steps_per_s"], 1),
        "train_vs_limit": round(run["steps_per_s"] / limit, 3),
        "env_agent_steps_per_s_one_core_policy": round(one_policy, 1),
        "train_vs_policy_limit": round(run["steps_per_s"] / (cores * one_policy), 3),
        "train_timesteps": timesteps,
        "learner_cpu_share": round(run["learner_cpu_s"] / capacity, 3),
        "workers_cpu_share": None,
        "idle_share": None,
        "quick": args.quick,
    }
    if run["workers_cpu_s"] is not None:
        out["workers_cpu_share"] = round(run["workers_cpu_s"] / capacity, 3)
        busy = run["learner_cpu_s"] + run["workers_cpu_s"]
        out["idle_share"] = round(max(0.0, 1.0 - busy / capacity), 3)
    if args.ray:
        ray_run = training(args.task, timesteps, vec_env="ray")
        out["ray_train_steps_per_s"] = round(ray_run["steps_per_s"], 1)
        out["ray_vs_local"] = round(ray_run["steps_per_s"] / run["steps_per_s"], 3)
        out["ray_nodes"] = {
            str(n): round(on_cluster(args.task, timesteps, n, cores), 1) for n in (1, 2, 4)
        }
    for k, v in out.items():
        print(f"{k:34s} {v}")
    print(json.dumps(out))
    return out


if __name__ == "__main__":
    main()

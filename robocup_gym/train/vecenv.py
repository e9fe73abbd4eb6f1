"""Vectorised environments for training.

``n_envs`` environments run in ``n_workers`` subprocesses (default: one per CPU core, at most one
per environment). With one environment per worker this is SB3's ``SubprocVecEnv``; with several,
:class:`BatchedSubprocVecEnv` steps a block of environments per worker, so one pipe round trip
serves many environments (the paper's 16 workers on a 2-core machine would otherwise spend much
of their time in inter-process traffic and context switches).
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import multiprocessing.connection as mp_connection
import os
import signal
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from robocup_gym.backends import DEFAULT_ENGINE
from robocup_gym.train.tasks import make_env


class _EnvFactory:
    """Picklable constructor of one seeded environment (for subprocess workers)."""

    def __init__(
        self,
        env_id: str,
        backend: str,
        env_kwargs: dict[str, Any],
        seed: int | None,
        assist: dict[str, Any] | None = None,
    ) -> None:
        self.env_id = env_id
        self.backend = backend
        self.env_kwargs = dict(env_kwargs)
        self.seed = seed
        self.assist = assist

    def __call__(self) -> gym.Env:
        env = make_env(self.env_id, backend=self.backend, env_kwargs=self.env_kwargs)
        if self.assist is not None:
            from robocup_gym.envs.assist import TorsoAssist

            env = TorsoAssist(env, **self.assist)
        if self.seed is not None:
            env.reset(seed=self.seed)
            env.action_space.seed(self.seed)
        return env


def env_factories(
    env_id: str,
    n_envs: int,
    *,
    backend: str = DEFAULT_ENGINE,
    env_kwargs: dict[str, Any] | None = None,
    seed: int | None = 0,
    assist: dict[str, Any] | None = None,
    robot_types: Sequence[int] = (),
) -> list[Callable[[], gym.Env]]:
    """``n_envs`` constructors, environment ``i`` seeded with ``seed + i``. ``assist``: the
    keyword arguments of a :class:`~robocup_gym.envs.assist.TorsoAssist` around each
    environment, with ``decay_steps`` and ``start_step`` counted over all environments together
    (each gets its part), or ``None``. ``robot_types``: Nao types the environments take in
    turn (environment ``i`` is of type ``robot_types[i % len(robot_types)]``, over
    ``env_kwargs``' ``robot_type``); empty: all as ``env_kwargs`` say."""
    per_env = None
    if assist is not None and assist.get("share", 0.0) > 0.0:
        per_env = dict(assist)
        per_env["decay_steps"] = max(1, round(assist.get("decay_steps", 0) / n_envs))
        per_env["start_step"] = round(assist.get("start_step", 0) / n_envs)
    kwargs = [dict(env_kwargs or {}) for _ in range(n_envs)]
    for i, options in enumerate(kwargs if robot_types else ()):
        options["robot_type"] = int(robot_types[i % len(robot_types)])
    return [
        _EnvFactory(env_id, backend, kwargs[i], None if seed is None else seed + i, per_env)
        for i in range(n_envs)
    ]


WORKER_PRELOAD = (
    "__main__",
    "robocup_gym.train.vecenv",
    "robocup_gym.sim.engines.ode",
    "robocup_gym.train.selfplay",
)
"""What the fork server imports once, before it forks the workers: SB3 and torch (which every
worker needs for SB3's ``Monitor``), the tasks and the engines, so a worker starts in a tenth of
a second instead of importing them for ~1.5 s. ``__main__`` first, as multiprocessing does."""


def default_start_method() -> str:
    """``forkserver`` where available (safe with torch threads), else ``spawn``."""
    methods = mp.get_all_start_methods()
    return "forkserver" if "forkserver" in methods else "spawn"


def worker_start_method(start_method: str = "") -> str:
    """``start_method``, or :func:`default_start_method`; with the fork server, it is set to
    import :data:`WORKER_PRELOAD` when it starts (a fork server already running is left as
    it is)."""
    method = start_method or default_start_method()
    if method == "forkserver":
        mp.set_forkserver_preload(list(WORKER_PRELOAD))
    return method


def make_vec_env(
    env_id: str,
    n_envs: int,
    *,
    backend: str = DEFAULT_ENGINE,
    env_kwargs: dict[str, Any] | None = None,
    seed: int | None = 0,
    kind: str = "auto",
    start_method: str = "",
    n_workers: int = 0,
    assist: dict[str, Any] | None = None,
    robot_types: Sequence[int] = (),
    ray_address: str = "",
    ray_start_timeout_s: float = 60.0,
):
    """A vectorised environment of the task.

    ``kind``: ``"dummy"`` (all in this process), ``"subproc"`` (worker processes), ``"auto"``
    (dummy for one environment, else subprocesses) or ``"ray"`` (Ray actors on this machine, or
    on the cluster at ``ray_address``: :class:`~robocup_gym.train.ray_vecenv.RayVecEnv`).
    ``n_workers`` (0 = one per CPU core, with Ray one per CPU of the cluster; capped at
    ``n_envs``) is the number of workers. Every environment is wrapped in SB3's ``Monitor``
    (episode return/length for the logs). ``assist``, ``robot_types``: see
    :func:`env_factories`.
    """
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    factories = env_factories(
        env_id,
        n_envs,
        backend=backend,
        env_kwargs=env_kwargs,
        seed=seed,
        assist=assist,
        robot_types=robot_types,
    )
    wrapped = [_Monitored(f) for f in factories]
    if kind == "dummy" or (kind == "auto" and n_envs == 1):
        return DummyVecEnv(wrapped)
    if kind != "ray" and resolve_n_workers(n_envs, n_workers) == n_envs:
        return SubprocVecEnv(wrapped, start_method=worker_start_method(start_method))
    return block_vec_env(
        wrapped,
        kind=kind,
        n_workers=n_workers,
        start_method=start_method,
        ray_address=ray_address,
        ray_start_timeout_s=ray_start_timeout_s,
    )


def block_vec_env(
    env_fns: list[Callable[[], Any]],
    *,
    kind: str = "auto",
    n_workers: int = 0,
    start_method: str = "",
    ray_address: str = "",
    ray_start_timeout_s: float = 60.0,
    block_class: type[EnvBlock] | None = None,
) -> BlockVecEnv:
    """A :class:`BlockVecEnv` of ``env_fns`` (each giving ``block_class.seats_of`` environments)
    in blocks: ``kind`` ``"dummy"`` (one block in this process), ``"ray"`` (Ray actors on the
    cluster at ``ray_address`` or an embedded Ray) or else worker processes; ``n_workers``
    (0 = one per CPU core, or per CPU of the Ray cluster) blocks, at most one per constructor."""
    block_class = block_class or EnvBlock
    if kind == "dummy":
        return InProcessBlockVecEnv(env_fns, block_class=block_class)
    if kind == "ray":
        from robocup_gym.train.ray_vecenv import RayVecEnv

        return RayVecEnv(
            env_fns,
            n_workers=n_workers,
            address=ray_address or None,
            start_timeout_s=ray_start_timeout_s,
            block_class=block_class,
        )
    return BatchedSubprocVecEnv(
        env_fns,
        n_workers=resolve_n_workers(len(env_fns), n_workers),
        start_method=worker_start_method(start_method),
        block_class=block_class,
    )


def resolve_n_workers(n_envs: int, n_workers: int = 0) -> int:
    """Worker processes for ``n_envs`` environments (0 = one per available CPU core)."""
    if n_workers <= 0:
        try:
            n_workers = len(os.sched_getaffinity(0))
        except AttributeError:  # not on Linux
            n_workers = os.cpu_count() or 1
    return max(1, min(int(n_workers), n_envs))


class _WorkerError:
    """An exception raised inside a worker, sent back instead of the command's result."""

    def __init__(self, message: str) -> None:
        self.message = message


def _worker_failed(result: Any) -> Any:
    """``result`` unless it is a worker's error, which is raised here as a ``RuntimeError``."""
    if isinstance(result, _WorkerError):
        raise RuntimeError(result.message)
    return result


class EnvBlock:
    """A block of environments (global indices ``first_index``…) stepped together: what one
    worker process or Ray actor hosts. :meth:`handle` answers one command for the whole block;
    an exception in an environment comes back as a :class:`_WorkerError` naming the
    environment instead of ending the worker."""

    what = "environment"
    """What each constructor builds, for error messages."""

    def __init__(self, env_fns: Sequence[Callable[[], Any]], first_index: int = 0) -> None:
        self.first_index = first_index
        self.seats = self.seats_of(env_fns)
        self.envs: list = []
        self.broken: _WorkerError | None = None
        self._policy_key: str | None = None
        self._policy: Any = None
        self._current = 0
        """The built environment a command is at (for its error)."""
        for k, fn in enumerate(env_fns):
            try:
                self.envs.append(self._make(fn))
            except Exception as e:  # reported to the parent at its first command
                self.broken = _WorkerError(
                    f"creating {self.what} {first_index // self.seats + k} failed: "
                    f"{type(e).__name__}: {e}"
                )
                break

    def _make(self, fn: Callable[[], Any]) -> Any:
        """One environment from its constructor (an old-Gym one converted to Gymnasium)."""
        from stable_baselines3.common.vec_env.patch_gym import _patch_env

        return _patch_env(fn())

    @staticmethod
    def seats_of(env_fns: Sequence[Callable[[], Any]]) -> int:
        """Environments of the vector environment per constructor (1: each is one)."""
        return 1

    def close(self) -> None:
        for env in self.envs:  # those created before a failure, too
            env.close()

    def handle(self, cmd: str, data: Any) -> Any:
        """The answer to one command (``step``, ``reset``, ``get_spaces``, ``env_method``,
        ``get_attr``, ``has_attr``, ``set_attr``, ``is_wrapped``, ``render``); ``k`` in a
        command is an environment of the vector environment (``seats`` of them per built
        one)."""
        if self.broken is not None:
            return self.broken
        envs = self.envs
        n = len(envs) * self.seats
        if cmd in ("step", "reset") and len(data) != n:
            return _WorkerError(f"{cmd}: {len(data)} entries for {n} environments")
        self._current = 0
        try:
            if cmd == "step":
                return self._step(data)
            if cmd == "reset":
                return self._reset(data)
            if cmd == "rollout":
                return self.rollout(*data)
            if cmd == "get_spaces":
                return envs[0].observation_space, envs[0].action_space
            if cmd == "has_attr":
                try:
                    envs[0].get_wrapper_attr(data)
                    return True
                except AttributeError:
                    return False
            k = data[0] if isinstance(data, tuple) else data  # (k, …), or render's k
            self._current = k // self.seats
            env = envs[self._current]
            if cmd == "env_method":
                _, name, args, kwargs = data
                return env.get_wrapper_attr(name)(*args, **kwargs)
            if cmd == "get_attr":
                return env.get_wrapper_attr(data[1])
            if cmd == "set_attr":
                _, name, value = data
                return setattr(env, name, value)
            if cmd == "is_wrapped":
                from stable_baselines3.common.env_util import is_wrapped

                return is_wrapped(env, data[1])
            if cmd == "render":
                return env.render()
            return _WorkerError(f"unknown worker command {cmd!r}")
        except Exception as e:
            return _WorkerError(
                f"{cmd} failed in {self.what} {self.first_index // self.seats + self._current}: "
                f"{type(e).__name__}: {e}"
            )

    def _step(self, data: Any) -> tuple:
        """One step of every environment, those that end reset: the block's answer as one
        array per quantity (one pickle each, not one per environment): obs, rewards, dones,
        infos, reset infos."""
        envs = self.envs
        n = len(envs)
        obs_block: list = [None] * n
        rewards = np.empty(n)
        dones = np.empty(n, dtype=bool)
        infos: list = [None] * n
        reset_infos: list = [{} for _ in range(n)]
        for k in range(n):
            self._current = k
            env = envs[k]
            obs, reward, terminated, truncated, info = env.step(data[k])
            done = terminated or truncated
            info["TimeLimit.truncated"] = truncated and not terminated
            if done:
                info["terminal_observation"] = obs
                obs, reset_infos[k] = env.reset()
            obs_block[k], rewards[k], dones[k], infos[k] = obs, reward, done, info
        return np.stack(obs_block), rewards, dones, infos, reset_infos

    def _reset(self, data: Any) -> list:
        """Every environment reset with its ``(seed, options)``: ``[(obs, info), …]``."""
        out = []
        for k, env in enumerate(self.envs):
            self._current = k
            seed, options = data[k]
            kw = {"options": options} if options else {}
            out.append(env.reset(seed=seed, **kw))
        return out

    def rollout(self, key: str, spec: bytes, state: dict, steps: int, obs0, eps, mats) -> Any:
        """The block plays ``steps`` steps with a policy: ``spec`` is its class and constructor
        parameters (cloudpickled; built once per ``key``), ``state`` its weights now. From the
        observations ``obs0``, with the rollout's noise for these environments (``eps``, or
        gSDE's exploration matrices ``mats``). Returns the fragment's arrays (``obs`` with
        ``steps + 1`` rows, ``actions``, ``values``, ``log_probs``, ``rewards``, ``dones``,
        ``infos``, ``reset_infos`` of the last step), or the block's error."""
        import cloudpickle
        import torch as th

        from robocup_gym.train.pipelined import block_forward

        if self._policy_key != key:
            th.set_num_threads(1)  # as the learner acts: the same numbers
            cls, kwargs = cloudpickle.loads(spec)
            self._policy = cls(**kwargs)
            self._policy.set_training_mode(False)
            self._policy_key = key
        policy = self._policy
        policy.load_state_dict(state)
        n = len(obs0)
        space = policy.action_space
        obs = np.empty((steps + 1, *obs0.shape), dtype=obs0.dtype)
        obs[0] = obs0
        actions = np.empty((steps, n, *space.shape), dtype=np.float32)
        values = np.empty((steps, n), dtype=np.float32)
        log_probs = np.empty((steps, n), dtype=np.float32)
        rewards = np.empty((steps, n))
        dones = np.empty((steps, n), dtype=bool)
        infos: list = [None] * steps
        reset_infos: list = []
        for t in range(steps):
            noise = None if eps is None else eps[t]
            with th.no_grad():
                a, v, lp = block_forward(policy, obs[t], "cpu", mats, noise)
            actions[t] = a.numpy()
            values[t] = v.flatten().numpy()
            log_probs[t] = lp.numpy()
            answer = self.handle("step", np.clip(actions[t], space.low, space.high))
            if isinstance(answer, _WorkerError):
                return answer
            obs[t + 1], rewards[t], dones[t], infos[t], reset_infos = answer
        return {
            "obs": obs,
            "actions": actions,
            "values": values,
            "log_probs": log_probs,
            "rewards": rewards,
            "dones": dones,
            "infos": infos,
            "reset_infos": reset_infos,
        }


def _batched_worker(
    remote, parent_remote, env_fns_wrapper, first_index: int = 0, block_class: type = EnvBlock
) -> None:
    """A worker process: hosts an :class:`EnvBlock` (or ``block_class``) and answers the
    parent's commands over its pipe until ``close`` (or the pipe's end)."""
    parent_remote.close()
    # SIGTERM/SIGHUP sent to the whole process group (a job scheduler, a closed terminal) are
    # the parent's to handle: it saves the run and then closes the workers. A worker whose
    # parent dies ends anyway: its pipe reaches end-of-file.
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    block = block_class(env_fns_wrapper.var, first_index)
    try:
        while True:
            try:
                cmd, data = remote.recv()
            except (EOFError, KeyboardInterrupt):
                break
            if cmd == "close":
                block.close()
                remote.close()
                break
            remote.send(block.handle(cmd, data))
    except KeyboardInterrupt:
        pass


def _split(n: int, parts: int) -> list[range]:
    """``n`` indices in ``parts`` contiguous blocks of near-equal size."""
    base, extra = divmod(n, parts)
    out, start = [], 0
    for p in range(parts):
        size = base + (1 if p < extra else 0)
        out.append(range(start, start + size))
        start += size
    return out


class BlockVecEnv(VecEnv):
    """A vector environment whose environments live in blocks (``blocks[w]``, contiguous
    indices), each hosted by one worker (:class:`EnvBlock` in a process or a Ray actor) that
    steps its block on its own clock: :meth:`step_block_async`, :meth:`ready_blocks` and
    :meth:`step_block_wait` let a learner send a block its actions as soon as that block's last
    step is back (:class:`~robocup_gym.train.pipelined.PipelinedPPO`).

    Same semantics as SB3's ``SubprocVecEnv`` (auto-reset with ``terminal_observation`` in the
    info, seeds and options passed on the next reset). A subclass sends a command to a worker
    (:meth:`_send`), receives its answer (:meth:`_recv`) and waits for any of several
    (:meth:`ready_blocks`).
    """

    blocks: list[range]

    def _start_blocks(self, n_envs: int, n_workers: int, group: int = 1) -> None:
        """``n_envs`` environments in contiguous blocks, one per worker, each block made of
        whole groups of ``group`` (the seats of one game: :class:`SeatBlock`)."""
        games = n_envs // group
        self.blocks = [
            range(r.start * group, r.stop * group)
            for r in _split(games, max(1, min(n_workers, games)))
        ]
        self._where = [(w, k) for w, block in enumerate(self.blocks) for k in range(len(block))]
        self._block_pending = [False] * len(self.blocks)

    # ------------------------------------------------------------------ for subclasses
    def _send(self, worker: int, cmd: str, data: Any) -> None:
        raise NotImplementedError

    def _recv(self, worker: int) -> Any:
        """Worker ``worker``'s answer to its last command (a :class:`_WorkerError` as it came)."""
        raise NotImplementedError

    def ready_blocks(self, workers: Sequence[int]) -> list[int]:
        """Block until at least one of ``workers`` (each stepping) has its result; returns those
        that have, in ascending order."""
        raise NotImplementedError

    # ------------------------------------------------------------------ stepping
    def step_async(self, actions: np.ndarray) -> None:
        for w, block in enumerate(self.blocks):
            self.step_block_async(w, actions[block.start : block.stop])

    def step_wait(self):
        results = self._from_every_worker(self.step_block_wait)
        obs, rews, dones, infos = zip(*results, strict=True)
        return (
            np.concatenate(obs),
            np.concatenate(rews),
            np.concatenate(dones),
            tuple(i for block_infos in infos for i in block_infos),
        )

    def step_block_async(self, worker: int, actions: np.ndarray) -> None:
        """Send one step's actions to worker ``worker`` only (its block of environments,
        ``blocks[worker]``, in order); the other workers are not touched. Collect the result with
        :meth:`step_block_wait` (or wait for any worker with :meth:`ready_blocks`)."""
        if self._block_pending[worker]:
            raise RuntimeError(f"worker {worker} is still stepping; call step_block_wait first")
        self._send(worker, "step", np.asarray(actions))
        self._block_pending[worker] = True

    def step_block_wait(self, worker: int):
        """``(obs, rewards, dones, infos)`` of worker ``worker``'s block, as :meth:`step_wait`
        returns them for all environments (auto-reset, ``terminal_observation`` in the info)."""
        try:
            results = _worker_failed(self._recv(worker))
        finally:
            self._block_pending[worker] = False
        obs, rews, dones, infos, reset_infos = results
        block = self.blocks[worker]
        self.reset_infos[block.start : block.stop] = reset_infos
        return obs, rews, dones, tuple(infos)

    # ------------------------------------------------------------------ whole rollouts
    def rollout(self, policy, steps: int, obs0: np.ndarray, eps, mats) -> dict[str, Any]:
        """Every worker plays its block's next ``steps`` steps with a copy of ``policy`` (the
        learner's, as it is now; the same numbers as the learner would compute), all workers at
        once, from the observations ``obs0`` (one per environment), with the rollout's noise:
        ``eps`` (``(steps, n_envs, action_dim)``) or, with gSDE, the per-environment exploration
        matrices ``mats``. One round trip per worker and rollout. Returns the rollout's ``obs``
        (``steps + 1`` rows), ``actions`` (unclipped), ``clipped``, ``values``, ``log_probs``,
        ``rewards``, ``dones``, ``infos`` (``[step][env]``) and ``restarted`` (per environment:
        its worker was lost and started again, and its block played the rollout afresh from a
        reset; only on Ray)."""
        import cloudpickle

        if getattr(self, "_spec_of", None) is not policy:
            spec = (type(policy), policy._get_constructor_parameters())
            self._spec = cloudpickle.dumps(spec)
            self._spec_key = f"{id(self)}-{id(policy)}-{len(self._spec)}"
            self._spec_of = policy
        state = {k: v.detach().cpu() for k, v in policy.state_dict().items()}
        for w in range(len(self.blocks)):
            self._send(w, "rollout", self._rollout_payload(w, state, steps, obs0, eps, mats))
        parts = self._from_every_worker(lambda w: _worker_failed(self._recv(w)))
        out: dict[str, Any] = {}
        for key in ("obs", "actions", "values", "log_probs", "rewards", "dones"):
            out[key] = np.concatenate([part[key] for part in parts], axis=1)
        out["clipped"] = np.clip(out["actions"], self.action_space.low, self.action_space.high)
        out["infos"] = [[info for part in parts for info in part["infos"][t]] for t in range(steps)]
        out["restarted"] = np.concatenate(
            [
                np.full(len(b), part.get("restarted", False))
                for b, part in zip(self.blocks, parts, strict=True)
            ]
        )
        self.reset_infos = [info for part in parts for info in part["reset_infos"]]
        return out

    def _rollout_payload(self, w: int, state, steps: int, obs0, eps, mats) -> tuple:
        b = self.blocks[w]
        noise = None if eps is None else eps[:, b.start : b.stop].cpu()
        block_mats = None if mats is None else mats[b.start : b.stop].detach().cpu()
        return self._spec_key, self._spec, state, steps, obs0[b.start : b.stop], noise, block_mats

    def reset(self):
        for w, block in enumerate(self.blocks):
            self._send(w, "reset", [(self._seeds[i], self._options[i]) for i in block])
        answers = self._from_every_worker(lambda w: _worker_failed(self._recv(w)))
        results = [r for answer in answers for r in answer]
        obs, reset_infos = zip(*results, strict=True)
        self.reset_infos = list(reset_infos)
        self._reset_seeds()
        self._reset_options()
        return np.stack(obs)

    def _from_every_worker(self, receive: Callable[[int], Any]) -> list[Any]:
        """``receive(w)`` for every worker; a worker's error is raised only after every answer
        is read (so that no answer is left waiting to be mistaken for the next one)."""
        answers, error = [], None
        for w in range(len(self.blocks)):
            try:
                answers.append(receive(w))
            except RuntimeError as e:
                error = error or e
        if error is not None:
            raise error
        return answers

    # ------------------------------------------------------------------ one environment
    def _targets(self, indices) -> list[tuple[int, int]]:
        return [self._where[i] for i in self._get_indices(indices)]

    def _ask(self, cmd: str, targets: list[tuple[int, int]], payload) -> list[Any]:
        out = []
        for w, k in targets:
            self._send(w, cmd, payload(k))
            out.append(_worker_failed(self._recv(w)))
        return out

    def get_images(self) -> Sequence[np.ndarray | None]:
        return self._ask("render", self._targets(None), lambda k: k)

    def has_attr(self, attr_name: str) -> bool:
        return bool(self._ask("has_attr", [(0, 0)], lambda k: attr_name)[0])

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return self._ask("get_attr", self._targets(indices), lambda k: (k, attr_name))

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        self._ask("set_attr", self._targets(indices), lambda k: (k, attr_name, value))

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        return self._ask(
            "env_method",
            self._targets(indices),
            lambda k: (k, method_name, method_args, method_kwargs),
        )

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return self._ask("is_wrapped", self._targets(indices), lambda k: (k, wrapper_class))


class BatchedSubprocVecEnv(BlockVecEnv):
    """Like SB3's ``SubprocVecEnv``, but each worker process steps a block of environments;
    environment ``i`` lives in the worker whose block contains ``i``."""

    def __init__(
        self,
        env_fns: list[Callable[[], Any]],
        n_workers: int,
        start_method: str | None = None,
        block_class: type[EnvBlock] | None = None,
    ) -> None:
        from stable_baselines3.common.vec_env.base_vec_env import CloudpickleWrapper

        self.closed = False
        block_class = block_class or EnvBlock
        seats = block_class.seats_of(env_fns)
        n_envs = len(env_fns) * seats
        self._start_blocks(n_envs, n_workers, seats)
        ctx = mp.get_context(worker_start_method(start_method))
        self.remotes, work_remotes = zip(*[ctx.Pipe() for _ in self.blocks], strict=True)
        self.processes = []
        for work_remote, remote, block in zip(work_remotes, self.remotes, self.blocks, strict=True):
            fns = CloudpickleWrapper(env_fns[block.start // seats : block.stop // seats])
            process = ctx.Process(
                target=_batched_worker,
                args=(work_remote, remote, fns, block.start, block_class),
                daemon=True,
            )
            process.start()
            self.processes.append(process)
            work_remote.close()
        try:  # every worker answers: a failed start is raised here, naming the environment
            for w in range(len(self.blocks)):
                self._send(w, "get_spaces", None)
            spaces = self._from_every_worker(lambda w: _worker_failed(self._recv(w)))
        except BaseException:
            self._abort()
            raise
        observation_space, action_space = spaces[0]
        super().__init__(n_envs, observation_space, action_space)

    def _send(self, worker: int, cmd: str, data: Any) -> None:
        self.remotes[worker].send((cmd, data))

    def _recv(self, worker: int) -> Any:
        try:
            return self.remotes[worker].recv()
        except (EOFError, ConnectionError):
            block = self.blocks[worker]
            if not hasattr(self, "observation_space"):  # still starting
                return _WorkerError(
                    "an environment worker process died while starting (its traceback is "
                    "printed above; with the spawn/forkserver start method the environment "
                    "factory must be importable from a module, not defined in a script read "
                    "from stdin)"
                )
            return _WorkerError(
                f"environment worker {worker} (environments {block.start}–{block.stop - 1}) died"
            )

    def ready_blocks(self, workers: Sequence[int]) -> list[int]:
        conns = {self.remotes[w]: w for w in workers}
        return sorted(conns[c] for c in mp_connection.wait(list(conns)))

    def close(self) -> None:
        if self.closed:
            return
        for remote, pending in zip(self.remotes, self._block_pending, strict=True):
            if pending:
                with contextlib.suppress(EOFError, OSError):
                    remote.recv()
        for remote in self.remotes:
            remote.send(("close", None))
        for process in self.processes:
            process.join()
        for remote in self.remotes:
            remote.close()
        self.closed = True

    def _abort(self) -> None:
        """Stop every worker at once (construction failed)."""
        for remote in self.remotes:
            with contextlib.suppress(OSError):
                remote.send(("close", None))
        for process in self.processes:
            process.join(timeout=5)
            if process.is_alive():
                process.terminate()
                process.join()
        for remote in self.remotes:
            remote.close()
        self.closed = True


class InProcessBlockVecEnv(BlockVecEnv):
    """A :class:`BlockVecEnv` whose one block (an :class:`EnvBlock`, or ``block_class``) lives
    in this process: no worker, the same numbers."""

    def __init__(
        self, env_fns: list[Callable[[], Any]], block_class: type[EnvBlock] | None = None
    ) -> None:
        block_class = block_class or EnvBlock
        seats = block_class.seats_of(env_fns)
        n_envs = len(env_fns) * seats
        self._start_blocks(n_envs, 1, seats)
        self.block = block_class(env_fns, 0)
        self._answer: Any = None
        self.closed = False
        try:
            spaces = _worker_failed(self.block.handle("get_spaces", None))
        except BaseException:
            self.close()
            raise
        super().__init__(n_envs, *spaces)

    def _send(self, worker: int, cmd: str, data: Any) -> None:
        self._answer = self.block.handle(cmd, data)

    def _recv(self, worker: int) -> Any:
        answer, self._answer = self._answer, None
        return answer

    def ready_blocks(self, workers: Sequence[int]) -> list[int]:
        return sorted(workers)

    def close(self) -> None:
        if not self.closed:
            self.block.close()
            self.closed = True


class _Monitored:
    """Picklable ``Monitor(factory())``."""

    def __init__(self, factory: Callable[[], gym.Env]) -> None:
        self.factory = factory

    def __call__(self) -> gym.Env:
        from stable_baselines3.common.monitor import Monitor

        return Monitor(self.factory())

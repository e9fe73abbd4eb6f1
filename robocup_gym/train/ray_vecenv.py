"""Environment workers as Ray actors: training beyond one machine.

:class:`RayVecEnv` is the vector environment of ``robocup-gym train --ray``: each Ray actor
hosts a block of environments (:class:`~robocup_gym.train.vecenv.EnvBlock`, exactly what a local
worker process hosts). :class:`~robocup_gym.train.pipelined.PipelinedPPO` has every actor play
its block's whole rollout with a copy of the policy (its weights and the rollout's noise sent
once per rollout): one round trip per actor and rollout instead of one per step, which is what
lets actors on other machines keep up, and the same numbers as local workers (a run learns the
same policy bit for bit). Updates overlap the next rollout as they do locally. The learner stays
in the process that runs the command; :meth:`RayVecEnv.step` still works step by step (SB3's
own loop, evaluation), one round trip per step.

Where the actors run: ``address=None`` starts an embedded Ray on this machine with one CPU per
core (and ends it on :meth:`RayVecEnv.close`); ``address="auto"`` or ``"HOST:PORT"`` joins a
running cluster (``ray start --head`` on one machine, ``ray start --address HOST:PORT`` on the
others), whose nodes must have the package installed. Each actor asks Ray for one CPU.

A lost actor or node does not hang a run: the block's environments start again in a new actor on
whatever resources remain (Ray places it). A rollout it was playing is played again by the new
actor from a reset (``restarted`` marks those environments, whose episodes then start afresh); a
step it was taking comes back as the end of an episode for each of its environments (``dones``
set, ``TimeLimit.truncated``, the last observation the learner saw as ``terminal_observation``,
reward 0, ``info["worker_restarted"]``). When no new actor can start within
``start_timeout_s`` (no resources left), :class:`WorkersLostError` says so, and the trainer saves
the model and stops.
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from robocup_gym.train.vecenv import (
    BlockVecEnv,
    EnvBlock,
    _worker_failed,
    _WorkerError,
    resolve_n_workers,
)

__all__ = ["RAY_MISSING", "RayVecEnv", "WorkersLostError", "import_ray"]

RAY_MISSING = (
    "training on Ray needs the ray package: pip install 'robocup-gym[ray]' (or pip install ray)"
)


class WorkersLostError(RuntimeError):
    """Environment workers were lost and none could be started again."""


def import_ray():
    """The ``ray`` module, or an ``ImportError`` that says how to install it."""
    try:
        import ray
    except ImportError as e:
        raise ImportError(RAY_MISSING) from e
    return ray


CLUSTER_PROBE_S = 5.0
"""Seconds a ``HOST:PORT`` cluster address has to accept a connection before a run is refused
(Ray itself retries an address where nothing listens for minutes)."""


def check_cluster_address(address: str, timeout: float = CLUSTER_PROBE_S) -> None:
    """Refuse at once a ``HOST:PORT`` Ray cluster address where nothing accepts a connection
    (``"auto"`` and other forms are left to Ray).

    Raises:
        ConnectionError: naming the address, what the connection got, and how to start a
            cluster.
    """
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except OSError as e:
        raise ConnectionError(
            f"could not join the Ray cluster at {address!r}: nothing answers there ({e}); "
            "start it with `ray start --head`, or leave out --ray-address for Ray on this machine"
        ) from None


class _BlockActor:
    """The body of a Ray actor: one :class:`EnvBlock`."""

    def __init__(
        self,
        env_fns: list[Callable[[], gym.Env]],
        first_index: int,
        block_class: type[EnvBlock] = EnvBlock,
    ) -> None:
        self.block = block_class(env_fns, first_index)

    def handle(self, cmd: str, data: Any) -> Any:
        return self.block.handle(cmd, data)

    def node(self) -> str:
        import ray

        return ray.get_runtime_context().get_node_id()

    def close(self) -> None:
        self.block.close()


FIRST_START_S = 60.0
"""Least time a run's first actors may take to start: their CPUs were counted before they were
asked for, so only a slow start (a busy machine) keeps them, not a lack of resources."""


def _n_actors(n_workers: int, n_blocks: int, cpus: int) -> int:
    """The actors for ``n_workers`` (0: one per CPU of the cluster), at most one per block.

    Raises:
        ValueError: more actors than the ``cpus`` of the Ray cluster, one each.
    """
    n_actors = max(1, min(n_workers if n_workers > 0 else cpus, n_blocks))
    if n_actors > cpus:
        raise ValueError(
            f"{n_actors} Ray actors need {n_actors} CPUs, one each; the Ray cluster has "
            f"{cpus} (use fewer workers, --n-workers {max(1, cpus)}, or add nodes)"
        )
    return n_actors


class RayVecEnv(BlockVecEnv):
    """``n_envs`` environments in ``n_workers`` Ray actors (module docstring).

    Each actor hosts one block of environments (``blocks[w]`` on ``actors[w]``). Stepped step
    by step (:meth:`step_block_async`, as a local worker), every step is a round trip to the
    actor; :meth:`rollout` has each actor play a whole rollout with a copy of the policy
    instead, one round trip per rollout (what
    :class:`~robocup_gym.train.pipelined.PipelinedPPO` uses).

    Args:
        env_fns: One constructor per environment (picklable; shipped to the actors).
        n_workers: Actors (0 = one per CPU Ray reports, at most one per environment).
        address: ``None``: an embedded Ray on this machine; else the cluster to join.
        start_timeout_s: How long an actor started in place of a lost one may take to start
            before the run gives up (the first ones: at least :data:`FIRST_START_S`).
        block_class: What an actor hosts: :class:`EnvBlock` (one environment per constructor)
            or one that gives several environments per constructor (the players of a team
            game: :class:`~robocup_gym.train.selfplay.SeatBlock`).
    """

    def __init__(
        self,
        env_fns: list[Callable[[], gym.Env]],
        n_workers: int = 0,
        address: str | None = None,
        start_timeout_s: float = 60.0,
        block_class: type[EnvBlock] = EnvBlock,
    ) -> None:
        ray = import_ray()
        self._ray = ray
        self.closed = False
        self.start_timeout_s = float(start_timeout_s)
        self.restarts = 0
        """Actors started again after one was lost."""
        self._owns_ray = False
        here = resolve_n_workers(1 << 30)  # every core of this machine
        if not ray.is_initialized() and not address:  # Ray on this machine: refuse at once
            _n_actors(n_workers, len(env_fns), here)
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {
                "include_dashboard": False,
                "logging_level": "ERROR",
                "log_to_driver": True,
            }
            if address:
                check_cluster_address(address)
                kwargs["address"] = address
            else:
                kwargs["num_cpus"] = here
            try:
                ray.init(**kwargs)
            except ConnectionError as e:
                raise ConnectionError(
                    f"could not join the Ray cluster at {address!r}: {e} (start it with "
                    "`ray start --head`, or leave out --ray-address for Ray on this machine)"
                ) from None
            self._owns_ray = True
        self._env_fns = list(env_fns)
        self._block_class = block_class
        self._seats = block_class.seats_of(self._env_fns)
        self._last_obs: np.ndarray | None = None
        n_envs = len(self._env_fns) * self._seats
        cpus = int(ray.cluster_resources().get("CPU", 0))
        try:
            n_actors = _n_actors(n_workers, len(self._env_fns), cpus)
        except ValueError:
            if self._owns_ray:
                ray.shutdown()
            raise
        self._start_blocks(n_envs, n_actors, self._seats)
        self._actor_class = ray.remote(num_cpus=1, max_restarts=0)(_BlockActor)
        self._pending: list[tuple[str, Any, Any] | None] = [None] * len(self.blocks)
        self._ref_block: dict[Any, int] = {}
        self.actors: list[Any] = []
        try:
            self.actors = [self._new_actor(w, first=True) for w in range(n_actors)]
            for w in range(len(self.blocks)):
                self._send(w, "get_spaces", None)
            spaces = self._from_every_worker(lambda w: _worker_failed(self._recv(w)))
        except BaseException:
            self.close()
            raise
        observation_space, action_space = spaces[0]
        super().__init__(n_envs, observation_space, action_space)

    # ------------------------------------------------------------------ actors
    def _new_actor(self, worker: int, first: bool = False):
        """A new actor hosting block ``worker`` (``blocks[worker]``), once it has started
        (the run's first actors, whose CPUs were counted, get at least
        :data:`FIRST_START_S`)."""
        block = self.blocks[worker]
        fns = self._env_fns[block.start // self._seats : block.stop // self._seats]
        handle = self._actor_class.remote(fns, block.start, self._block_class)
        timeout = max(self.start_timeout_s, FIRST_START_S) if first else self.start_timeout_s
        try:
            self._ray.get(handle.node.remote(), timeout=timeout)
        except self._ray.exceptions.GetTimeoutError:
            self._ray.kill(handle)
            free = self._ray.available_resources().get("CPU", 0)
            why = (
                "the cluster has no free CPU left"
                if free < 1
                else f"{free:g} CPU free, but the worker did not come up (a machine too busy?)"
            )
            raise WorkersLostError(
                f"no Ray worker for environments {block.start}–{block.stop - 1} could start "
                f"within {timeout:g} s: {why}"
            ) from None
        return handle

    def actor_nodes(self) -> list[str]:
        """The Ray node id of each actor (``actors[w]`` hosts block ``blocks[w]``)."""
        return self._ray.get([a.node.remote() for a in self.actors])

    # ------------------------------------------------------------------ BlockVecEnv
    def _send(self, worker: int, cmd: str, data: Any) -> None:
        ref = self.actors[worker].handle.remote(cmd, data)
        self._pending[worker] = (cmd, data, ref)
        self._ref_block[ref] = worker

    def _recv(self, worker: int) -> Any:
        pending = self._pending[worker]
        if pending is None:
            return _WorkerError(f"worker {worker} was asked nothing")
        cmd, data, ref = pending
        self._pending[worker] = None
        self._ref_block.pop(ref, None)
        try:
            answer = self._ray.get(ref)
        except (self._ray.exceptions.RayActorError, self._ray.exceptions.ObjectLostError):
            return self._replace(worker, cmd, data)
        if cmd == "step" and not isinstance(answer, _WorkerError):
            self._remember(worker, answer[0])
        elif cmd == "reset" and not isinstance(answer, _WorkerError):
            self._remember(worker, np.stack([obs for obs, _ in answer]))
        elif cmd == "rollout" and not isinstance(answer, _WorkerError):
            self._remember(worker, answer["obs"][-1])
        return answer

    def ready_blocks(self, workers: Sequence[int]) -> list[int]:
        refs = [self._pending[w][2] for w in workers if self._pending[w] is not None]
        self._ray.wait(refs, num_returns=1)
        ready, _ = self._ray.wait(refs, num_returns=len(refs), timeout=0)
        return sorted(self._ref_block[r] for r in ready)

    def _remember(self, worker: int, obs: np.ndarray) -> None:
        block = self.blocks[worker]
        if self._last_obs is None:
            self._last_obs = np.zeros((self.num_envs, *obs.shape[1:]), dtype=obs.dtype)
        self._last_obs[block.start : block.stop] = obs

    def _replace(self, worker: int, cmd: str, data: Any) -> Any:
        """Block ``worker``'s actor is gone: start the block again in a new actor and answer
        ``cmd`` as well as can be (a lost step ends every episode of the block)."""
        self.restarts += 1
        self.actors[worker] = self._new_actor(worker)
        block = self.blocks[worker]
        if cmd == "rollout":  # played again from a reset
            self._send(worker, "reset", [(None, None)] * len(block))
            fresh = self._recv(worker)
            if isinstance(fresh, _WorkerError):
                return fresh
            obs0 = np.stack([o for o, _ in fresh])
            self._send(worker, cmd, (*data[:4], obs0, *data[5:]))
            answer = self._recv(worker)
            if isinstance(answer, dict):
                answer["restarted"] = True
            return answer
        if cmd != "step":
            self._send(worker, cmd, data)
            return self._recv(worker)
        self._send(worker, "reset", [(None, None)] * len(block))
        answer = self._recv(worker)
        if isinstance(answer, _WorkerError):
            return answer
        obs = np.stack([o for o, _ in answer])
        reset_infos = [info for _, info in answer]
        infos = []
        for i in block:
            info: dict[str, Any] = {"TimeLimit.truncated": True, "worker_restarted": True}
            if self._last_obs is not None:
                info["terminal_observation"] = self._last_obs[i].copy()
            infos.append(info)
        self._remember(worker, obs)
        return obs, np.zeros(len(block)), np.ones(len(block), dtype=bool), infos, reset_infos

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        ray = self._ray
        for actor in self.actors:
            with contextlib.suppress(Exception):  # a lost actor has nothing to close
                ray.get(actor.close.remote(), timeout=30)
            ray.kill(actor)
        if self._owns_ray:
            ray.shutdown()

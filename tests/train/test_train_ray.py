"""Training on Ray: the environment workers as Ray actors step exactly what local workers step,
a run on them learns the same policy bit for bit, a lost node's environments start again on the
remaining nodes and the run goes on, and with no resources left the run saves and stops."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

ray = pytest.importorskip("ray")
pytest.importorskip("stable_baselines3")

from ray.cluster_utils import Cluster  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402

from robocup_gym.train.config import TrainConfig  # noqa: E402
from robocup_gym.train.pipelined import PipelinedPPO  # noqa: E402
from robocup_gym.train.ray_vecenv import RayVecEnv, WorkersLostError  # noqa: E402
from robocup_gym.train.vecenv import make_vec_env  # noqa: E402

TASK = "RobocupGym/VelocityKick-v0"
SMALL_PPO = {"n_steps": 64, "batch_size": 64, "n_epochs": 2}

pytestmark = pytest.mark.timeout(600)


@pytest.fixture(scope="module")
def cluster():
    """A Ray cluster on this machine: a head without CPUs (the learner's side) and four nodes
    of one CPU each; nodes die fast when removed. The tests that take it remove nodes: each
    starts from the nodes still alive (``live_nodes``)."""
    c = Cluster(
        initialize_head=True,
        head_node_args={
            "num_cpus": 0,
            "_system_config": {"health_check_period_ms": 500, "health_check_failure_threshold": 2},
        },
    )
    nodes = [c.add_node(num_cpus=1) for _ in range(4)]
    c.wait_for_nodes()
    ray.init(address=c.address, include_dashboard=False, logging_level="ERROR")
    try:
        yield c, nodes
    finally:
        ray.shutdown()
        c.shutdown()


def live_nodes(nodes) -> list:
    """The nodes of ``nodes`` still alive in the joined cluster."""
    alive = {n["NodeID"] for n in ray.nodes() if n["Alive"]}
    return [n for n in nodes if n.node_id in alive]


def _small_run(timesteps: int, **fields) -> TrainConfig:
    """VelocityKick in 4 environments on 2 workers with :data:`SMALL_PPO`, no evaluations or
    checkpoints; ``fields`` over that."""
    return TrainConfig(
        task="velocity-kick",
        timesteps=timesteps,
        n_envs=4,
        n_workers=2,
        eval_freq=0,
        checkpoint_freq=0,
        checkpoint_every_s=0,
        algo_kwargs=SMALL_PPO,
        **fields,
    )


def _rollout(venv, steps: int, seed: int = 3):
    rng = np.random.default_rng(seed)
    venv.seed(11)
    out = [venv.reset()]
    for _ in range(steps):
        obs, rew, done, _ = venv.step(rng.uniform(-1, 1, (venv.num_envs, *venv.action_space.shape)))
        out += [obs, rew, done]
    return out


def test_ray_address_without_ray_vec_env_is_refused():
    with pytest.raises(ValueError, match="needs vec_env='ray'"):
        TrainConfig(ray_address="auto")
    with pytest.raises(ValueError, match="vec_env must be one of"):
        TrainConfig(vec_env="threads")


def test_a_cluster_address_where_nothing_listens_is_refused_at_once():
    """Ray retries such an address for minutes; the run is refused before Ray is asked."""
    import socket

    from robocup_gym.train.ray_vecenv import check_cluster_address

    with socket.socket() as bound, socket.socket() as listening:
        bound.bind(("127.0.0.1", 0))  # bound, not listening: a connection is refused
        port = bound.getsockname()[1]
        with pytest.raises(ConnectionError, match=rf"Ray cluster at '127.0.0.1:{port}'.*ray start"):
            check_cluster_address(f"127.0.0.1:{port}")
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        check_cluster_address(f"127.0.0.1:{listening.getsockname()[1]}")  # something answers
    check_cluster_address("auto")  # Ray's own forms are Ray's to resolve


def test_train_on_ray_from_the_command_line_and_resume_on_local_workers(tmp_path):
    from .train_helpers import TINY_PPO, invoke

    out = tmp_path / "runs"
    common = ["--n-envs", 4, "--checkpoint-freq", 0, "--eval-freq", 0, "--no-progress"]
    invoke(
        ["train", "velocity-kick", "--ray", "--timesteps", 256, "--out", out, *common, *TINY_PPO]
    )
    (run,) = out.iterdir()
    cfg = TrainConfig.load(run / "config.yaml")
    assert cfg.vec_env == "ray" and cfg.ray_address == ""
    assert not ray.is_initialized()
    invoke(["train", "--resume", run, "--no-ray", "--timesteps", 512, "--no-progress"])
    assert TrainConfig.load(run / "config.yaml").vec_env == "auto"
    steps = [int(r.split(",")[0]) for r in (run / "progress.csv").read_text().splitlines()[1:]]
    assert steps[-1] >= 512


def test_more_actors_than_the_cluster_has_cpus_is_refused_at_once():
    with pytest.raises(ValueError, match=r"64 Ray actors need 64 CPUs, one each; the Ray cluster"):
        make_vec_env(TASK, 64, n_workers=64, kind="ray")
    assert not ray.is_initialized()


# the tests on the module's cluster come last: it is joined until the module ends (the ones that
# remove nodes after the ones that need them all)


def test_ray_actors_step_what_local_workers_step(cluster):
    local = make_vec_env(TASK, 4, seed=5, n_workers=2)
    try:
        expected = _rollout(local, 40)
        local_frame_size = local.get_attr("frame_size", indices=[0])
    finally:
        local.close()
    remote = make_vec_env(TASK, 4, seed=5, n_workers=2, kind="ray")
    try:
        assert isinstance(remote, RayVecEnv) and len(remote.blocks) == 2
        got = _rollout(remote, 40)
        assert remote.get_attr("frame_size") == local_frame_size * 4
        assert remote.env_method("get_wrapper_attr", "league", indices=[3]) == [False]
    finally:
        remote.close()
    assert len(got) == len(expected)
    for a, b in zip(got, expected, strict=True):
        np.testing.assert_array_equal(a, b)


def test_team_games_on_ray_actors_play_what_local_workers_play(cluster):
    """Each actor hosts whole games (the players of a game are consecutive environments)."""
    pytest.importorskip("pettingzoo")
    from robocup_gym.sim.engines.ode import available
    from robocup_gym.train.selfplay import make_team_vec_env

    if not available():
        pytest.skip("the shipped skills run on ODE")
    runs = {}
    for kind in ("subproc", "ray"):
        venv = make_team_vec_env(
            "game-2v2", 3, options={"max_cycles": 60}, seed=2, kind=kind, n_workers=2
        )
        try:
            assert venv.num_envs == 6 and [len(b) for b in venv.blocks] == [4, 2]
            runs[kind] = _rollout(venv, 8)  # past the end of a game: its reset too
        finally:
            venv.close()
    for a, b in zip(runs["ray"], runs["subproc"], strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_run_on_ray_learns_the_same_policy_as_on_local_workers(cluster, tmp_path):
    from stable_baselines3 import PPO

    from robocup_gym.train.trainer import train

    params = {}
    for vec in ("subproc", "ray"):
        result = train(_small_run(512, vec_env=vec), out=tmp_path / vec, progress=False)
        assert result.timesteps == 512
        params[vec] = PPO.load(result.run_dir / "model.zip").policy.state_dict()
    for name, value in params["subproc"].items():
        assert np.array_equal(value.numpy(), params["ray"][name].numpy()), name


class _RemoveNode(BaseCallback):
    """Removes the node of block ``worker``'s actor once ``after`` steps are done."""

    def __init__(self, cluster, nodes, venv: RayVecEnv, worker: int, after: int) -> None:
        super().__init__()
        self.cluster, self.nodes, self.venv = cluster, nodes, venv
        self.worker, self.after = worker, after
        self.removed: str | None = None

    def _on_step(self) -> bool:
        if self.removed is None and self.num_timesteps >= self.after:
            node_id = self.venv.actor_nodes()[self.worker]
            node = next(n for n in self.nodes if n.node_id == node_id)
            self.cluster.remove_node(node)
            self.removed = node_id
        return True


def test_a_lost_node_s_environments_start_again_and_the_run_goes_on(cluster):
    c, nodes = cluster
    nodes = live_nodes(nodes)
    assert len(nodes) == 4  # (no node removed before: it needs two spare nodes)
    venv = make_vec_env(TASK, 4, seed=0, n_workers=2, kind="ray", ray_start_timeout_s=120)
    try:
        before = venv.actor_nodes()
        model = PipelinedPPO("MlpPolicy", venv, seed=0, verbose=0, **SMALL_PPO)
        assert model.can_pipeline(venv) and model.worker_rollouts
        cb = _RemoveNode(c, nodes, venv, worker=1, after=128)
        model.learn(total_timesteps=768, callback=cb)
        assert cb.removed == before[1]
        assert model.num_timesteps == 768
        assert venv.restarts == 1
        after = venv.actor_nodes()
        assert after[0] == before[0]  # the other actor was not touched
        assert after[1] not in (before[0], before[1])  # a spare node took the block

        # a step lost with its node ends the episodes of that block, and they play on
        last = venv.reset()
        c.remove_node(next(n for n in nodes if n.node_id == after[0]))
        obs, rewards, dones, infos = venv.step(np.zeros((4, *venv.action_space.shape)))
        assert venv.restarts == 2
        assert dones.tolist() == [True, True, False, False]
        assert rewards[:2].tolist() == [0.0, 0.0]
        for i in (0, 1):
            assert infos[i]["worker_restarted"] and infos[i]["TimeLimit.truncated"]
            np.testing.assert_array_equal(infos[i]["terminal_observation"], last[i])
        assert "worker_restarted" not in infos[2]
        assert np.isfinite(obs).all()
        assert venv.actor_nodes()[0] not in (before[0], before[1], after[1])
    finally:
        venv.close()
    assert ray.is_initialized()  # a joined cluster is not ours to end


def test_with_no_resources_left_the_run_saves_and_stops(cluster, tmp_path):
    from robocup_gym.train.trainer import train

    c, nodes = cluster
    nodes = live_nodes(nodes)
    for node in nodes[2:]:  # two one-CPU nodes left, two actors: no spare
        c.remove_node(node)
    # the actors are placed only once Ray counts the removed nodes out (else one may be given a
    # dead node's CPU and never start)
    deadline = time.monotonic() + 60
    while ray.cluster_resources().get("CPU", 0) > 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert ray.cluster_resources().get("CPU", 0) == 2
    cfg = _small_run(10_000_000, vec_env="ray", ray_start_timeout_s=5)
    run_dir = tmp_path / "run"
    trained = threading.Event()

    def remove_when_training() -> None:
        while not (run_dir / "progress.csv").exists() and not trained.wait(0.2):
            pass
        c.remove_node(nodes[0])

    remover = threading.Thread(target=remove_when_training, daemon=True)
    remover.start()
    try:
        with pytest.raises(WorkersLostError) as err:
            train(cfg, run_dir=run_dir, progress=False, curve_every=256)
    finally:
        trained.set()
    remover.join()
    message = str(err.value)
    assert "no Ray worker for environments" in message and "could start within 5 s" in message
    assert f"robocup-gym train --resume {run_dir}" in message
    assert (run_dir / "model.zip").exists()

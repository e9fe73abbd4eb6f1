"""The batched subprocess vector env steps exactly like SB3's DummyVecEnv."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from robocup_gym.train.vecenv import BatchedSubprocVecEnv, _split, make_vec_env


def test_split_blocks():
    assert [list(b) for b in _split(5, 2)] == [[0, 1, 2], [3, 4]]
    assert [len(b) for b in _split(16, 3)] == [6, 5, 5]


def test_batched_matches_dummy():
    kw = {"env_kwargs": {"max_episode_steps": 5, "wait_steps": 2}, "seed": 11}
    batched = make_vec_env("RobocupGym/VelocityKick-v0", 3, n_workers=2, **kw)
    dummy = make_vec_env("RobocupGym/VelocityKick-v0", 3, kind="dummy", **kw)
    try:
        assert isinstance(batched, BatchedSubprocVecEnv)
        rng = np.random.default_rng(0)
        np.testing.assert_allclose(batched.reset(), dummy.reset(), atol=1e-6)
        for _ in range(12):  # crosses episode ends (auto-reset)
            a = rng.uniform(-0.3, 0.3, (3, *batched.action_space.shape)).astype(np.float32)
            ob, rb, db, ib = batched.step(a)
            od, rd, dd, idd = dummy.step(a)
            np.testing.assert_allclose(ob, od, atol=1e-6)
            np.testing.assert_allclose(rb, rd, atol=1e-9)
            assert (db == dd).all()
            for x, y in zip(ib, idd, strict=True):
                assert ("terminal_observation" in x) == ("terminal_observation" in y)
        assert batched.get_attr("spec")[2].id == "RobocupGym/VelocityKick-v0"
        assert batched.env_method("get_wrapper_attr", "episode_step", indices=[1]) == [
            dummy.env_method("get_wrapper_attr", "episode_step", indices=[1])[0]
        ]
    finally:
        batched.close()
        dummy.close()


def _broken_factory():
    raise ValueError("no such robot type 9")


def test_worker_errors_name_the_environment():
    from robocup_gym.train.vecenv import _Monitored, env_factories

    fns = [_Monitored(f) for f in env_factories("RobocupGym/VelocityKick-v0", 3, seed=0)]
    with pytest.raises(RuntimeError, match=r"creating environment 2 failed: ValueError: no such"):
        BatchedSubprocVecEnv([fns[0], fns[1], _broken_factory], n_workers=2)

    venv = make_vec_env("RobocupGym/VelocityKick-v0", 3, n_workers=2, seed=0)
    try:
        venv.reset()
        bad = np.zeros((3, *venv.action_space.shape), dtype=np.float32)
        bad[2, 0] = np.nan
        with pytest.raises(RuntimeError, match=r"step failed in environment 2: .*NaN|nan"):
            venv.step(bad)
        bad[:] = 0.0
        bad[0, 1] = np.inf  # first worker fails: the second one's answer must not be left over
        with pytest.raises(RuntimeError, match=r"step failed in environment 0"):
            venv.step(bad)
        venv.step_block_async(0, bad[:1])  # block 0 holds environments 0 and 1
        with pytest.raises(RuntimeError, match=r"step: 1 entries for 2 environments"):
            venv.step_block_wait(0)
        # the workers survive: the next step works
        obs, *_ = venv.step(np.zeros_like(bad))
        assert obs.shape[0] == 3
    finally:
        venv.close()


def test_the_assist_is_shared_out_over_the_environments():
    """``TrainConfig.assist_steps`` count all environments together: each gets its part, and
    a resumed run's steps done continue the schedule; without an assist nothing is wrapped."""
    from robocup_gym.envs.assist import TorsoAssist
    from robocup_gym.train.vecenv import env_factories

    fns = env_factories(
        "RobocupGym/GetUp-v0",
        4,
        backend="mujoco",
        seed=0,
        assist={"share": 0.6, "decay_steps": 4000, "start_step": 1000, "max_tilt_deg": 60.0},
    )
    expected = {"share": 0.6, "decay_steps": 1000, "start_step": 250, "max_tilt_deg": 60.0}
    assert all(f.assist == expected for f in fns)
    env = fns[0]()
    try:
        assert isinstance(env, TorsoAssist)
        assert (env.share, env.decay_steps, env.steps, env.max_tilt_deg) == (0.6, 1000, 250, 60)
    finally:
        env.close()
    plain = env_factories("RobocupGym/GetUp-v0", 2, backend="mujoco", assist=None)
    env = plain[0]()
    try:
        assert not isinstance(env, TorsoAssist)
    finally:
        env.close()


def test_workers_fork_from_a_server_that_imported_the_environments_once():
    """With the fork server, the workers are forked from a server that imports torch, SB3 and
    the tasks when it starts (each worker would spend ~1.5 s importing them)."""
    import multiprocessing as mp
    import multiprocessing.forkserver as fs

    from robocup_gym.train.vecenv import WORKER_PRELOAD, worker_start_method

    if "forkserver" not in mp.get_all_start_methods():
        assert worker_start_method() == "spawn"
        return
    assert worker_start_method() == "forkserver"
    assert fs._forkserver._preload_modules == list(WORKER_PRELOAD)
    assert worker_start_method("spawn") == "spawn"
    for module in WORKER_PRELOAD[1:]:  # each one importable (the server skips those that fail)
        __import__(module)


def test_robot_types_are_taken_in_turn_by_the_environments():
    """``TrainConfig.robot_types``: environment ``i`` is of type ``robot_types[i % n]``, each
    built as that type; without it every environment is of ``env_kwargs``' type."""
    from robocup_gym.train.vecenv import env_factories

    fns = env_factories(
        "RobocupGym/Walk-v0",
        5,
        env_kwargs={"robot_type": 2, "max_episode_steps": 7},
        robot_types=[1, 3],
    )
    assert [f.env_kwargs["robot_type"] for f in fns] == [1, 3, 1, 3, 1]
    assert all(f.env_kwargs["max_episode_steps"] == 7 for f in fns)
    env = fns[1]()
    try:
        assert env.unwrapped.config.robot_type == 3
        assert env.unwrapped.backend.robot_type == 3
    finally:
        env.close()
    plain = env_factories("RobocupGym/Walk-v0", 2, env_kwargs={"robot_type": 2})
    assert [f.env_kwargs["robot_type"] for f in plain] == [2, 2]

"""Episodes: wait steps, the kick rewards, termination, truncation, seeding, reset options."""

from __future__ import annotations

import math

import numpy as np
import pytest
from env_helpers import raw, raw_env_options

from robocup_gym.envs import BaseEnv, SimpleKick, VelocityKick

CYCLE = 0.02
# A ball rolling freely along +x, far from the robot (which stands at (-1, 0) facing +x).
ROLL = {"ball_pos": (1.0, 2.0), "ball_vel": (2.0, 0.0, 0.0)}


def _rolled(distance, speed, cycles):
    # A ball placed sliding without spin slows to rolling speed (5/7 of it for a solid sphere;
    # friction and drag details are the world's business): between half and all of v·t.
    return 0.5 * speed * cycles * CYCLE < distance <= 1.001 * speed * cycles * CYCLE


def _zero(env):
    return np.zeros(env.action_space.shape, dtype=np.float32)


def test_wait_steps_run_after_the_episode_and_before_the_reward(make_env):
    env = make_env(
        observations=("time", "ball_rel"),
        max_episode_steps=3,
        wait_steps=25,
        terminate_on_fall=False,
        **raw_env_options(),
    )
    obs, _ = env.reset(seed=0, options=ROLL)
    xs = []
    for k in range(3):
        obs, _reward, terminated, truncated, info = env.step(_zero(env))
        xs.append(raw(env, obs, "ball_rel")[0])
        assert info["cycles"] == (1 if k < 2 else 26)
    assert truncated and not terminated
    # the returned observation is from before the wait …
    assert raw(env, obs, "time")[0] == 3
    per_cycle = xs[2] - xs[1]
    assert _rolled(per_cycle, 2.0, 1)
    # … the info (and the reward) from after it: 28 cycles of rolling
    after = info["ball_displacement"][0]
    assert _rolled(after, 2.0, 28)
    assert after > (xs[2] - xs[0]) + 0.6 * 25 * per_cycle


def test_wait_steps_zero_ends_immediately(make_env):
    env = make_env(max_episode_steps=2, wait_steps=0, terminate_on_fall=False)
    env.reset(seed=0, options=ROLL)
    env.step(_zero(env))
    *_, truncated, info = env.step(_zero(env))
    assert truncated and info["cycles"] == 1
    assert _rolled(info["ball_displacement"][0], 2.0, 2)


def test_simple_kick_pays_the_ball_distance_once_at_the_end(make_env):
    env = make_env(SimpleKick, max_episode_steps=4, wait_steps=30, terminate_on_fall=False)
    assert SimpleKick.default_config().wait_steps == 200
    env.reset(seed=0, options={"ball_pos": (1.0, 2.0), "ball_vel": (1.2, -0.9, 0.0)})
    rewards = []
    for _ in range(4):
        _, reward, _terminated, truncated, info = env.step(_zero(env))
        rewards.append(reward)
    assert truncated
    assert rewards[:3] == [0.0, 0.0, 0.0]
    assert rewards[3] == pytest.approx(info["ball_distance"], rel=1e-9)
    assert rewards[3] == pytest.approx(np.linalg.norm(env.ball_pos - (1.0, 2.0, 0.041)), rel=1e-6)
    # 1.5 m/s for 34 cycles (4 steps + 30 wait cycles), not just the 4 steps
    assert _rolled(rewards[3], 1.5, 34)
    assert rewards[3] > 0.5 * 1.5 * 20 * CYCLE


def test_velocity_kick_formula_on_a_placed_ball(make_env):
    env = make_env(VelocityKick, max_episode_steps=1, wait_steps=0, terminate_on_fall=False)
    assert VelocityKick.default_config().wait_steps == 20
    start = (1.0, 2.0, 0.2)  # in the air: x–z speed includes the fall
    vel = (3.0, 0.8, 1.0)
    env.reset(seed=0, options={"ball_pos": start, "ball_vel": vel})
    _, reward, _, truncated, info = env.step(_zero(env))
    assert truncated
    p, v = info["ball_pos"], info["ball_vel"]
    expected = (p[0] - start[0]) + math.hypot(v[0], v[2]) - abs(p[1] - start[1])
    assert reward == pytest.approx(expected, rel=1e-9)
    # physically: one 20 ms cycle of flight (gravity; a little drag)
    assert p[0] - start[0] == pytest.approx(3.0 * CYCLE, rel=0.05)
    assert abs(p[1] - start[1]) == pytest.approx(0.8 * CYCLE, rel=0.05)
    assert reward == pytest.approx(0.06 + math.hypot(3.0, 1.0 - 9.81 * CYCLE) - 0.016, rel=0.03)


def test_velocity_kick_coefficients_and_options(make_env):
    start, vel = (1.0, 2.0, 0.041), (2.5, -1.5, 0.0)
    results = {}
    for key, opts in {
        "plain": {},
        "weights": {"displacement_weight": 2.0, "speed_weight": 0.5, "lateral_weight": 3.0},
        "yvel": {"penalise_y_velocity": True},
        "square": {"penalise_y_velocity": True, "square_lateral_penalty": True},
        "field": {"lateral_reference": "field"},
    }.items():
        env = make_env(
            VelocityKick, max_episode_steps=1, wait_steps=0, terminate_on_fall=False, **opts
        )
        env.reset(seed=0, options={"ball_pos": start, "ball_vel": vel})
        _, reward, *_, info = env.step(_zero(env))
        results[key] = (reward, info["ball_pos"], info["ball_vel"])
    for key, (reward, p, v) in results.items():
        a, b, c = (2.0, 0.5, 3.0) if key == "weights" else (1.0, 1.0, 1.0)
        y_ref = 0.0 if key == "field" else start[1]
        lateral = abs(p[1] - y_ref) + (abs(v[1]) if key in ("yvel", "square") else 0.0)
        if key == "square":
            lateral = lateral**2
        expected = a * (p[0] - start[0]) + b * math.hypot(v[0], v[2]) - c * lateral
        assert reward == pytest.approx(expected, rel=1e-9), key
    assert results["yvel"][0] < results["plain"][0] - 1.0  # |v_y| ≈ 1.5 m/s penalised
    assert results["field"][0] < results["plain"][0] - 1.5  # |y| ≈ 2 m from the field axis


def test_velocity_kick_fall_penalty(make_env):
    start, vel = (1.0, 2.0, 0.041), (2.5, 0.0, 0.0)
    rewards = {}
    for penalty in (0.0, 1.5):
        for fallen in (False, True):
            # fall_height 0.5 m: the standing robot (torso 0.384 m) counts as down
            env = make_env(
                VelocityKick,
                max_episode_steps=1,
                wait_steps=0,
                fall_penalty=penalty,
                fall_height=0.5 if fallen else 0.2,
            )
            env.reset(seed=0, options={"ball_pos": start, "ball_vel": vel})
            _, reward, terminated, _, info = env.step(_zero(env))
            assert info["fallen"] == fallen == terminated
            rewards[penalty, fallen] = reward
    assert rewards[0.0, True] == pytest.approx(rewards[0.0, False], rel=1e-9)  # the paper's
    assert rewards[1.5, False] == pytest.approx(rewards[0.0, False], rel=1e-9)
    assert rewards[1.5, True] == pytest.approx(rewards[0.0, True] - 1.5, rel=1e-9)
    with pytest.raises(ValueError, match="fall_penalty"):
        make_env(VelocityKick, fall_penalty=float("nan"))


def test_rewards_are_zero_before_the_end(make_env):
    env = make_env(VelocityKick, max_episode_steps=5, wait_steps=3, terminate_on_fall=False)
    env.reset(seed=0, options=ROLL)
    rewards = [env.step(_zero(env))[1] for _ in range(5)]
    assert rewards[:4] == [0.0] * 4 and rewards[4] > 0.5


def test_fall_terminates(make_env):
    env = make_env(fall_height=0.5)  # standing torso (0.384 m) counts as fallen
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(_zero(env))
    assert terminated and not truncated and info["fallen"]
    env = make_env(fall_height=0.5, terminate_on_fall=False, max_episode_steps=2)
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(_zero(env))
    assert not terminated and not truncated and info["fallen"]
    env = make_env(fall_up_z=1.0)  # the slightest tilt counts as fallen
    env.reset(seed=0)
    assert env.step(_zero(env))[2]


def test_truncation_at_max_episode_steps(make_env):
    env = make_env(max_episode_steps=3, terminate_on_fall=False)
    env.reset(seed=0)
    flags = [env.step(_zero(env))[3] for _ in range(3)]
    assert flags == [False, False, True]
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(_zero(env))
    env.reset()
    assert env.step(_zero(env))[3] is False


def test_step_before_reset_is_an_error(make_env):
    env = make_env()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(_zero(env))


def _rollout(env, seed, n=12):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(123)
    out = [obs]
    for _ in range(n):
        obs, reward, terminated, truncated, info = env.step(
            rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        )
        out.append(np.append(obs, [reward, info["ball_distance"]]))
        if terminated or truncated:
            break
    return out


def test_seeded_resets_are_reproducible(make_env):
    noisy = dict(
        observation_noise_std=0.01,
        action_noise_std=0.1,
        ball_spawn_noise=0.03,
        joint_start_noise_deg=2.0,
        max_episode_steps=12,
        wait_steps=5,
    )
    a, b = make_env(VelocityKick, **noisy), make_env(VelocityKick, **noisy)
    _rollout(a, seed=99)  # a used env must not remember its past
    ra, rb = _rollout(a, seed=7), _rollout(b, seed=7)
    assert len(ra) == len(rb)
    for x, y in zip(ra, rb, strict=True):
        np.testing.assert_array_equal(x, y)
    rc = _rollout(b, seed=8)
    assert not np.array_equal(ra[0], rc[0])


def test_spawn_and_start_noise(make_env):
    env = make_env(ball_spawn_noise=0.05, joint_start_noise_deg={"lae1": 3.0})
    spawns, angles = [], []
    for s in range(20):
        env.reset(seed=s)
        spawns.append(env.ball_spawn_pos.copy())
        angles.append(env.joint_angles_deg[2])
    offsets = np.array(spawns)[:, :2] - (-0.8, -0.055)
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=1), 0.05, atol=1e-9)  # on the circle
    assert np.std(angles) == pytest.approx(3.0, rel=0.5)
    np.testing.assert_allclose(env.joint_angles_deg[3:], env.joint_angles_deg[3:] * 0, atol=1e-6)


def test_reset_options_and_errors(make_env):
    env = make_env()
    env.reset(options={"robot_pos": (3.0, 1.0), "ball_pos": (3.5, 1.0, 0.3)})
    np.testing.assert_allclose(env.torso_pos[:2], (3.0, 1.0), atol=1e-9)
    np.testing.assert_allclose(env.ball_spawn_pos, (3.5, 1.0, 0.3))
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(options={"ball_position": (0, 0)})
    with pytest.raises(ValueError, match="joint_angles_deg must have shape"):
        env.reset(options={"joint_angles_deg": [1.0, 2.0]})


def test_info_has_what_users_log(make_env):
    env = make_env(VelocityKick)
    _, info = env.reset(seed=0)
    for key in (
        "step",
        "fallen",
        "diverged",
        "ball_pos",
        "ball_vel",
        "ball_displacement",
        "ball_distance",
        "ball_speed",
        "torso_pos",
    ):
        assert key in info
    _, _, _, _, info = env.step(_zero(env))
    assert info["step"] == 1 and info["cycles"] == 1


def test_custom_task_is_one_small_subclass(make_env):
    class KickLeft(BaseEnv):
        def _get_reward(self, action):
            if not self.has_completed:
                return 0.0
            return float(self.ball_pos[1] - self.ball_spawn_pos[1])

    env = make_env(KickLeft, max_episode_steps=2, wait_steps=5, terminate_on_fall=False)
    env.reset(seed=0, options={"ball_pos": (1.0, 2.0), "ball_vel": (0.0, 1.0, 0.0)})
    env.step(_zero(env))
    reward = env.step(_zero(env))[1]
    assert _rolled(reward, 1.0, 7)


def test_info_fallen_describes_the_world_after_the_wait_cycles():
    """A robot that falls during the wait cycles is down in ``info`` (and for the fall
    penalty), as the video and the reward's ball state show it."""
    from robocup_gym.envs.base_env import BaseEnv

    leaning = {"rle3": 60.0, "lle3": 60.0}  # hips bent: the robot topples over in ~1 s
    results = {}
    for wait in (0, 100):
        env = BaseEnv(
            max_episode_steps=1, wait_steps=wait, joint_start_deg=leaning, terminate_on_fall=False
        )
        env.reset(seed=0)
        info = env.step(np.zeros(env.action_space.shape))[4]
        results[wait] = (info["fallen"], float(info["torso_pos"][2]))
        env.close()
    assert results[0][0] is False and results[0][1] > 0.25  # still up when the episode ends
    assert results[100][0] is True and results[100][1] < 0.15  # down after the wait

"""The RobocupGym paper's code runs unchanged on the compatibility aliases."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.envs import SimpleKick, VelocityKick


def _zero(env):
    return np.zeros(env.action_space.shape, dtype=np.float32)


# The paper's README listing, verbatim (apart from the class name).
from robocup_gym.rl.envs.base_env import BaseEnv  # noqa: E402


class PaperSimpleKick(BaseEnv):
    def _get_reward(self, action: np.ndarray) -> float:
        if self.has_completed:
            CURRENT_BALL_POS = np.array(self.python_agent_conn.player.real_ball_pos)
            start_ball_pos = np.array(self.env_config.ball_start_pos)
            return np.linalg.norm(CURRENT_BALL_POS - start_ball_pos)
        return 0


def test_paper_base_env_subclass_gets_the_same_reward_as_simple_kick():
    roll = {"ball_pos": (-0.8, -0.055), "ball_vel": (0.0, 0.0, 0.0)}
    paper = PaperSimpleKick(None, 1, wait_steps=10, max_episode_steps=6)
    ours = SimpleKick(wait_steps=10, max_episode_steps=6)
    assert paper.wait_steps_after_done == 10
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (6, 20)).astype(np.float32)
    results = []
    for env in (paper, ours):
        env.reset(seed=5, options=roll)
        rewards = []
        for a in actions:
            _, reward, terminated, truncated, _ = env.step(a)
            rewards.append(reward)
            if terminated or truncated:
                break
        results.append(rewards)
    assert results[0] == pytest.approx(results[1], abs=1e-9)
    assert results[0][-1] > 0 or paper.fallen  # a real number, paid at the end


def test_paper_player_attributes():
    env = PaperSimpleKick(agent_type=0, joint_start_deg={"rlj3": 20.0, "laj1": -40.0})
    env.reset(seed=0, options={"ball_vel": (1.0, 0.0, 0.0)})
    player = env.python_agent_conn.player
    np.testing.assert_allclose(player.real_ball_pos, (-0.8, -0.055, 0.041), atol=1e-6)
    np.testing.assert_allclose(player.ball_velocity, (1.0, 0.0, 0.0), atol=1e-9)
    assert player.rightHipPitch == pytest.approx(20.0)
    assert player.leftShoulderPitch == pytest.approx(-40.0)
    assert player.is_fallen is False
    assert player.my_orientation == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(player.acc, (0.0, 0.0, 9.81), atol=1e-6)
    assert player.lf.shape == (2, 3)
    assert env.latest_ball_pos == pytest.approx((-0.8, -0.055, 0.041))
    assert env.step_counter == 0
    env.step(_zero(env))
    assert env.step_counter == 1 and player.steps == 1
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        _ = player.nonsense


def test_env_simple_kick_default_and_ppo_learns():
    from stable_baselines3 import PPO

    from robocup_gym.envs.tasks.env_simple_kick import EnvSimpleKick

    env = EnvSimpleKick()
    assert isinstance(env, SimpleKick) and env.config.wait_steps == 200
    model = PPO("MlpPolicy", env, n_steps=48, batch_size=24, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=48)
    action, _ = model.predict(env.reset(seed=0)[0], deterministic=True)
    assert env.action_space.contains(action)
    env.close()


def test_paper_velocity_kick_arguments():
    from robocup_gym.rl.envs.tasks.benchmark.simple_kick import EnvSimpleKick
    from robocup_gym.rl.envs.tasks.benchmark.velocity_kick import KickVelocityReward
    from robocup_gym.rl.envs.tasks.env_simple_kick import EnvSimpleKick as Alias

    assert EnvSimpleKick is Alias
    env = KickVelocityReward(
        None,
        0,
        wait_steps=0,
        coefficients=[2.0, 0.5, 3.0],
        square_y=True,
        penalise_y_vel_too=True,
        div_reward_by=2.0,
        max_episode_steps=1,
    )
    assert isinstance(env, VelocityKick)
    c = env.config
    assert (c.displacement_weight, c.speed_weight, c.lateral_weight) == (2.0, 0.5, 3.0)
    assert c.square_lateral_penalty and c.penalise_y_velocity and c.wait_steps == 0
    start = (1.0, 2.0, 0.041)
    env.reset(seed=0, options={"ball_pos": start, "ball_vel": (2.0, 0.5, 0.0)})
    _, reward, *_, info = env.step(_zero(env))
    p, v = info["ball_pos"], info["ball_vel"]
    lateral = (abs(p[1] - start[1]) + abs(v[1])) ** 2
    expected = (2.0 * (p[0] - start[0]) + 0.5 * np.hypot(v[0], v[2]) - 3.0 * lateral) / 2.0
    assert reward == pytest.approx(expected, rel=1e-9)
    with pytest.raises(ValueError, match="coefficients"):
        KickVelocityReward(coefficients=[1, 2])


def test_paper_logger_gets_the_ball_at_episode_end():
    logged = []

    class Logger:
        def log(self, d):
            logged.append(d)

    env = PaperSimpleKick(logger=Logger(), max_episode_steps=2)
    env.reset(seed=0)
    env.step(_zero(env))
    assert logged == []
    env.step(_zero(env))
    assert len(logged) == 1 and set(logged[0]["ballpos"]) == {"x", "y", "z"}

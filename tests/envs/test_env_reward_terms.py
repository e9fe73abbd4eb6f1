"""Every task's reward is the sum of its named terms, given in info; the trainer logs each term."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.envs import GetUp, SimpleKick, VelocityKick, Walk
from robocup_gym.train.callbacks import EpisodeStatsCallback

EXPECTED = {
    SimpleKick: {"distance"},
    VelocityKick: {"displacement", "speed", "lateral"},
    Walk: {"tracking_linear", "tracking_turn", "upright", "alive", "fall"},
    GetUp: {"height", "upright", "time", "action_rate", "success"},
}


@pytest.mark.parametrize("cls", list(EXPECTED), ids=lambda c: c.__name__)
def test_the_reward_is_the_sum_of_the_terms_in_info(make_env, cls):
    env = make_env(cls, engine="mujoco", max_episode_steps=6)
    env.reset(seed=0)
    assert "reward_terms" not in env._info()  # nothing paid before the first step
    rng = np.random.default_rng(0)
    seen: set[str] = set()
    done = False
    while not done:
        _, reward, terminated, truncated, info = env.step(
            rng.uniform(-1, 1, env.action_space.shape)
        )
        terms = info.get("reward_terms", {})
        assert reward == pytest.approx(sum(terms.values()), abs=0.0)  # bit-equal: the same sum
        seen |= set(terms)
        done = terminated or truncated
    assert EXPECTED[cls] <= seen


def test_a_fall_is_a_term_of_velocity_kick(make_env):
    env = make_env(VelocityKick, engine="mujoco", fall_penalty=2.0, max_episode_steps=40)
    env.reset(seed=0)
    done, info = False, {}
    while not done:  # full-speed flailing: the robot falls
        *_, terminated, truncated, info = env.step(np.ones(env.action_space.shape))
        done = terminated or truncated
    assert info["fallen"] and info["reward_terms"]["fall"] == -2.0


def test_the_trainer_sums_each_term_over_an_episode():
    cb = EpisodeStatsCallback()
    cb._ep_returns, cb._ep_lengths = np.zeros(2), np.zeros(2, dtype=int)

    def step(terms0, terms1, dones):
        infos = [{"reward_terms": terms0}, {"reward_terms": terms1}]
        cb.locals = {"rewards": np.zeros(2), "dones": np.array(dones), "infos": infos}
        cb._on_step()

    step({"a": 1.0, "b": -0.5}, {"a": 2.0}, [False, False])
    step({"a": 1.0, "b": -0.5}, {"a": 2.0}, [True, False])
    step({"a": 3.0}, {"a": 2.0, "b": 1.0}, [False, True])
    means = cb.reward_term_means()
    assert means == {"a": pytest.approx((2.0 + 6.0) / 2), "b": pytest.approx((-1.0 + 1.0) / 2)}

"""The soccer scenarios on the league's simulator (``robot="T1"``/``"K1"``): RCSSServerMJ's own
game in-process behind the PettingZoo API. Skipped where the optional ``rcsssmj`` is not
installed (CI has it)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rcsssmj", reason="the optional rcsssmj package is not installed")

from pettingzoo.test import parallel_api_test

from robocup_gym.soccer import game_v1, keepaway_v1, penalty_v1
from robocup_gym.soccer.league import LeagueSoccerEnv


def _zero(env) -> dict[str, np.ndarray]:
    return {a: np.zeros(env.action_space(a).shape) for a in env.agents}


@pytest.mark.parametrize(
    ("module", "robot"), [(penalty_v1, "T1"), (game_v1, "K1")], ids=["penalty-T1", "game-K1"]
)
def test_pettingzoo_api(module, robot):
    env = module.parallel_env(robot=robot, max_cycles=20, privileged=True)
    assert isinstance(env, LeagueSoccerEnv)
    parallel_api_test(env, num_cycles=30)


def test_the_game_starts_from_the_left_kick_off_with_both_teams_in_their_halves():
    env = game_v1.parallel_env(robot="T1", left_size=3, right_size=3, privileged=True)
    obs, infos = env.reset(seed=0)
    assert env.agents == ["left_1", "left_2", "left_3", "right_1", "right_2", "right_3"]
    assert {i["play_mode"] for i in infos.values()} == {"KickOff_Left"}
    n = len(env.robot.joints)
    for agent, o in obs.items():
        x, _y, cos_h, _sin_h = o[2 * n + 6 : 2 * n + 10]
        assert x < 0.0 and cos_h == pytest.approx(1.0, abs=1e-3), agent  # own half, facing +x
    # the right team's x is mirrored: its players stand at world x > 0
    for i in (3, 4, 5):
        assert env.world.torso_pose(i)[0][0] > 0.0
    env.close()


def test_a_goal_pays_the_scorers_and_ends_the_penalty():
    env = penalty_v1.parallel_env(robot="T1")
    env.reset(seed=0)
    env.world.place_ball((26.0, 0.0, env.robot.ball_radius), (8.0, 0.0, 0.0))
    for _ in range(100):
        _, rewards, terms, truncs, infos = env.step(_zero(env))
        if not env.agents:
            break
    assert rewards == {"left_1": 1.0, "right_1": -1.0}
    assert all(terms.values()) and not any(truncs.values())
    assert infos["left_1"]["goal"] == "left" and infos["left_1"]["score"] == (1, 0)


def test_ball_progress_is_zero_sum_and_seeded_episodes_repeat():
    def run():
        env = game_v1.parallel_env(robot="T1", left_size=1, right_size=1, ball_progress=1.0)
        obs, _ = env.reset(seed=3)
        env.world.place_ball((0.0, 0.0, env.robot.ball_radius), (1.0, 0.0, 0.0))
        rng = np.random.default_rng(0)
        total = {a: 0.0 for a in env.agents}
        trace = [obs["left_1"].copy()]
        for _ in range(25):
            acts = {a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
            obs, rewards, *_ = env.step(acts)
            for a, r in rewards.items():
                total[a] += r
            trace.append(obs["left_1"].copy())
        env.close()
        return total, np.array(trace)

    total, trace = run()
    assert total["left_1"] > 0.1 and total["left_1"] == pytest.approx(-total["right_1"])
    _, trace2 = run()
    np.testing.assert_array_equal(trace, trace2)


def test_bad_actions_and_options_name_the_problem():
    env = penalty_v1.parallel_env(robot="T1")
    env.reset(seed=0)
    bad = _zero(env)
    bad["right_1"] = np.full_like(bad["right_1"], np.nan)
    with pytest.raises(ValueError, match=r"right_1.*NaN"):
        env.step(bad)
    with pytest.raises(ValueError, match=r"left_1.*shape"):
        env.step({"left_1": np.zeros(3), "right_1": _zero(env)["right_1"]})
    with pytest.raises(KeyError, match="no agent 'left_9'"):
        env.action_space("left_9")
    with pytest.raises(ValueError, match="keepaway needs the Nao"):
        keepaway_v1.parallel_env(robot="T1")
    with pytest.raises(TypeError, match="left_types"):
        game_v1.parallel_env(robot="T1", left_types=(0,))
    with pytest.raises(ValueError, match="0-7"):
        game_v1.parallel_env(robot="T1", left_size=8)
    with pytest.raises(ValueError, match=r"R2D2"):
        game_v1.parallel_env(robot="R2D2")

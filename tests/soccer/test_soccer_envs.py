"""The soccer scenarios as PettingZoo environments: the API, seeds, bad input, the rules'
outcomes (goals, a won ball, the ball out) and their rewards."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from pettingzoo.test import api_test, parallel_api_test

from robocup_gym.sim import SimulationDivergedError
from robocup_gym.soccer import (
    SCENARIOS,
    game_v0,
    game_v1,
    keepaway_v0,
    keepaway_v1,
    penalty_v0,
    penalty_v1,
)
from robocup_gym.soccer.observations import observation_labels

MODULES = {
    "penalty_v1": penalty_v1,
    "keepaway_v1": keepaway_v1,
    "game_v1": game_v1,
    "penalty_v0": penalty_v0,
    "keepaway_v0": keepaway_v0,
    "game_v0": game_v0,
}


@pytest.fixture
def make():
    envs = []

    def factory(module, **options):
        env = module.parallel_env(**options)
        envs.append(env)
        return env

    yield factory
    for env in envs:
        env.close()


def _zero(env):
    return {a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents}


def test_every_scenario_module_is_listed():
    assert set(SCENARIOS) == set(MODULES)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_pettingzoos_parallel_and_aec_api_tests_pass(name):
    module = MODULES[name]
    parallel_api_test(module.parallel_env(max_cycles=40), num_cycles=120)
    api_test(module.env(max_cycles=40), num_cycles=120)


def test_agents_are_named_by_team_and_number_with_spaces_per_robot(make):
    env = make(game_v1, left_types=(0, 4, 2), right_types=(1,), max_cycles=5)
    assert env.possible_agents == ["left_1", "left_2", "left_3", "right_1"]
    assert env.action_space("left_2").shape == (24,)  # type 4 has toes
    assert env.action_space("left_1").shape == (22,)
    assert env.observation_space("left_2") is env.observation_space("left_2")
    model = env.game.world.robots[1].model
    assert env.observation_space("left_2").shape == (len(observation_labels(model, False)),)
    obs, infos = env.reset(seed=0)
    assert set(obs) == set(env.possible_agents)
    for a, o in obs.items():
        assert env.observation_space(a).contains(o)
    assert infos["right_1"]["play_mode"] == "KickOff_Left"


def test_a_seeded_game_repeats_exactly(make):
    def run(env, seed):
        rng = np.random.default_rng(7)
        obs, _ = env.reset(seed=seed)
        trace = [np.concatenate([obs[a] for a in env.possible_agents])]
        while env.agents:
            acts = {a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
            obs, rew, *_ = env.step(acts)
            trace.append(np.concatenate([obs[a] for a in sorted(obs)] + [[*rew.values()]]))
        return np.concatenate(trace)

    env = make(keepaway_v1, max_cycles=60)
    first = run(env, 3)
    again = run(env, 3)
    other = run(env, 4)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)  # another seed: other vision noise


def test_bad_actions_name_the_agent_and_the_problem(make):
    env = make(penalty_v1)
    env.reset(seed=0)
    acts = _zero(env)
    acts["right_1"] = np.full(22, np.nan)
    with pytest.raises(ValueError, match=r"right_1: action value 0 \(he1\) is nan"):
        env.step(acts)
    acts = _zero(env)
    acts["left_1"] = np.zeros(5)
    with pytest.raises(ValueError, match=r"left_1: action of shape \(5,\), expected \(22,\)"):
        env.step(acts)
    with pytest.raises(KeyError, match="no action for 'right_1'"):
        env.step({"left_1": np.zeros(22)})
    with pytest.raises(KeyError, match="'left_7'"):
        env.step({**_zero(env), "left_7": np.zeros(22)})
    with pytest.raises(KeyError, match="no agent 'middle_1'"):
        env.action_space("middle_1")
    acts = _zero(env)
    acts["left_1"] = "kick"
    with pytest.raises(ValueError, match=r"left_1: action must be numbers \(one value per joint"):
        env.step(acts)
    env.step(_zero(env))  # nothing was broken by the refused steps


def test_a_bad_action_in_the_aec_form_is_refused_at_its_agents_step():
    """PettingZoo's conversion keeps a cycle's actions until its last agent acts: a bad one is
    refused at its own agent's step, is not kept, and the agent acts again."""
    env = game_v1.env(max_cycles=20)
    try:
        env.reset(seed=0)
        first = env.agent_selection
        shape = env.action_space(first).shape
        with pytest.raises(ValueError, match=rf"{first}: action value 3 \(\w+\) is nan"):
            env.step(np.where(np.arange(shape[0]) == 3, np.nan, 0.0))
        with pytest.raises(ValueError, match=rf"{first}: action must be numbers"):
            env.step("kick")
        assert env.agent_selection == first
        acted = []
        for _ in range(2 * len(env.agents)):  # two whole cycles go on from there
            acted.append(env.agent_selection)
            env.step(np.zeros(env.action_space(env.agent_selection).shape))
        assert acted[0] == first and len(set(acted)) == len(env.possible_agents)
    finally:
        env.close()


def test_unknown_options_and_bad_values_are_refused():
    with pytest.raises(TypeError, match=r"unknown soccer option.*nosuch"):
        penalty_v1.parallel_env(nosuch=1)
    with pytest.raises(ValueError, match="9 is not a Nao type"):
        game_v1.parallel_env(left_types=(0, 9))
    with pytest.raises(ValueError, match="one player a side"):
        penalty_v1.parallel_env(left_types=(0, 0))
    with pytest.raises(ValueError, match="action_mode"):
        keepaway_v1.parallel_env(action_mode="torque")
    # a value of the wrong kind is named (from --env ball_progress=lots, say)
    with pytest.raises(ValueError, match="ball_progress must be a finite number, got 'lots'"):
        game_v1.parallel_env(ball_progress="lots")
    with pytest.raises(ValueError, match="reward_goal must be a finite number, got True"):
        game_v1.parallel_env(reward_goal=True)
    with pytest.raises(ValueError, match="privileged must be true or false, got 'no'"):
        game_v1.parallel_env(privileged="no")
    with pytest.raises(ValueError, match="left_types must be a sequence of Nao types 0-4"):
        game_v1.parallel_env(left_types=(0, "1"))
    with pytest.raises(ValueError, match="start_noise must be a finite distance >= 0, got 'x'"):
        penalty_v1.parallel_env(start_noise="x")


def test_a_penalty_goal_ends_the_episode_and_pays_the_striker(make):
    env = make(penalty_v1)
    env.reset(seed=0)
    # the ball rolls into the goal past the keeper
    env.game.host.set_ball((14.5, 0.8, 0.041), (3.0, 0.0, 0.0))
    for _ in range(100):
        _obs, rew, term, trunc, info = env.step(_zero(env))
        if term["left_1"]:
            break
    assert term == {"left_1": True, "right_1": True}
    assert not any(trunc.values())
    assert rew["left_1"] == pytest.approx(1.0) and rew["right_1"] == pytest.approx(-1.0)
    assert info["left_1"]["goal"] == "left"
    assert info["left_1"]["score"] == (1, 0) and info["right_1"]["score"] == (0, 1)
    assert info["left_1"]["end"] == "goal for the left team"
    assert env.agents == []
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})


def test_a_penalty_ball_out_ends_without_reward(make):
    env = make(penalty_v1)
    env.reset(seed=0)
    env.game.referee.last_touch = env.game.players[0]  # the striker kicked it wide
    env.game.host.set_ball((14.0, 3.0, 0.041), (3.0, 0.0, 0.0))
    for _ in range(100):
        _obs, rew, term, _trunc, info = env.step(_zero(env))
        if term["left_1"]:
            break
    assert term["left_1"] and rew == {"left_1": 0.0, "right_1": 0.0}
    assert info["left_1"]["end"].startswith("the ball is out (goal_kick_right")


def test_keepaway_pays_every_cycle_held_and_ends_when_the_defender_wins_the_ball(make):
    env = make(keepaway_v1)
    env.reset(seed=0)
    _, rew, *_ = env.step(_zero(env))
    assert rew["left_1"] == rew["left_2"] == pytest.approx(0.01)
    assert rew["right_1"] == pytest.approx(-0.01)
    # roll the ball into the defender (right_1 stands at x = 3 facing the attackers)
    env.game.host.set_ball((2.3, 0.0, 0.041), (2.0, 0.0, 0.0))
    for _ in range(60):
        _obs, rew, term, _trunc, info = env.step(_zero(env))
        if term["right_1"]:
            break
    assert term["right_1"] and info["left_1"]["end"] == "the defender won the ball"


def test_the_game_rewards_goals_zero_sum_and_runs_the_kickoff(make):
    env = make(game_v1, left_types=(0,), right_types=(0,), ball_progress=0.5, max_cycles=200)
    env.reset(seed=0)
    assert env.game.world.game.play_mode == "KickOff_Left"
    env.game.referee.set_play_mode("PlayOn")  # (kicked off)
    env.game.referee.last_touch = env.game.players[1]
    env.game.host.set_ball((-14.5, 0.8, 0.041), (-3.0, 0.0, 0.0))  # past the keeper, in
    total = {a: 0.0 for a in env.possible_agents}
    for _ in range(50):
        _obs, rew, _term, _trunc, info = env.step(_zero(env))
        for a, r in rew.items():
            total[a] += r
        if info["left_1"]["goal"]:
            break
    assert info["left_1"]["goal"] == "right" and info["right_1"]["score"] == (1, 0)
    assert total["left_1"] == pytest.approx(-total["right_1"])
    assert info["right_1"]["reward_terms"]["goal"] == pytest.approx(1.0)
    assert env.agents  # a goal does not end the game: the left team kicks off after 3 s


def test_a_diverged_simulation_ends_the_episode_truncated_for_everyone(make, monkeypatch):
    env = make(penalty_v1)
    env.reset(seed=0)
    world = env.game.world

    def blow_up():
        raise SimulationDivergedError("simulation diverged (test)")

    monkeypatch.setattr(world, "step", blow_up)
    _, rew, term, trunc, info = env.step(_zero(env))
    assert trunc == {"left_1": True, "right_1": True} and not any(term.values())
    assert info["left_1"]["diverged"] == "simulation diverged (test)"
    assert rew == {"left_1": 0.0, "right_1": 0.0}
    monkeypatch.undo()
    _obs, _ = env.reset(seed=0)  # and the next episode goes on
    env.step(_zero(env))


def test_privileged_observations_are_in_the_team_frame(make):
    env = make(game_v1, left_types=(0,), right_types=(0,), privileged=True, max_cycles=5)
    obs, _ = env.reset(seed=0)
    labels = observation_labels(env.game.world.robots[0].model, True, mates=0, opponents=1)
    x = labels.index("privileged/x")
    cos_h = labels.index("privileged/heading_cos")
    # both kick-off places are at x = -14 / +14 (the goalkeepers) facing the other goal: in
    # each team's frame the keeper stands at -14 m facing +x
    for a in env.possible_agents:
        assert obs[a][x] == pytest.approx(-14.0 / 15.0, abs=1e-3)
        assert obs[a][cos_h] == pytest.approx(1.0, abs=1e-3)
    # the other player's place, in the same frame: the opponent keeper at the opponent goal
    assert labels[-2:] == ["privileged/opponent1_x", "privileged/opponent1_y"]
    for a in env.possible_agents:
        assert obs[a][-2] == pytest.approx(14.0 / 15.0, abs=1e-3)


def test_privileged_observations_place_teammates_then_opponents(make):
    env = make(game_v1, left_types=(0, 1), right_types=(0, 1), privileged=True, max_cycles=5)
    obs, _ = env.reset(seed=0)
    w = env.game.world
    labels = observation_labels(w.robots[0].model, True, mates=1, opponents=2)
    assert env.observation_space("left_1").shape == (len(labels),)
    k = labels.index("privileged/mate1_x")
    assert labels[k:] == [
        "privileged/mate1_x",
        "privileged/mate1_y",
        "privileged/opponent1_x",
        "privileged/opponent1_y",
        "privileged/opponent2_x",
        "privileged/opponent2_y",
    ]
    where = {a: w.torso_position(env.game.index(a))[:2] for a in env.possible_agents}
    for a, others in (
        ("left_1", ["left_2", "right_1", "right_2"]),
        ("right_2", ["right_1", "left_1", "left_2"]),
    ):
        s = 1.0 if a.startswith("left") else -1.0
        want = np.concatenate([s * where[o] / (15.0, 10.0) for o in others])
        np.testing.assert_allclose(obs[a][k:], want, atol=1e-6)


def test_a_one_minute_eleven_against_eleven_game_runs_to_its_end(make):
    types = (0, 1, 2, 3, 4, 0, 1, 2, 3, 4, 0)  # mixed, as a league team
    env = make(game_v1, left_types=types, right_types=types, max_cycles=3000)
    assert len(env.possible_agents) == 22
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    steps = 0
    while env.agents:
        # small random joint velocities: robots move and some fall, nothing diverges (larger
        # ones topple every robot, and a field's side piled with robots only slows the test)
        acts = {a: 0.03 * rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
        _obs, _rew, term, trunc, info = env.step(acts)
        steps += 1
    assert steps == 3000
    assert all(trunc.values()) and not any(term.values())
    assert "diverged" not in info["left_1"]
    assert env.game.world.game.game_time == pytest.approx(60.0, abs=0.03)
    # robots that stayed down were taken off the field, beside it, as the referee does
    world = env.game.world
    off = [p for p in env.game.players if abs(float(world.torso_position(p.index)[1])) > 10.1]
    assert 0 < len(off) < 22


def test_the_soccer_benchmark_reports_every_measure(run_benchmark):
    res, _ = run_benchmark("soccer.py", "--quick", timeout=300)
    for key in (
        "penalty_env_steps_per_s",
        "game_2v2_steps_per_s",
        "game_2v2_skill_steps_per_s",
        "game_11v11_cycles_per_s",
        "game_11v11_joint_cycles_per_s",
        "physics_22_robots_cycles_per_s",
    ):
        assert res[key] > 0, key
    ratio = res["game_11v11_cycles_per_s"] / res["physics_22_robots_cycles_per_s"]
    assert res["game_vs_physics"] == pytest.approx(ratio, abs=1e-3)


def test_single_rules_can_be_switched_off(make):
    # without the ball-out rule a ball over the side line is not a kick-in: play goes on
    env = make(game_v1, left_types=(0,), right_types=(0,), rules={"ball_out": False})
    env.reset(seed=0)
    env.game.referee.set_play_mode("PlayOn")
    env.game.referee.last_touch = env.game.players[0]
    env.game.host.set_ball((0.0, 9.9, 0.041), (0.0, 2.0, 0.0))
    for _ in range(30):
        *_, info = env.step(_zero(env))
    assert info["left_1"]["play_mode"] == "PlayOn"
    assert env.game.ball_position()[1] > 10.1  # out, and nobody said so
    # with every rule it is
    env = make(game_v1, left_types=(0,), right_types=(0,))
    env.reset(seed=0)
    env.game.referee.set_play_mode("PlayOn")
    env.game.referee.last_touch = env.game.players[0]
    env.game.host.set_ball((0.0, 9.9, 0.041), (0.0, 2.0, 0.0))
    for _ in range(30):
        *_, info = env.step(_zero(env))
    assert info["left_1"]["play_mode"] == "KickIn_Right"
    # without goals a ball in the goal scores nothing
    env = make(penalty_v1, rules={"goals": False}, max_cycles=60)
    env.reset(seed=0)
    env.game.host.set_ball((14.5, 0.8, 0.041), (3.0, 0.0, 0.0))
    rewards = []
    while env.agents:
        _, rew, *_ = env.step(_zero(env))
        rewards.append(rew["left_1"])
    assert env.game.world.game.score_left == 0 and sum(rewards) == 0.0
    with pytest.raises(ValueError, match=r"unknown rule.*offside.*rules: ball_out"):
        game_v1.parallel_env(rules={"offside": False})


def test_a_random_start_places_players_and_ball_on_the_field_in_play(make):
    from robocup_gym.soccer.env import RANDOM_START_MARGIN_M, RANDOM_START_SPACING_M

    env = make(game_v1, left_types=(0, 1, 2), right_types=(0, 1, 2), random_start=True)
    starts = []
    for seed in (0, 0, 1):
        env.reset(seed=seed)
        world = env.game.world
        assert env.game.referee.play_mode == "PlayOn"
        ball = world.ball_position()[:2]
        xy = np.array([world.torso_position(env.game.index(a))[:2] for a in env.agents])
        for p in (ball, *xy):
            assert abs(p[0]) <= 15.0 - RANDOM_START_MARGIN_M[0] + 0.05
            assert abs(p[1]) <= 10.0 - RANDOM_START_MARGIN_M[1] + 0.05
        points = np.vstack([ball, xy])
        gaps = np.hypot(*(points[:, None] - points[None]).transpose(2, 0, 1))
        assert gaps[np.triu_indices(len(points), 1)].min() >= RANDOM_START_SPACING_M - 0.05
        starts.append(points)
    np.testing.assert_array_equal(starts[0], starts[1])  # the seed repeats the start
    assert np.abs(starts[0] - starts[2]).max() > 1.0
    with pytest.raises(ValueError, match="random_start is an option of the game"):
        make(penalty_v1, random_start=True)

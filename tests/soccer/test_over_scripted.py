"""A learning team that acts by correcting the scripted team (the team option
``over_scripted``: :class:`robocup_gym.soccer.scripted.OverScripted`)."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.sim.engines.ode import available as ode_available
from robocup_gym.soccer.scripted import OverScripted, ScriptedTeam, StandingTeam
from robocup_gym.soccer.team_view import TeamView, scenario_options, team_actions

needs_ode = pytest.mark.skipif(not ode_available(), reason="needs the system's libode")


def test_the_option_is_checked_and_excludes_plays():
    assert scenario_options("game-2v2")["over_scripted"] is False
    assert scenario_options("game-2v2", {"over_scripted": True})["over_scripted"] is True
    assert team_actions({"over_scripted": False}) is None
    with pytest.raises(ValueError, match="game-2v2: over_scripted must be true or false"):
        scenario_options("game-2v2", {"over_scripted": 1})
    with pytest.raises(ValueError, match="plays and over_scripted are two kinds of team action"):
        scenario_options("game-2v2", {"over_scripted": True, "plays": True})


@needs_ode
def test_a_zero_residual_plays_the_scripted_team_and_a_residual_moves_its_actions():
    """Through a game, a zero action of each player is what the scripted team decides for it;
    a residual is added to that (clipped to [-1, 1]); the game goes on with the actions the
    residuals give."""
    game = TeamView("game-2v2", lambda rng: StandingTeam(), {"over_scripted": True}, seed=3)
    scripted, over = ScriptedTeam(), OverScripted()  # each remembers its players' dribbles
    try:
        game.reset(seed=3)
        assert game.action_space.shape == (4,)
        residual = np.array([0.5, -0.25, 0.0, 0.0])
        moved = 0
        for step in range(120):
            mine = game.mine
            want = scripted(game.env, mine)
            zero = game.to_skills(game.env, mine, {a: np.zeros(4) for a in mine})
            shifted = over.skill_actions(game.env, mine, {a: residual for a in mine})
            for a in mine:
                assert np.array_equal(zero[a], want[a]), (step, a)
                np.testing.assert_allclose(shifted[a], np.clip(want[a] + residual, -1.0, 1.0))
                moved += not np.array_equal(shifted[a], want[a])
            game.step(np.zeros((game.seats, 4), np.float32))
        assert moved > 100  # the residual changed the actions (where not clipped away)
    finally:
        game.close()


@needs_ode
def test_a_bad_residual_names_the_player_and_the_value():
    game = TeamView("game-1v1", lambda rng: StandingTeam(), {"over_scripted": True}, seed=0)
    try:
        game.reset(seed=0)
        (me,) = game.mine
        with pytest.raises(ValueError, match=rf"{me}: action value 1 \(left\) is nan"):
            game.step(np.array([[0.0, np.nan, 0.0, 0.0]], np.float32))
        with pytest.raises(ValueError, match=rf"{me}: action of shape \(3,\), expected \(4,\)"):
            OverScripted().skill_actions(game.env, [me], {me: np.zeros(3)})
    finally:
        game.close()


@needs_ode
def test_a_learnt_team_acts_over_the_scripted_team():
    """A policy team trained with ``over_scripted`` plays its residuals over the scripted team
    in matches: a policy that always answers zero plays the scripted team's actions (its
    snapshots in the self-play pool and on serve: tests/soccer/test_ball_play.py)."""
    from robocup_gym.soccer.learnt import PolicyTeam

    options = {"over_scripted": True, "max_cycles": 200}
    game = TeamView("game-1v1", lambda rng: StandingTeam(), options, seed=1)
    try:
        obs, _ = game.reset(seed=1)
        team = PolicyTeam(lambda x: np.zeros((len(x), 4)), obs.shape[1], "zero", options)
        mine = game.mine
        got = team(game.env, mine, {a: obs[k] for k, a in enumerate(mine)})
        want = ScriptedTeam()(game.env, mine)
        for a in mine:
            assert np.array_equal(got[a], want[a])
    finally:
        game.close()

"""The referee's fallen-robot rule (reference §9.5) on an in-process game."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.sim.referee import INCAPABLE_S, Rules
from robocup_gym.sim.rotations import axis_angle_quat, quat_multiply, yaw_quat
from robocup_gym.soccer.game import SoccerGame, Start

LYING = quat_multiply(yaw_quat(np.radians(-90.0)), axis_angle_quat((1, 0, 0), np.radians(-90)))


def _lying_game(unum_of_lying: int, rules=True) -> SoccerGame:
    game = SoccerGame((0, 0), (), engine="mujoco", rules=rules, seed=0)
    game.reset(Start(players={"left_1": (-14.0, 0.0, 0.0), "left_2": (-3.0, 2.0, 0.0)}))
    game.referee.set_play_mode("PlayOn")
    game.world.place_robot(
        unum_of_lying - 1, -5.0, 1.0, z=0.1, quat=LYING, joint_angles_deg=np.zeros(22)
    )
    return game


def _run(game: SoccerGame, seconds: float) -> None:
    for _ in range(round(seconds / 0.02)):
        game.step({})


def test_a_field_player_not_standing_for_30_s_is_taken_off_the_field():
    game = _lying_game(2)
    down_s = INCAPABLE_S["not_standing"][0]
    _run(game, down_s - 0.5)
    assert game.world.torso_position(1)[2] < 0.25  # still lying where it fell
    _run(game, 0.6)  # past 30 s: lifted
    assert game.world.torso_position(1)[2] > 0.9
    _run(game, 0.6)  # held 0.5 s, then put beside the field, opposite the ball (y = 0 → -y)
    x, y, _ = game.world.torso_position(1)
    assert y == pytest.approx(-10.5, abs=0.05) and x == pytest.approx(-0.6 * 5, abs=0.05)
    game.close()


def test_the_goalkeeper_may_lie_twice_as_long_and_the_rule_can_be_off():
    game = _lying_game(1)
    _run(game, INCAPABLE_S["not_standing"][0] + 1.0)
    assert game.world.torso_position(0)[2] < 0.25  # a goalkeeper: 60 s
    game.close()
    game = _lying_game(2, rules={"fallen_robots": False})
    _run(game, INCAPABLE_S["not_standing"][0] + 1.0)
    assert game.world.torso_position(1)[2] < 0.25
    assert not Rules.of({"fallen_robots": False}).fallen_robots
    game.close()


def test_time_while_the_game_is_paused_does_not_count():
    game = _lying_game(2)
    game.referee.set_play_mode("BeforeKickOff")
    _run(game, INCAPABLE_S["not_standing"][0] + 1.0)
    assert game.world.torso_position(1)[2] < 0.25
    game.close()


def test_time_in_a_goals_pause_does_not_count_and_starts_the_count_again():
    """rcssserver3d pauses the fouls in a goal's pause (not only before a kick-off): a robot
    lying through a long Goal_Left (goals off, so the mode stays) is left alone, and in play-on
    it gets its whole 30 s again."""
    game = _lying_game(2, rules={"goals": False})
    down_s = INCAPABLE_S["not_standing"][0]
    _run(game, down_s - 10.0)
    game.referee.set_play_mode("Goal_Left")
    _run(game, down_s + 1.0)
    assert game.world.torso_position(1)[2] < 0.25
    game.referee.set_play_mode("PlayOn")
    _run(game, down_s - 0.5)
    assert game.world.torso_position(1)[2] < 0.25
    _run(game, 0.6)
    assert game.world.torso_position(1)[2] > 0.9
    game.close()

"""rcssserver3d's rules on the restarting kick and on scoring (robocup_gym.sim.kick_rules): each
decision on a constructed situation, and the referee applying them in a game."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robocup_gym.sim.kick_rules import KickRules
from robocup_gym.soccer.game import SoccerGame, Start


@dataclass(frozen=True)
class P:
    side: str
    unum: int


L2, L3, R2 = P("left", 2), P("left", 3), P("right", 2)
CENTRE = np.zeros(3)
FAR = np.array([8.0, 0.0, 0.04])


def test_the_kick_off_team_scores_only_after_the_others_touched_or_it_left_the_circle():
    k = KickRules()
    k.taken(L2, 1.0, True, kick_off=True)
    assert k.goal("right", L3, 3.0, 3.0, many=True) == ("goal_kick", "right")
    assert k.goal("left", L3, 3.0, 3.0, many=True) == ("goal", None)  # an own goal counts
    k.ball_touched_by({"left"}, np.array([1.0, 0.5, 0.04]))  # inside the centre circle
    assert k.goal("right", L3, 3.0, 3.0, many=True) == ("goal_kick", "right")
    k.ball_touched_by({"left"}, FAR)
    assert k.goal("right", L3, 3.0, 3.0, many=True) == ("goal", None)
    k = KickRules()
    k.taken(L2, 1.0, True, kick_off=True)
    k.ball_touched_by({"right"}, CENTRE)
    assert k.goal("right", L3, 3.0, 3.0, many=True) == ("goal", None)
    k.kick_off()  # the next kick-off: its team may score until it is taken
    assert k.kick_off_taker is None


def test_no_goal_straight_from_an_indirect_kick_nor_an_own_goal_from_any_set_piece():
    k = KickRules()
    k.taken(L2, 10.0, indirect=True)  # a kick-in
    assert k.goal("right", L2, 10.06, 11.0, many=True) == ("goal_kick", "right")
    k.taken(L2, 10.0, indirect=True)
    assert k.goal("right", L2, 10.06, 11.0, many=False) == ("goal", None)  # 2 players
    assert k.goal("right", L3, 10.3, 11.0, many=True) == ("goal", None)  # someone else's
    k.taken(L2, 10.0, indirect=True)
    assert k.goal("right", L2, 10.12, 11.0, many=True) == ("goal", None)  # a later touch
    k.taken(L2, 10.0, indirect=False)  # a corner or direct free kick
    assert k.goal("right", L2, 10.04, 11.0, many=True) == ("goal", None)
    k.taken(L2, 10.0, indirect=False)
    assert k.goal("left", L2, 10.04, 11.0, many=True) == ("corner_kick", "right")


def test_the_taker_may_not_touch_the_ball_twice_in_a_row():
    k = KickRules()
    k.taken(L2, 10.0, indirect=True)
    assert not k.second_touch(L2, 10.06)  # still the kick
    assert k.second_touch(L2, 10.2)
    assert not k.second_touch(L2, 10.4)  # called once
    k.taken(L2, 10.0, indirect=True)
    assert not k.second_touch(R2, 10.3)  # someone else played it: the watch ends
    assert not k.second_touch(L2, 10.6)
    k.taken(L2, 10.0, indirect=True)
    k.restart()  # the next restart
    assert not k.second_touch(L2, 10.2)


def test_after_pass_mode_a_goal_needs_two_team_mates_outside_the_circle():
    k = KickRules()
    k.in_pass_mode("left", 5.0, CENTRE)
    assert k.goal("right", L2, 6.0, 6.0, many=True) == ("goal_kick", "right")
    k.after_pass_mode([L2], 6.0, np.array([0.5, 0.0, 0.04]))
    k.after_pass_mode([L3], 6.5, np.array([0.8, 0.0, 0.04]))  # inside the 1 m circle
    assert k.goal("right", L3, 7.0, 7.0, many=True) == ("goal_kick", "right")
    k.after_pass_mode([L2], 7.5, np.array([2.0, 0.0, 0.04]))
    assert k.goal("right", L2, 8.0, 8.0, many=True) == ("goal", None)
    k.in_pass_mode("left", 20.0, CENTRE)
    assert k.goal("right", L2, 31.0, 31.0, many=True) == ("goal", None)  # 10 s later
    assert k.goal("left", R2, 21.0, 21.0, many=True) == ("goal", None)  # the other team


def test_a_taker_standing_on_the_ball_gives_the_other_team_a_free_kick():
    """A kick-in taken by a player put onto the ball, which keeps touching it: after 0.1 s
    that is a second touch, an indirect free kick for the other team where the ball is."""
    game = SoccerGame((0,), (0,), engine="ode", seed=0)
    game.reset(
        Start(
            players={"left_1": (-3.0, 2.0, 0.0), "right_1": (8.0, 0.0, 180.0)},
            ball=(0.0, 0.0),
            play_mode="KickIn_Left",
        )
    )
    modes = []
    for k in range(80):
        if k == 55:
            game.world.place_robot(0, -0.1, 0.0)
        game.step({})
        modes.append(game.referee.play_mode)
    game.close()
    assert modes[54] == "KickIn_Left"
    first = modes.index("PlayOn")
    assert "free_kick_right" in modes[first : first + 10]

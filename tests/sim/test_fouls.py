"""rcssserver3d's fouls between robots (reference §9.5): touching groups, charging and the
referee's safe spots, on in-process games of both Nao engines."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.sim.fouls import (
    AGENT_RADIUS,
    CHARGING_IMMUNITY_S,
    MAX_TOUCH_GROUP,
    ContactFouls,
    SafeSpot,
    robot_box,
)
from robocup_gym.sim.referee import Rules
from robocup_gym.soccer.env import SoccerConfig
from robocup_gym.soccer.game import SoccerGame, Start

ENGINES = ["ode", "mujoco"]
CHARGING_IMMUNITY_CYCLES = round(CHARGING_IMMUNITY_S / 0.02)
FAR = {"left_1": (-14.0, 0.0, 0.0), "right_1": (14.0, 0.0, 180.0)}


def _game(engine: str, left: int, right: int, rules=True, seed: int = 0) -> SoccerGame:
    """Goalkeepers at their goals, every other player parked on a side line, play-on."""
    game = SoccerGame((0,) * left, (0,) * right, engine=engine, rules=rules, seed=seed)
    players = {}
    for side, n in (("left", left), ("right", right)):
        for k in range(1, n + 1):
            name = f"{side}_{k}"
            players[name] = (
                FAR[name] if k == 1 else (-8.0 + 1.0 * k, 9.0 if side == "left" else -9.0, 0.0)
            )
    game.reset(Start(players=players, ball=(3.0, 3.0)))
    game.referee.set_play_mode("PlayOn")
    return game


def _xy(game: SoccerGame, index: int) -> np.ndarray:
    return game.world.torso_position(index)[:2].copy()


def _step(game: SoccerGame, n: int = 1) -> None:
    for _ in range(n):
        game.step({})


def _touching_setup(game: SoccerGame, pair: tuple[int, int], joiner: int) -> None:
    """``pair`` placed touching (shoulder to shoulder, 0.24 m apart in y) for a cycle, then
    ``joiner`` placed against the first of them from the other side."""
    _step(game, 5)
    game.world.move_robot(pair[0], (-5.0, 0.0, 0.36))
    game.world.move_robot(pair[1], (-5.0, 0.24, 0.36))
    _step(game)
    game.world.move_robot(joiner, (-5.0, -0.24, 0.36))
    _step(game)


@pytest.mark.parametrize("engine", ENGINES)
def test_contacts_between_robots_are_reported_by_pair(engine):
    game = _game(engine, 3, 0)
    _step(game, 3)
    assert game.world.robot_contacts() == {}
    game.world.move_robot(1, (-5.0, 0.0, 0.36))
    game.world.move_robot(2, (-5.0, 0.24, 0.36))
    _step(game)
    contacts = game.world.robot_contacts()
    assert set(contacts) == {(1, 2)}
    point, count = contacts[(1, 2)]
    assert count > 0
    assert -5.2 < point[0] < -4.8 and 0.0 < point[1] < 0.24 and 0.2 < point[2] < 0.6
    game.close()


@pytest.mark.parametrize("engine", ENGINES)
def test_the_robot_that_joins_a_group_of_two_is_moved_away_from_its_centre(engine):
    game = _game(engine, 4, 0)
    _touching_setup(game, (1, 2), 3)
    # the group's centre is y = 0: the joiner at y = -0.24 goes 0.4 m further, to -0.64
    assert _xy(game, 3) == pytest.approx([-5.0, -0.64], abs=0.02)
    assert game.referee.fouls == [(1, 1, "left", 4)]  # a touching foul (type 1) of left #4
    assert _xy(game, 1)[1] == pytest.approx(0.0, abs=0.05)  # the two stay (pushed apart a bit)
    assert _xy(game, 2)[1] == pytest.approx(0.24, abs=0.05)
    game.close()


@pytest.mark.parametrize(
    "rules", [{"touching": False}, {"before_kickoff": False, "kickoff": False}]
)
def test_no_touching_foul_with_the_rule_off_or_while_the_game_is_paused(rules):
    game = _game("ode", 4, 0, rules=rules)
    if "kickoff" in rules:
        game.referee.set_play_mode("BeforeKickOff")
    _touching_setup(game, (1, 2), 3)
    assert _xy(game, 3) == pytest.approx([-5.0, -0.24], abs=0.02)
    game.close()


def test_two_robots_in_contact_are_no_foul():
    assert MAX_TOUCH_GROUP == 2
    game = _game("ode", 3, 0)
    _step(game, 5)
    game.world.move_robot(1, (-5.0, 0.0, 0.36))
    _step(game)
    game.world.move_robot(2, (-5.0, 0.24, 0.36))
    _step(game, 3)
    assert _xy(game, 2) == pytest.approx([-5.0, 0.24], abs=0.05)
    game.close()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_goalkeeper_that_joins_has_a_team_mate_moved_instead(seed):
    game = _game("ode", 3, 0, seed=seed)
    _touching_setup(game, (1, 2), 0)
    assert _xy(game, 0) == pytest.approx([-5.0, -0.24], abs=0.02)  # the goalkeeper stays
    moved = [i for i, y in ((1, 0.0), (2, 0.24)) if abs(_xy(game, i)[1] - y) > 0.2]
    assert len(moved) == 1
    game.close()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_opponent_joining_two_has_one_of_the_two_moved(seed):
    """The team with more robots in the group loses one: a right player joining two left
    players stays, one of the left players is moved."""
    game = _game("ode", 3, 2, seed=seed)
    _touching_setup(game, (1, 2), 4)
    assert _xy(game, 4) == pytest.approx([-5.0, -0.24], abs=0.02)
    moved = [i for i, y in ((1, 0.0), (2, 0.24)) if abs(_xy(game, i)[1] - y) > 0.2]
    assert len(moved) == 1
    game.close()


def _charge(engine: str, rules=True, opponent=True):
    """left_2 pushed (+x) into a standing robot 0.45 m ahead of it, the ball far away; the
    pushed robot's torso height over the next 0.9 s."""
    game = _game(engine, 2, 2, rules=rules)
    other = 3 if opponent else 0
    game.world.move_robot(1, (-5.0, 0.0, 0.36))
    game.world.move_robot(other, (-4.55, 0.0, 0.36))
    _step(game, 55)  # more than 1 s after the last move of the referee
    game.world.set_torso_force(1, (60.0, 0.0, 0.0))
    wake = np.zeros(22)
    wake[0] = 0.01  # a robot put down rests until a joint moves
    heights = []
    for _ in range(45):
        game.step({1: wake})
        heights.append(float(game.world.torso_position(1)[2]))
    return game, heights


@pytest.mark.parametrize("engine", ENGINES)
def test_a_robot_running_into_an_opponent_is_lifted_and_put_beside_the_field(engine):
    game, heights = _charge(engine)
    assert max(heights) > 1.0  # lifted
    # a charging foul (type 6) of left #2, recorded every cycle it is held, as the server does
    assert {f[1:] for f in game.referee.fouls} == {(6, "left", 2)}
    game.world.set_torso_force(1, (0.0, 0.0, 0.0))
    _step(game, 30)
    x, y, _ = game.world.torso_position(1)
    assert len(game.referee.fouls) == 26  # the foul's cycle, 25 cycles held, the last move
    # beside the field on the side away from the ball (at y = 3)
    assert y == pytest.approx(-10.5, abs=0.05) and x == pytest.approx(-0.6 * 5, abs=0.3)
    assert game.world.torso_position(3)[2] < 1.0  # the robot it ran into is no foul
    game.close()


@pytest.mark.parametrize(
    "kwargs", [{"rules": {"charging": False}}, {"opponent": False}], ids=["rule-off", "team-mate"]
)
def test_no_charging_foul_with_the_rule_off_or_into_a_team_mate(kwargs):
    game, heights = _charge("ode", **kwargs)
    assert max(heights) < 0.6
    game.close()


def _clash(ball=(5.0, 5.0), speed=0.6, fouls: ContactFouls | None = None, **kwargs) -> set[int]:
    """The charging analysis of one cycle: left robot 1 at the origin moving +x at
    ``speed`` into right robot 2 standing at (0.3, 0), touching at (0.15, 0, 0.3)."""
    fouls = fouls or ContactFouls()
    for _ in range(3):
        fouls.record_velocity(1, np.array([speed, 0.0, 0.0]))
        fouls.record_velocity(2, np.zeros(3))
    fouls.tick([1, 2], set())
    return fouls.charging(
        [1],
        {1: [(2, np.array([0.15, 0.0, 0.3]))]},
        {1: np.array([0.0, 0.0, 0.38]), 2: np.array([0.3, 0.0, 0.38])},
        np.array([*ball, 0.04]),
        kwargs.get("exempt", set()),
        kwargs.get("goalie", {}),
    )


def test_charging_is_running_at_an_opponent_not_at_the_ball():
    assert _clash() == {1}
    assert _clash(speed=0.3) == set()  # slower than 0.4 m/s
    assert _clash(exempt={1}) == set()  # not standing, just moved by the referee, ...
    assert _clash(goalie={1: True}) == set()  # a goalkeeper in its own penalty area
    # within 1 m of the ball: heading for the opponent more than for the ball is charging
    assert _clash(ball=(0.15, 0.12)) == {1}  # the ball 39° off the run, the opponent 0°
    # a contact within 0.1 m of the ball is a challenge for it
    assert _clash(ball=(0.15, 0.09)) == set()


def test_a_touch_of_the_ball_gives_a_second_of_immunity():
    fouls = ContactFouls()
    fouls.tick([1, 2], {1})  # robot 1 touches the ball
    for _ in range(CHARGING_IMMUNITY_CYCLES - 1):
        assert _clash(fouls=fouls) == set()
    assert _clash(fouls=fouls) == {1}


def test_a_charge_needs_a_fifth_of_a_second_after_a_clash_that_was_none():
    fouls = ContactFouls()
    assert _clash(speed=0.0, fouls=fouls) == set()  # a clash without a charge: clock to 0
    results = [_clash(fouls=fouls) for _ in range(12)]
    first = results.index({1})
    assert first == 9 and not any(results[:first])


def test_a_safe_spot_is_the_target_when_free_and_the_nearest_free_one_otherwise():
    box = (np.array([-0.15, -0.15, 0.0]), np.array([0.15, 0.15, 0.55]))
    spot = SafeSpot(
        side="left",
        area=(-15.0, -13.2, -1.95, 1.95),
        crowded=False,
        inside=False,
        boxes=[box],
        ball=np.array([5.0, 5.0]),
    )
    free = spot.find(np.array([2.0, 0.0, 0.4]), np.array([2.0, 0.5]))
    assert free.tolist() == [2.0, 0.0, 0.4]
    taken = spot.find(np.array([0.3, 0.0, 0.4]), np.array([0.3, 0.3]))
    lo, hi = box
    nearest = np.clip(taken, lo, hi)
    assert np.linalg.norm(taken - nearest) > AGENT_RADIUS
    assert np.hypot(*(taken[:2] - [0.3, 0.0])) == pytest.approx(AGENT_RADIUS)
    goal = spot.find(np.array([-15.3, 0.0, 0.4]), np.array([-14.8, 0.0]))
    assert abs(goal[0]) <= 15.0 or abs(goal[1]) >= 1.05 + AGENT_RADIUS
    near_ball = spot.find(np.array([5.2, 5.0, 0.4]), np.array([5.6, 5.0]))
    assert np.hypot(*(near_ball[:2] - [5.0, 5.0])) >= 2 * AGENT_RADIUS


def test_a_full_own_penalty_area_is_no_safe_spot_for_one_outside_it():
    spot = SafeSpot(
        side="left",
        area=(-15.0, -13.2, -1.95, 1.95),
        crowded=True,
        inside=False,
        boxes=[],
        ball=np.array([0.0, 0.0]),
    )
    # from deeper in: out over the area's front edge; from in front: out over a side edge
    out = spot.find(np.array([-13.5, 0.5, 0.4]), np.array([-14.5, 0.5]))
    assert out[:2] == pytest.approx([-13.2 + AGENT_RADIUS, 0.5])
    out = spot.find(np.array([-13.5, 0.5, 0.4]), np.array([-12.5, 0.5]))
    assert out[:2] == pytest.approx([-13.5, 1.95 + AGENT_RADIUS])


def test_a_robots_bounding_box_holds_its_parts():
    game = _game("ode", 1, 0)
    lo, hi = robot_box(game.world, 0)
    centres, _ = game.world.body_frames(0)
    assert np.all(centres >= lo) and np.all(centres <= hi)
    assert hi[2] - lo[2] == pytest.approx(0.385 + 0.155 + 0.065, abs=0.03)  # sole to head top
    game.close()


def test_the_environments_keep_the_contact_fouls_off_unless_asked():
    assert not SoccerConfig().game_rules.touching and not SoccerConfig().game_rules.charging
    on = SoccerConfig(contact_fouls=True).game_rules
    assert on.touching and on.charging
    assert Rules.of(True).touching and Rules.of(True).charging  # serve: every rule
    with pytest.raises(ValueError, match="contact_fouls"):
        SoccerConfig(contact_fouls="yes")


def test_monitors_get_each_foul_once():
    from robocup_gym.server.monitor import MonitorStream

    stream = MonitorStream()
    fouls = [(1, 1, "left", 4)]
    stream.fouls = fouls
    game = _game("ode", 1, 0)
    assert "(foul 1 1 1 4)" in stream._env_full(game.world, 1, {})
    assert "foul" not in stream._env_delta(game.world, 1, {})
    fouls.append((2, 6, "right", 3))
    assert "(foul 2 6 2 3)" in stream._env_delta(game.world, 1, {})
    game.close()

"""examples/shooting_team.py: a team composed from the scripted team and ``approach-kick``."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from robocup_gym.soccer import game_v1
from robocup_gym.soccer.scripted import ScriptedTeam

_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "shooting_team.py"


def _example():
    spec = importlib.util.spec_from_file_location("shooting_team", _EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_shooting_team_kicks_off_with_a_shot_toward_the_goal():
    """At its kick-off the ball is free: the field player walks to it and kicks it with
    ``approach-kick``; once the ball has gone, the team no longer asks for the motion (a second
    touch would be a foul at a kick-off); the keeper never shoots."""
    example = _example()
    env = game_v1.parallel_env(
        actions="skills",
        skills=("kick", "approach-kick"),
        walk="walk",
        walk_faces_x=False,
        max_cycles=1000,  # 20 s
    )
    team, other = example.ShootingTeam(), ScriptedTeam()
    try:
        obs, _ = env.reset(seed=0)
        assert env.game.referee.play_mode == "KickOff_Left"
        keeper_shot, kicked_by, steps_after = False, None, 0
        player = env.skills.players[env.game.index("left_2")]
        while env.agents:
            mine = [n for n in env.agents if n.startswith("left")]
            theirs = [n for n in env.agents if n.startswith("right")]
            actions = team(env, mine, obs)
            keeper_shot |= actions["left_1"][4] > 0.5
            mode = player.mode
            obs, *_ = env.step({**actions, **other(env, theirs, obs)})
            if kicked_by is None and np.hypot(*env.game.world.ball_position()[:2]) > 0.5:
                kicked_by = mode
            steps_after += kicked_by is not None
            if steps_after == 10:  # 2 s after the kick
                assert "left_2" not in team.shooting
    finally:
        env.close()
    assert team.shots >= 1
    assert not keeper_shot
    assert kicked_by == "approach-kick"
    assert steps_after > 10


def test_a_shot_is_aimed_beside_the_goalkeeper_within_the_skills_reach():
    example = _example()
    from robocup_gym.soccer.scripted import TeamView

    team = example.ShootingTeam()
    view = TeamView(
        side="left",
        ball=np.array([8.0, 0.0]),
        positions={"left_2": np.array([7.5, 0.0])},
        headings={"left_2": (1.0, 0.0)},
        keepers=set(),
        opponents=np.array([[13.8, 0.2]]),  # their keeper, a little left of the middle
    )
    shot = team._shot(view, "left_2", 0.5, 5.8)
    assert shot is not None and shot[0] == 1.0
    assert shot[2] < 0.0  # to the right, away from the keeper
    # a contested ball, or one ahead of the player, is not shot at
    assert team._shot(view, "left_2", 0.5, 1.0) is None
    view.positions["left_2"] = np.array([8.5, 0.0])
    assert team._shot(view, "left_2", 0.5, 5.8) is None

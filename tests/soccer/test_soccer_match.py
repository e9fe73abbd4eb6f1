"""Matches: the result counted from the first team's side, and the command's output and errors."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

from robocup_gym.sim.engines.ode import available
from robocup_gym.soccer import game_v1
from robocup_gym.soccer.match import GameResult, MatchResult, make_team, play_match
from robocup_gym.soccer.scripted import ScriptedTeam


def test_a_match_result_counts_from_the_first_teams_side():
    r = MatchResult("a", "b")
    r.games = [
        GameResult("left", 2, 0, 60.0),
        GameResult("right", 1, 1, 60.0),
        GameResult("left", 0, 1, 60.0),
        GameResult("right", 3, 0, 60.0),
    ]
    s = r.summary
    assert (s["wins"], s["draws"], s["losses"]) == (2, 1, 1)
    assert (s["goals_for"], s["goals_against"]) == (6, 2)
    diffs = np.array([2, 0, -1, 3])
    half = 1.96 * diffs.std(ddof=1) / 2
    assert s["goal_difference_ci95"] == pytest.approx([1.0 - half, 1.0 + half], abs=1e-3)
    assert (
        MatchResult("a", "b", [GameResult("left", 1, 0, 60.0)]).summary["goal_difference_ci95"]
        is None
    )  # one game gives no interval


def test_unknown_teams_and_set_ups_are_refused():
    with pytest.raises(ValueError, match="unknown team 'nosuch'; teams: scripted, standing"):
        make_team("nosuch")
    with pytest.raises(ValueError, match="players must be 1-11"):
        play_match("scripted", "standing", players=12)
    with pytest.raises(ValueError, match="2 players need 2 robot types"):
        play_match("scripted", "standing", players=2, robot_types=[0])


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_the_scripted_striker_takes_the_ball_toward_the_goal_and_kicks():
    """The scripted team's chaser walks round to the ball, lines up with the goal and kicks."""
    env = game_v1.parallel_env(actions="skills", left_types=(0,), right_types=(), max_cycles=3000)
    env.reset(seed=0)
    env.game.referee.set_play_mode("PlayOn")
    env.game.host.set_ball((5.0, 1.0, 0.041), (0.0, 0.0, 0.0))
    w = env.game.world
    w.place_robot(0, 6.0, -1.0, heading_deg=180.0)  # in front of the ball, facing away from goal
    team = ScriptedTeam()
    modes = []
    for _ in range(300):  # 60 s
        env.step(team(env, list(env.agents)))
        modes.append(env.skills.modes()[0])
    env.close()
    assert "kick" in modes
    ball = w.ball_position()
    assert ball[0] > 6.5 or w.game.score_left == 1, ball


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_the_match_command_prints_its_result_last():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "robocup_gym.cli",
            "match",
            "scripted",
            "standing",
            "--games",
            "2",
            "--seconds",
            "4",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout.strip().splitlines()[-1])
    assert res["games"] == 2 and res["team_a"] == "scripted"
    assert res["wins"] + res["draws"] + res["losses"] == 2
    assert "game 2/2" in out.stdout


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_the_match_command_records_the_first_game(tmp_path, offscreen_gl):
    import imageio.v2 as imageio

    video = tmp_path / "game.mp4"
    cmd = ["match", "scripted", "standing", "--games", "1", "--players", "1", "--seconds", "2"]
    out = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", *cmd, "--video", str(video)],
        env=offscreen_gl,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout.strip().splitlines()[-1])["video"] == str(video)
    frames = [f.astype(float) for f in imageio.get_reader(str(video), format="FFMPEG")]
    assert len(frames) == 50  # 2 s of game time at 25 frames a second
    assert frames[0].shape == (360, 640, 3) and frames[0].std() > 1.0  # not blank
    assert np.abs(frames[0] - frames[-1]).mean() > 0.1  # the game moved


def test_the_match_command_names_an_unknown_team():
    out = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", "match", "scripted", "nosuch", "--games", "1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 1
    assert "unknown team 'nosuch'" in out.stdout + out.stderr

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
from robocup_gym.soccer.scripted import ScriptedTeam, TeamView


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
    with pytest.raises(ValueError, match=r"seed must be an integer >= 0 \(game k plays seed"):
        play_match("scripted", "standing", seed=-1)


def _chaser_alone(robot_type: int, ball: tuple[float, float], cycles: int):
    """The scripted team's one player, Nao type ``robot_type``, in play on an empty field: 1 m in
    front of the ball (toward the opponent goal) and 2 m to its right, facing away from the goal.
    Plays until a goal or ``cycles``; returns the ball's largest x, the player's skill modes
    and the left team's score."""
    env = game_v1.parallel_env(
        actions="skills", left_types=(robot_type,), right_types=(), max_cycles=3000
    )
    env.reset(seed=0)
    env.game.referee.set_play_mode("PlayOn")
    env.game.host.set_ball((ball[0], ball[1], 0.041), (0.0, 0.0, 0.0))
    w = env.game.world
    w.place_robot(0, ball[0] + 1.0, ball[1] - 2.0, heading_deg=180.0)
    team = ScriptedTeam()
    modes, furthest = [], ball[0]
    for _ in range(cycles // env.config.skill_cycles):
        env.step(team(env, list(env.agents)))
        modes.append(env.skills.modes()[0])
        furthest = max(furthest, float(w.ball_position()[0]))
        if w.game.score_left:
            break
    score = w.game.score_left
    env.close()
    return furthest, modes, score


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_the_scripted_chaser_rounds_the_ball_and_dribbles_it_toward_the_goal():
    """From in front of the ball, facing away from the goal, the chaser walks round the ball,
    lines up and walks it forward without falling: 45 s take it 3 m on."""
    furthest, modes, _ = _chaser_alone(0, (0.0, 1.0), cycles=2250)
    assert "get-up" not in modes
    assert furthest > 3.0


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_the_scripted_chaser_takes_the_ball_into_the_goal():
    """3.6 m from the goal, facing away from it: a type 1 chaser, whose walk falls more often,
    gets the ball into the goal within 60 s."""
    _, _, score = _chaser_alone(1, (11.5, 1.0), cycles=3000)
    assert score == 1


def test_the_scripted_chaser_kicks_a_ball_before_its_right_foot_in_shooting_range():
    """The kick decision: behind the ball, facing the goal, the ball 12 cm ahead and 6 cm to
    the right: within 4 m of the goal it kicks; farther it walks on (dribbles)."""

    class _Game:
        def __init__(self, view: TeamView) -> None:
            self.view = view

        def team_view(self, agents):
            return self.view

    for ball_x, kicks in ((12.0, True), (5.0, False)):
        ball = np.array([ball_x, 0.0])
        pos = ball - np.array([0.12, -0.06])
        view = TeamView("left", ball, {"left_1": pos}, {"left_1": (1.0, 0.0)}, set())
        act = ScriptedTeam()(_Game(view), ["left_1"])["left_1"]
        assert bool(act[3] > 0.5) is kicks, (ball_x, act)
        assert act[0] > 0  # walking on toward the goal


def test_the_scripted_chaser_waits_outside_the_circle_at_the_other_team_s_kick_off():
    """In play the chaser 1 m in front of the ball, facing it, walks to it; at the other team's
    kick-off it does not: it heads for a spot 2.5 m from the ball on its own goal's side
    (behind it: it turns)."""

    class _Game:
        play_mode = "PlayOn"

        def team_view(self, agents):
            return TeamView(
                side="right",
                ball=np.zeros(2),
                positions={"right_1": np.array([14.0, 0.0]), "right_2": np.array([1.0, 0.0])},
                headings={"right_1": (-1.0, 0.0), "right_2": (-1.0, 0.0)},
                keepers={"right_1"},
                play_mode=self.play_mode,
            )

    game, team = _Game(), ScriptedTeam()
    assert team(game, ["right_1", "right_2"])["right_2"][0] > 0.2
    game.play_mode = "KickOff_Left"
    act = team(game, ["right_1", "right_2"])["right_2"]
    assert act[0] <= 0.0 and abs(act[2]) > 0.5 and act[3] < 0


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
    cmd = ["match", "scripted", "standing", "--games", "1", "--players", "1", "--seconds", "1"]
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
    assert len(frames) == 25  # 1 s of game time at 25 frames a second
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


def test_a_match_on_serve_plays_each_game_on_a_fresh_server_and_changes_sides():
    """``--on serve``: each player its own connection; the first team in plays left, the
    teams change sides every game; the result is counted from the first team's side."""
    cmd = ["match", "scripted", "standing", "--on", "serve", "--games", "2", "--seconds", "10"]
    out = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", *cmd, "--players", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert "game 1/2: scripted (left)" in out.stdout
    assert "game 2/2: scripted (right)" in out.stdout
    summary = json.loads(out.stdout.strip().splitlines()[-1])
    assert summary["games"] == 2 and summary["team_a"] == "scripted"
    assert summary["wins"] + summary["draws"] + summary["losses"] == 2


@pytest.mark.skipif(not available(), reason="the shipped skills run on ODE")
def test_a_match_game_on_a_seeded_serve_is_the_same_every_time():
    """Both teams join in fixed cycles, the trainer kicks off in a fixed cycle and the skills
    are seeded: a game of ``match --on serve`` is the same every time (compared to the last bit
    of where the scripted team sees the ball at each decision); another seed, another game."""
    from robocup_gym.soccer.match import SETTLE_CYCLES, _GameServer, _server_game
    from robocup_gym.soccer.scripted import StandingTeam

    def game(seed: int) -> tuple[np.ndarray, dict]:
        seen: list[np.ndarray] = []

        class Watched(ScriptedTeam):
            def __call__(self, env, agents, obs=None):
                seen.append(np.asarray(env.team_view(agents).ball, dtype=float).copy())
                return super().__call__(env, agents, obs)

        with _GameServer("serve", "ode", seed, None) as ports:
            teams = {"A": Watched(), "B": StandingTeam()}
            played = _server_game(teams, ("A", "B"), ports, (0, 1), 8.0, seed, SETTLE_CYCLES)
        return np.array(seen), played

    first, played = game(3)
    assert len(first) > 30 and played["A"].side == "left" and played["A"].end == "time"
    assert np.ptp(first[:, 0]) > 0.3  # the scripted team played the ball
    again, _ = game(3)
    np.testing.assert_array_equal(first, again)
    other, _ = game(4)
    assert other.shape != first.shape or not np.array_equal(first, other)


def test_a_match_on_a_real_server(real_rcssserver3d):
    from robocup_gym.soccer.match import play_server_match

    games = []
    result = play_server_match(
        "standing",
        "scripted",
        server="rcssserver3d",
        binary=real_rcssserver3d,
        games=2,
        players=1,
        seconds=10.0,
        on_game=lambda k, g: games.append(k),
    )
    assert games == [0, 1]
    assert [g.a_side for g in result.games] == ["left", "right"]
    assert result.games[0].seconds == 10.0
    assert result.summary["goals_for"] == 0  # standing players do not score


def test_a_match_on_a_server_refuses_what_it_cannot_play():
    from robocup_gym.soccer.match import play_server_match

    with pytest.raises(ValueError, match="server must be one of serve, rcssserver3d"):
        play_server_match("scripted", "standing", server="nowhere")
    with pytest.raises(ValueError, match="unknown team 'nosuch'"):
        play_server_match("scripted", "nosuch", games=1)
    out = subprocess.run(
        [sys.executable, "-m", "robocup_gym.cli", "match", "scripted", "standing", "--on",
         "serve", "--scenario", "penalty"],
        capture_output=True,
        text=True,
        timeout=120,
    )  # fmt: skip
    assert out.returncode == 1
    assert (
        "on serve a match plays games (no --scenario penalty, no --video)"
        in out.stderr + out.stdout
    )


def test_a_match_can_be_played_with_the_omnidirectional_walk():
    """``--walk walk``: both teams' skill actions walk with the omnidirectional walk (the
    players seen as they face); on a server the players keep the game's walk."""
    from typer.testing import CliRunner

    from robocup_gym.cli import app

    result = play_match("scripted", "standing", games=1, seconds=4.0, walk="walk")
    assert len(result.games) == 1 and not result.games[0].diverged
    runner = CliRunner()
    bad = runner.invoke(app, ["match", "scripted", "standing", "--walk", "nowalk", "--games", "1"])
    assert bad.exit_code == 1 and "no pretrained policy 'nowalk'" in bad.output
    served = runner.invoke(
        app, ["match", "scripted", "standing", "--walk", "walk", "--on", "serve"]
    )
    assert served.exit_code == 1 and "--walk is for in-process" in served.output


def test_a_match_plays_a_team_object_in_the_game_its_options_name():
    """A team object plays as a named team does; its ``options`` (as a learnt team records
    them) set the game's motion skills and walk; the result names it by its ``name``."""
    from robocup_gym.soccer.scripted import StandingTeam

    seen = {}

    class Team(StandingTeam):
        name = "mine"

        def __init__(self) -> None:
            self.options = {"skills": ("kick", "approach-kick"), "walk": "walk"}

        def __call__(self, env, agents, obs=None):
            seen["labels"], seen["walk"] = env.skill_action_labels, env.config.walk
            return super().__call__(env, agents, obs)

    result = play_match(Team(), "scripted", games=1, seconds=1.0)
    assert result.summary["team_a"] == "mine" and result.summary["team_b"] == "scripted"
    assert seen["labels"][3:5] == ("kick", "approach-kick")
    assert seen["walk"] == "walk"
    with pytest.raises(ValueError, match=r"a team is a name or a callable.*got int"):
        play_match(42, "scripted", games=1)

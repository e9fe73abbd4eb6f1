"""Playing the ball along a direction (``robocup_gym.soccer.ball_play``): the scripted chaser's
dribble, and the ``plays`` actions of a learning team (beside its residuals over the scripted
team, ``over_scripted``, where both go the same way: the self-play pool, serve)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from robocup_gym.sim.engines.ode import available as ode_available
from robocup_gym.soccer.ball_play import PLAY_ACTION_LABELS, BallPlay, as_play_action
from robocup_gym.soccer.remote import HEAD_TILT_DEG
from robocup_gym.soccer.scripted import ScriptedTeam, StandingTeam, TeamView
from robocup_gym.soccer.team_view import TeamView as TeamGame
from robocup_gym.soccer.team_view import scenario_options

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

needs_ode = pytest.mark.skipif(not ode_available(), reason="needs the system's libode")


def _view(side: str = "left") -> TeamView:
    """Two players of ``side``, one goalkeeper, near a ball off the middle of the field."""
    return TeamView(
        side=side,
        ball=np.array([1.0, 0.5]),
        positions={f"{side}_1": np.array([-10.0, 0.0]), f"{side}_2": np.array([0.3, 0.2])},
        headings={f"{side}_1": (1.0, 0.0), f"{side}_2": (math.cos(0.3), math.sin(0.3))},
        keepers={f"{side}_1"},
    )


def test_a_plays_action_that_does_not_play_the_ball_is_its_skill_action():
    walk = np.array([0.5, -0.2, 0.1, 0.9, -1.0, 0.7])
    out = BallPlay().skill_actions(_view(), {"left_2": walk})
    np.testing.assert_array_equal(out["left_2"], walk[:4])
    np.testing.assert_array_equal(as_play_action(walk[:4])[:4], walk[:4])
    assert as_play_action(walk[:4])[4] < 0.5  # does not play the ball
    assert len(PLAY_ACTION_LABELS) == 6


@pytest.mark.parametrize("side", ["left", "right"])
def test_the_scripted_chaser_plays_the_ball_at_the_goal(side):
    """With nobody in the way, the scripted chaser's action is the plays action "the ball
    straight at the goal" (direction 0), the dribble far from the goal and the shot near it."""
    for ball in (np.array([1.0, 0.5]), np.array([12.0 if side == "left" else -12.0, 1.0])):
        view = _view(side)
        view.ball = ball
        view.positions[f"{side}_2"] = ball + np.array([-0.5 if side == "left" else 0.5, -0.3])
        scripted = ScriptedTeam()(_Env(view), [f"{side}_1", f"{side}_2"])
        near_goal = abs(ball[0]) > 10.0
        play = np.array([0.0, 0.0, 0.0, 1.0 if near_goal else -1.0, 1.0, 0.0])
        played = BallPlay().skill_actions(view, {f"{side}_2": play})
        np.testing.assert_allclose(played[f"{side}_2"], scripted[f"{side}_2"], atol=1e-12)


class _Env:
    """A game that shows a fixed view to a team."""

    def __init__(self, view: TeamView) -> None:
        self.view = view

    def team_view(self, agents: list[str]) -> TeamView:
        return self.view


def test_a_bad_plays_action_names_the_player_and_the_value():
    with pytest.raises(ValueError, match=r"left_2: action value 5 \(direction\) is nan"):
        BallPlay().skill_actions(_view(), {"left_2": np.array([0, 0, 0, 0, 1.0, np.nan])})
    with pytest.raises(ValueError, match=r"left_2: action of shape \(4,\), expected \(6,\)"):
        BallPlay().skill_actions(_view(), {"left_2": np.zeros(4)})


@needs_ode
@pytest.mark.parametrize("direction", [0.0, 0.5])
def test_playing_the_ball_walks_it_the_way_asked(direction):
    """From a random start, the ball 0.5 m from the player, 20 s of play along the line to the
    goal and 90° to its left (``benchmarks/ball_play.py``'s episode)."""
    from ball_play import episode

    travel, error = episode(seed=0, direction=direction, seconds=20.0)
    assert travel > 3.0
    assert abs(error) < 20.0


def test_a_team_option_plays_is_checked_and_gives_plays_actions():
    assert scenario_options("game-2v2")["plays"] is False
    assert scenario_options("game-2v2", {"plays": True})["plays"] is True
    with pytest.raises(ValueError, match="game-2v2: plays must be true or false, got 'yes'"):
        scenario_options("game-2v2", {"plays": "yes"})


TEAM_ACTIONS = pytest.mark.parametrize(
    ("option", "action"),
    [("plays", [0.0, 0.0, 0.0, -1.0, 1.0, 0.0]), ("over_scripted", [0.0, 0.0, 0.0, 0.0])],
)
"""A team's own kinds of action, each with an action of it: plays actions (the ball straight at
the goal), residuals over the scripted team (none)."""


@needs_ode
@TEAM_ACTIONS
def test_a_team_with_its_own_actions_trains_and_plays_against_its_snapshots(
    tmp_path, option, action
):
    """A team game with ``plays`` takes six values a player, with ``over_scripted`` four; the
    pool's snapshots of such a team act with them too (their actions become skill actions
    before the game takes them)."""
    import gymnasium as gym
    from stable_baselines3.common.policies import ActorCriticPolicy

    from robocup_gym.soccer.learnt import PolicyTeam
    from robocup_gym.train.selfplay import (
        OpponentPool,
        SelfPlaySettings,
        make_team_vec_env,
        snapshot_policy,
    )

    options = {option: True, "max_cycles": 200}
    game = TeamGame("game-1v1", lambda rng: StandingTeam(), options)
    obs_space = game.observation_space
    assert game.action_space.shape == (len(action),)
    assert len(action) == (len(PLAY_ACTION_LABELS) if option == "plays" else 4)
    game.close()
    policy = ActorCriticPolicy(
        obs_space, gym.spaces.Box(-1.0, 1.0, (len(action),), np.float32), lr_schedule=lambda _: 0.0
    )
    snapshot_policy(policy, tmp_path, 100)
    pool = OpponentPool(tmp_path, SelfPlaySettings(scripted_share=0.0))
    venv = make_team_vec_env("game-1v1", 1, options=options, pool=pool, kind="dummy")
    try:
        venv.reset()
        view = venv.block.envs[0]
        assert isinstance(view.opponent, PolicyTeam) and view.opponent.options[option]
        assert view.opponent._to_skills is not None  # its actions become skill actions
        for _ in range(5):
            venv.step(np.tile([action], (venv.num_envs, 1)))
    finally:
        venv.close()


@needs_ode
@TEAM_ACTIONS
def test_a_team_with_its_own_actions_plays_the_ball_on_serve(option, action):
    """A team that acts with plays actions (here: always the ball straight at the goal), or
    with residuals over the scripted team (here: none), plays through ``robocup-gym serve``
    from its own perceptors: its actions become skill actions from what the team sees, and the
    ball goes toward the other goal. The game is the same on every run of one machine (a sync
    server and the team seeded, the kick-off sent in a fixed cycle)."""
    seen = _play_on_serve(option, action, seed=0, heads=(heads := []))
    assert len(seen) == 125, len(seen)  # 25 s of play, a decision every 10 cycles
    # a walking player holds its head tilted down (the ball at its feet stays in view)
    assert abs(np.median(heads) - HEAD_TILT_DEG) < 2.0, np.median(heads)
    # the ball pushed toward the right team's goal (+x): 6.7 m (plays) and 4.2 m (residuals)
    # here; 1.0-13.1 m over team seeds 0-8 for each (with the head held level instead of
    # tilted down: 0.07-11.4 m, the ball lost from view at the feet; joined at the start)
    farthest = max(b[0] for b in seen)
    assert farthest - seen[0][0] > 0.3, seen


@needs_ode
def test_a_seeded_team_plays_the_same_game_twice_on_a_seeded_sync_serve():
    """The players join in fixed cycles whatever the machine's load, and the skills draw from
    the team's seed: the same game twice, to the last bit of what the team sees."""
    action = [0.0, 0.0, 0.0, -1.0, 1.0, 0.0]
    first = _play_on_serve("plays", action, seed=1, seconds=10.0)
    again = _play_on_serve("plays", action, seed=1, seconds=10.0)
    assert len(first) == len(again) == 50
    np.testing.assert_array_equal(np.array(first), np.array(again))
    other = _play_on_serve("plays", action, seed=2, seconds=10.0)
    assert not np.array_equal(np.array(first), np.array(other))  # the seed matters


def _play_on_serve(
    option: str,
    action: list[float],
    seed: int,
    heads: list[float] | None = None,
    seconds: float = 25.0,
) -> list[np.ndarray]:
    """Where a team of two (keeper and field player) that always takes ``action`` sees the
    ball at each of its decisions in the first ``seconds`` of play on a seeded ``serve`` in
    sync mode, alone on the field (joined once the ball has settled), kick-off sent after 50
    cycles; the walking players' head pitch (deg) at those decisions into ``heads``."""
    from robocup_gym.protocol import trainer as trainer_cmds
    from robocup_gym.protocol.framing import connect
    from robocup_gym.server.bench import start_server_process, stop_server_process
    from robocup_gym.soccer.learnt import PolicyTeam
    from robocup_gym.soccer.match import SETTLE_CYCLES, _sends_at_cycle, _wait_frames
    from robocup_gym.soccer.remote import ServerTeam

    seen: list[np.ndarray] = []

    def at_the_goal(x: np.ndarray) -> np.ndarray:
        return np.tile(action, (len(x), 1))

    policy = PolicyTeam(at_the_goal, 1, "at-the-goal", {option: True})

    class Watched:
        """The policy team, noting where its team sees the ball at each decision."""

        privileged = False  # observations without ground truth, as a learnt team's

        def __call__(self, env, agents, obs=None):
            view = env.team_view(agents)
            if view.play_mode == "PlayOn":
                seen.append(np.asarray(view.ball, dtype=float).copy())
                if heads is not None:
                    heads.extend(
                        p.last.joint("hj2")
                        for p, mode in zip(env.players, env.skills.modes(), strict=True)
                        if mode == "walk"
                    )
            return policy(env, agents, obs)

    proc, agent_port, monitor_port = start_server_process(
        "--sync", "--no-real-time", "--seed", "5", "--monitor-interval", "1"
    )
    monitor = None
    try:
        monitor = connect("127.0.0.1", monitor_port)
        _wait_frames(monitor, SETTLE_CYCLES)  # the ball settles and sleeps before the team joins
        kickoff_after_50 = _sends_at_cycle(monitor, 50, trainer_cmds.play_mode("PlayOn"))
        with ServerTeam(Watched(), port=agent_port, name="A", players=2, seed=seed) as team:
            assert team.side == "left"
            team.play(seconds=seconds + 1.5, on_cycle=kickoff_after_50)
    finally:
        if monitor is not None:
            monitor.close()
        stop_server_process(proc)
    return seen[: round(seconds / 0.2)]


@needs_ode
def test_the_ball_play_benchmark_reports_travel_and_direction(run_benchmark):
    res, lines = run_benchmark("ball_play.py", "--episodes", 1, "--seconds", 4)
    assert res["episodes"] == 3 and len(lines) == 3  # one start, three directions
    assert set(res) >= {"ball_travel_median_m", "direction_error_deg_median", "on_course_rate"}
    assert 0.0 <= res["moved_rate"] <= 1.0 and 0.0 <= res["on_course_rate"] <= 1.0

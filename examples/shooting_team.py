"""A team of your own from the scripted team and a motion skill: the scripted team, whose field
player shoots at the goal with ``approach-kick`` when it is behind a free ball, plays 2-against-2
games against the scripted team.

    python examples/shooting_team.py --games 20

The team names the game it plays in its ``options`` (as a learnt team's record): the motion
skills the teams may start (``("kick", "approach-kick")``) and the omnidirectional walk the
approach was made for (``"walk"``); ``play_match`` sets the game up from them. A team is any
callable ``team(env, agents, obs) -> {agent: skill action}``; the scripted team's actions are
fitted to the game's layout (``env.skill_action_labels``), so this team only sets the
``approach-kick`` values of its shooter. An approach takes ~10 s: the shooter keeps asking for
the motion until the ball moves, and stops it (the scripted dribble takes over) when an
opponent comes near the ball or the ball leaves it.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from robocup_gym.soccer.match import GameResult, play_match
from robocup_gym.soccer.motions import kick_to_values
from robocup_gym.soccer.scripted import ScriptedTeam

FREE_M = 2.5
"""A ball with no opponent within this distance (m) is free: the shooter may start."""
CONTESTED_M = 1.0
"""An opponent this near the ball (m) stops a shot before the kick."""
REACH_M = 1.5
"""The shooter starts from within this distance of the ball (m), behind it, …"""
LEAVE_M = 2.5
"""… and stops when the ball is farther than this (m)."""
AIM_Y_M = 0.55
"""It aims this far to the side of the middle of the goal (m), away from a goalkeeper there."""
MOVED_M = 0.3
"""A shot is over once the ball is this far from where it lay when it started (m): kicked, or
played by another (the approach follows a ball that moves less)."""
MAX_TURN_DEG = 45.0
"""``approach-kick``'s directions: within this of the heading when it starts."""


class ShootingTeam(ScriptedTeam):
    """The scripted team; its field players shoot with ``approach-kick`` from behind a free
    ball (the game must list ``approach-kick`` among its skills)."""

    name = "shooting"

    def __init__(self) -> None:
        super().__init__()
        self.options = {"skills": ("kick", "approach-kick"), "walk": "walk"}
        """The game it plays: the motion skills it may start and the walk the approach was
        made for (``play_match`` sets the game up from a team's ``options``)."""
        self.shooting: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        """Each shooter's ``approach-kick`` values, which it keeps asking for, and where the
        ball was when it started."""
        self.shots = 0
        """Approaches started."""
        self._game_time = 0.0

    def __call__(self, env, agents, obs=None):
        out = super().__call__(env, agents, obs)
        if not agents:
            return out
        if env.game.referee.game_time < self._game_time:  # a new game: no shot goes on
            self.shooting.clear()
        self._game_time = env.game.referee.game_time
        view = env.team_view(agents)
        at = env.skill_action_labels.index("approach-kick")
        nearest_opponent = min(
            (float(np.hypot(*(o - view.ball))) for o in view.opponents), default=math.inf
        )
        for a in agents:
            if a in view.keepers:
                continue
            to_ball = float(np.hypot(*(view.ball - view.positions[a])))
            if a in self.shooting:
                values, ball = self.shooting[a]
                moved = float(np.hypot(*(view.ball - ball))) > MOVED_M
                if moved or to_ball > LEAVE_M or nearest_opponent < CONTESTED_M:
                    del self.shooting[a]  # kicked, or the scripted action stops the approach
                else:
                    out[a][at : at + 3] = values
                continue
            shot = self._shot(view, a, to_ball, nearest_opponent)
            if shot is not None:
                self.shooting[a] = (shot, view.ball.copy())
                self.shots += 1
                out[a][at : at + 3] = shot
        return out

    def _shot(self, view, agent, to_ball, nearest_opponent) -> np.ndarray | None:
        """The ``approach-kick`` values of a shot by ``agent`` now, or ``None``."""
        keeper_side = [o[1] for o in view.opponents if abs(o[0] - view.goal[0]) < 3.0]
        side = -np.sign(keeper_side[0]) if keeper_side else np.sign(view.ball[1])
        aim = view.goal + np.array([0.0, AIM_Y_M * (side or 1.0)]) - view.ball
        distance = float(np.hypot(*aim))
        behind = float(np.dot(view.ball - view.positions[agent], aim / distance))
        if to_ball > REACH_M or behind < 0.2 or nearest_opponent < FREE_M:
            return None
        c, s = view.headings[agent]
        turn = math.degrees(math.atan2(aim[1], aim[0]) - math.atan2(s, c))
        turn = (turn + 180.0) % 360.0 - 180.0
        if abs(turn) > MAX_TURN_DEG:
            return None
        return np.array([1.0, *kick_to_values(min(distance + 2.5, 10.0), turn)])


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--games", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args()
    team = ShootingTeam()

    def on_game(k: int, game: GameResult) -> None:
        print(f"game {k}: {game.goals_for}:{game.goals_against} ({team.shots} shots so far)")

    result = play_match(team, "scripted", games=args.games, seed=args.seed, on_game=on_game)
    print(json.dumps(result.summary))


if __name__ == "__main__":
    main()

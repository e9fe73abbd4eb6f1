"""RoboCup 3D soccer as multi-agent environments (PettingZoo): one module per scenario, each
with ``env()`` (AEC) and ``parallel_env()`` (Parallel).

* :mod:`~robocup_gym.soccer.penalty_v1`: one striker against one goalkeeper;
* :mod:`~robocup_gym.soccer.keepaway_v1`: two attackers keep the ball from one defender;
* :mod:`~robocup_gym.soccer.game_v1`: N against N (1–11), the full field and rules.

Their first versions (``penalty_v0``, ``keepaway_v0``, ``game_v0``) stay: their walk skill saw
the torso's orientation in the world frame (a player facing −x walked askew), and ``game_v0``'s
kick-offs and set pieces waited for the drop ball.

They run in-process on the world of the single-agent environments with the referee of
``robocup-gym serve`` (:mod:`robocup_gym.sim.referee`), with joint-level actions or skills as
actions (:mod:`~robocup_gym.soccer.skills`: the shipped walk and get-up policies, the scripted
kick and any registered motion skill). :mod:`~robocup_gym.soccer.scripted` has the scripted
teams, :mod:`~robocup_gym.soccer.match` plays matches (``robocup-gym match``). Needs
``pettingzoo`` (the ``soccer`` extra).
"""

SCENARIOS = ("penalty_v1", "keepaway_v1", "game_v1", "penalty_v0", "keepaway_v0", "game_v0")
"""The scenario modules of this package."""

"""The league's current simulator, RCSSServerMJ, in-process: its own simulation classes stepped
exactly as its server steps them (:class:`~robocup_gym.sim.engines.rcsssmj.world.LeagueWorld`).
Needs the optional ``rcsssmj`` package (``pip install robocup-gym[mj]``)."""

from robocup_gym.sim.engines.rcsssmj.world import LeagueSimulationError, LeagueWorld, PDCommand

__all__ = ["LeagueSimulationError", "LeagueWorld", "PDCommand"]

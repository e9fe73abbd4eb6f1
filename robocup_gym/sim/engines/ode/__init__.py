"""SimSpark's physics on the Open Dynamics Engine itself (the engine rcssserver3d runs on): the
reference the MuJoCo world is compared with. Needs the system library ``libode``."""

from robocup_gym.sim.engines.ode.lib import OdeUnavailableError, available
from robocup_gym.sim.engines.ode.surfaces import mix_surfaces
from robocup_gym.sim.engines.ode.world import OdeWorld

__all__ = ["OdeUnavailableError", "OdeWorld", "available", "mix_surfaces"]

"""The MuJoCo engine: the SimSpark Nao world translated onto MuJoCo (``world.World``; its scene
in ``scene``, its per-cycle work in C in ``cstep.c``). Fast; matches slow motions and walking,
not impacts."""

from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError, World

__all__ = ["SimulationDivergedError", "World"]

"""The SimSpark Nao world, in-process, over two physics engines.

``make_world(engine="ode")`` (the default) is SimSpark's own step on the Open Dynamics Engine
(:class:`robocup_gym.sim.engines.ode.OdeWorld`): what rcssserver3d runs, reproduced to rounding.
``make_world(engine="mujoco")`` is the fast approximation
(:class:`robocup_gym.sim.engines.mujoco.world.World`).
Both have the same interface for placing robots and the ball, commanding joints (rad/s), stepping
20 ms cycles and perceiving as rcssserver3d sends it; game state, hearing, vision and perception
are one implementation (:mod:`robocup_gym.sim.senses`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["ENGINES", "SimulationDivergedError", "make_world"]

ENGINES = ("ode", "mujoco")
"""The physics engines, default first."""


class SimulationDivergedError(RuntimeError):
    """The physics produced NaN/inf or the engine reported an instability; call the world's
    ``reset``."""


def make_world(robot_types: Sequence[int] = (0,), *, engine: str = "ode", **options: Any):
    """A world with one robot per entry of ``robot_types`` (Nao types 0–4) on ``engine``.

    ``options`` are those of the engine's world class (``dead_time_cycles``, ``vision``,
    ``seed``, ``compiled``; MuJoCo also ``teams`` and ``physics``).

    Raises:
        ValueError: an unknown engine (naming the engines).
        robocup_gym.sim.engines.ode.OdeUnavailableError: ``engine="ode"`` without a suitable libode
            (the message says how to install it).
    """
    if engine == "ode":
        from robocup_gym.sim.engines.ode import OdeWorld

        return OdeWorld(robot_types, **options)
    if engine == "mujoco":
        from robocup_gym.sim.engines.mujoco.world import World

        return World(robot_types, **options)
    raise ValueError(f"unknown engine {engine!r}; engines: {', '.join(map(repr, ENGINES))}")

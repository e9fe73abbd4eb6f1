"""SimSpark's contact handlers and its rule for mixing two of them (reference §7.3, §7.4): what
ODE gets for each pair of surfaces that touch."""

from __future__ import annotations

from dataclasses import dataclass

from robocup_gym.sim.engines.ode import lib as ode

__all__ = [
    "BALL_SURFACE",
    "GROUND_SURFACE",
    "ROBOT_SURFACE",
    "WALL_SURFACE",
    "Surface",
    "mix_surfaces",
    "surface_parameters",
]


@dataclass(frozen=True)
class Surface:
    """One contact handler's surface settings (reference §7.3); ``None`` = that mode is off."""

    bounce: tuple[float, float] | None
    """(restitution, minimum approach speed m/s)."""
    soft_erp: float | None
    soft_cfm: float | None
    slip: float | None
    """Force-dependent slip, m/s per N (both friction directions)."""


ROBOT_SURFACE = Surface(bounce=None, soft_erp=0.6, soft_cfm=1e-4, slip=0.005)
"""Every robot part and foot (contact-joint and touch-perceptor handlers)."""
BALL_SURFACE = Surface(bounce=(0.8, 0.8), soft_erp=0.5, soft_cfm=0.05, slip=0.6)
GROUND_SURFACE = Surface(bounce=None, soft_erp=0.2, soft_cfm=None, slip=0.005)
WALL_SURFACE = Surface(bounce=(0.8, 2.0), soft_erp=None, soft_cfm=None, slip=None)
"""The default handler of walls and goals (not built here; kept for the mixing table)."""


def _mix(a, b):
    if a is None:
        return b
    if b is None:
        return a
    if isinstance(a, tuple):
        return tuple((x + y) / 2 for x, y in zip(a, b, strict=True))
    return (a + b) / 2


def mix_surfaces(a: Surface, b: Surface) -> Surface:
    """The contact parameters SimSpark gives a pair: a mode enabled on both sides averages the
    two values, on one side takes that side's value, on neither stays off (reference §7.3)."""
    return Surface(
        bounce=_mix(a.bounce, b.bounce),
        soft_erp=_mix(a.soft_erp, b.soft_erp),
        soft_cfm=_mix(a.soft_cfm, b.soft_cfm),
        slip=_mix(a.slip, b.slip),
    )


def surface_parameters(s: Surface) -> ode.SurfaceParameters:
    """ODE's ``dSurfaceParameters`` for a mixed surface (μ = ∞, as every SimSpark handler)."""
    p = ode.SurfaceParameters()
    p.mu = ode.INFINITY
    mode = 0
    if s.bounce is not None:
        mode |= ode.CONTACT_BOUNCE
        p.bounce, p.bounce_vel = s.bounce
    if s.soft_erp is not None:
        mode |= ode.CONTACT_SOFT_ERP
        p.soft_erp = s.soft_erp
    if s.soft_cfm is not None:
        mode |= ode.CONTACT_SOFT_CFM
        p.soft_cfm = s.soft_cfm
    if s.slip is not None:
        mode |= ode.CONTACT_SLIP1 | ode.CONTACT_SLIP2
        p.slip1 = p.slip2 = s.slip
    p.mode = mode
    return p

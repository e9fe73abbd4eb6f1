"""Physics settings of the embedded world and where each number comes from.

SimSpark steps ODE once per 20 ms cycle with the exact big-matrix solver (``dWorldStep``). The
embedded world does the same: **one MuJoCo step of 20 ms per cycle**, every constraint row
translated from ODE's ERP/CFM formulation to MuJoCo's soft-constraint parameters so that both
solve the same regularised problem (:func:`ode_solref`, :func:`ode_impedance`). Commands, drag
forces and the accelerometer sample are applied once per cycle, as in SimSpark (reference §7.7).
``docs/reference/engines.md`` derives the mapping and lists every known difference from SimSpark.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

CYCLE_S = 0.02
"""One agent cycle = one SimSpark physics step, s."""
GRAVITY = 9.81
"""m/s² (reference §7.1)."""
SURFACE_LAYER = 0.001
"""ODE contact surface layer (m): resting bodies sink this deep into the ground (reference §7.1).

ODE makes a contact as soon as two geoms overlap, but its normal row pushes them apart only by
what exceeds this layer (target separation speed ``erp·max(depth − layer, 0)/h``); within the
layer the contact still stops further approach and, with SimSpark's μ = ∞, its friction rows
hold at full strength. The world reproduces this by shifting each contact row's reference
acceleration every step (``World._surface_layer``)."""
GROUND_PLANE_Z = 0.0
"""Height of the ground's collision plane, m (z = 0, as in SimSpark)."""
UNBOUNDED_FRICTION = 1e4
"""Coulomb μ that stands for SimSpark's μ = ∞ (every contact handler keeps ODE's ``dInfinity``,
reference §7.3): ODE's friction rows are then unbounded and act whatever the normal force, even on a
contact that carries none (a toe resting within the surface layer). MuJoCo bounds friction by
μ times the normal force; with this μ its elliptic cone still transmits the full viscous
friction of a contact with a near-zero normal force (μ = 10 let a hopping robot's toe slide
where ODE's stays put)."""

BALL_RADIUS = 0.042
BALL_REST_Z = BALL_RADIUS - SURFACE_LAYER
"""Height of the centre of a ball resting on the ground, m (0.041: radius 0.042, sunk 1 mm)."""
BALL_MASS = 0.026
BALL_LINEAR_DRAG = 0.01
"""N·s/m (reference §5)."""
BALL_ANGULAR_DRAG = 0.00005
"""N·m·s/rad (reference §5)."""
BALL_ROLLING_TIME_S = (
    (1.0 + 2.0 / 5.0) * BALL_MASS / (BALL_LINEAR_DRAG + BALL_ANGULAR_DRAG / BALL_RADIUS**2)
)
"""Time constant of a ball rolling on the ground, s (0.95): it rolls without slipping (μ = ∞),
so its inertia is that of a solid sphere, m (1 + 2/5), and both drags brake it, the angular one
as a force ``BALL_ANGULAR_DRAG``·v / r²; its speed decays as exp(−t / this)."""


def ball_rest_point(pos: Sequence[float], vel: Sequence[float]) -> np.ndarray:
    """Where a ball rolling on the ground at ``pos`` (m) with velocity ``vel`` (m/s) comes to
    rest, (x, y) m: ``pos`` + ``vel`` × :data:`BALL_ROLLING_TIME_S` (the drags' exponential
    decay; a ball in the air is treated as rolling at its horizontal velocity)."""
    return np.array([pos[0] + vel[0] * BALL_ROLLING_TIME_S, pos[1] + vel[1] * BALL_ROLLING_TIME_S])


BODY_LINEAR_DRAG = 0.01
"""Drag on every robot body, N·s/m (reference §7.5)."""
BODY_ANGULAR_DRAG = 0.01
"""Angular drag on every robot body, N·m·s/rad (reference §7.5)."""
MOTOR_MAX_TORQUE = 10.0
"""ODE motor FMax of every hinge, N·m (reference §2.4)."""
MOTOR_FUDGE_FACTOR = 1e-5
"""ODE's hinge fudge factor (reference §2.4): at a stop the motor row gives way to a constant
torque, the full FMax into the stop, or this fraction of it when the target pulls away from the
stop."""
JOINT_STOP_BOUNCE = 1.0
"""Restitution of the hinge stops (reference §2.4): a joint that runs into a stop leaves it with the
speed it arrived at."""

BALL_RESTITUTION = 0.8
"""Ball contact bounce (reference §5); ODE applies it above 0.8 m/s approach speed."""
BALL_BOUNCE_MIN_SPEED = 0.8
"""Approach speed above which ODE applies the ball's restitution, m/s."""

MAX_IMPEDANCE = 0.9999
"""MuJoCo's largest constraint impedance (``mjMAXIMP``): the hardest row it allows."""


def finite_force(force: Sequence[float]) -> tuple[float, float, float]:
    """``force`` (N, world x, y, z) as three finite floats, for the worlds'
    ``set_torso_force``.

    Raises:
        ValueError: it is not three finite numbers.
    """
    try:
        f = np.asarray(force, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        f = np.zeros(0)
    if f.shape != (3,) or not np.isfinite(f).all():
        raise ValueError(f"a force is three finite numbers (N, world x, y, z), got {force!r}")
    return (float(f[0]), float(f[1]), float(f[2]))


def ode_impedance(cfm: float, inv_weight: float, h: float = CYCLE_S) -> float:
    """MuJoCo impedance ``d`` of a row that is as soft as an ODE row with constraint force mixing
    ``cfm`` (m/s per N at step ``h``).

    ODE adds ``cfm / h`` to the diagonal of the constraint matrix; MuJoCo adds the regulariser
    ``R = (1 − d)/d · A`` with ``A`` its approximation of that diagonal (``inv_weight``, 1/kg or
    1/(kg·m²)). Equal regularisers give ``d = A / (A + cfm/h)``.
    """
    r = cfm / h
    d = inv_weight / (inv_weight + r) if inv_weight > 0 else MAX_IMPEDANCE
    return min(max(d, 1e-4), MAX_IMPEDANCE)


def ode_solref(erp: float, d: float, *, restitution: float = 0.0, h: float = CYCLE_S) -> tuple:
    """Direct MuJoCo ``solref = (−k, −b)`` of an ODE contact/limit row with error reduction
    ``erp`` and restitution ``restitution`` solved with impedance ``d``.

    ODE asks the row velocity after the step to be ``−erp·pos/h − e·v`` (``pos`` the signed
    distance, ``v`` the approach velocity), i.e. a reference acceleration
    ``a = −(1 + e)/h · v − erp/h² · pos``. MuJoCo's direct form gives
    ``a = −b/d · v − k/d · pos`` for a row of constant impedance ``d``, hence
    ``b = (1 + e)·d/h`` and ``k = erp·d/h²``.
    """
    return (-erp * d / (h * h), -(1.0 + restitution) * d / h)


# ODE mixed contact parameters (reference §7.4) as (soft ERP, soft CFM).
ROBOT_GROUND_ERP_CFM = (0.40, 1e-4)
"""Robot part ↔ ground (robot 0.6 mixed with the ground's 0.2; CFM from the robot side)."""
ROBOT_SLIP = 0.005
"""ODE force-dependent slip of robot contacts, m/s per N."""
JOINT_STOP_ERP_CFM = (0.8, 1e-8)
"""Hinge stops (reference §2.4)."""
BALL_GROUND_ERP_CFM = (0.35, 0.05)
BALL_ROBOT_ERP_CFM = (0.55, 0.02505)
BALL_WALL_ERP_CFM = (0.50, 0.05)


@dataclass(frozen=True)
class PhysicsConfig:
    """MuJoCo settings of the embedded world (defaults are the documented choice).

    Attributes:
        timestep: MuJoCo step, s; ``CYCLE_S`` must be a whole multiple of it. Default: one step
            per cycle, as SimSpark's single ``dWorldStep(0.02)``.
        solver: MuJoCo solver. ``"Newton"`` solves the regularised problem exactly (as ODE's
            big-matrix LCP solver does) in a few iterations.
        iterations, ls_iterations, tolerance: Newton solver limits. A random-flailing robot
            needs 6 iterations on average and up to ~40; an unconverged solve can diverge, so
            the cap is well above that (it costs nothing when not reached).
        motor_impedance: impedance of the velocity-motor rows: ODE's motor row has CFM 1e-8,
            i.e. MuJoCo's hardest row (0.9999). Softer rows solve faster (0.99: half the
            iterations) but let the other joints of a chain yield: a knee then reaches only
            ~70 % of a commanded step in velocity, and the scripted kick changes completely.
        jacobian: MuJoCo constraint Jacobian layout; sparse is faster here (each motor row has
            one non-zero).
        robot_friction: Coulomb μ of robot contacts. ODE uses μ = ∞ with force-dependent slip;
            the slip is modelled by the friction rows' regulariser (``impratio``), the cone is
            only there for MuJoCo and so wide that it never binds (:data:`UNBOUNDED_FRICTION`).
        ball_friction: Coulomb μ ball–anything (ODE μ = ∞ + slip 0.30, see ``robot_friction``).
        impratio: MuJoCo's frictional-to-normal regulariser ratio; ``cfm/slip`` of the
            robot contacts (1e-4 / 0.005) gives ODE's force-dependent slip for them.
    """

    timestep: float = CYCLE_S
    solver: str = "Newton"
    iterations: int = 100
    ls_iterations: int = 50
    tolerance: float = 1e-8
    ls_tolerance: float = 0.01
    motor_impedance: float = MAX_IMPEDANCE
    robot_friction: float = UNBOUNDED_FRICTION
    ball_friction: float = UNBOUNDED_FRICTION
    impratio: float = ROBOT_GROUND_ERP_CFM[1] / ROBOT_SLIP
    jacobian: str = "sparse"

    @property
    def substeps(self) -> int:
        """MuJoCo steps per 20 ms cycle."""
        n = round(CYCLE_S / self.timestep)
        if n < 1 or abs(n * self.timestep - CYCLE_S) > 1e-9:
            raise ValueError(f"timestep {self.timestep} s must divide the 0.02 s cycle")
        return n

    def solref(self, erp: float, d: float, *, restitution: float = 0.0) -> tuple:
        """:func:`ode_solref` at this config's timestep."""
        return ode_solref(erp, d, restitution=restitution, h=self.timestep)

    def impedance(self, cfm: float, inv_weight: float) -> float:
        """:func:`ode_impedance` at this config's timestep."""
        return ode_impedance(cfm, inv_weight, h=self.timestep)

    def ode_row(
        self, erp: float, cfm: float, inv_weight: float, restitution: float = 0.0
    ) -> tuple[tuple[float, float], float]:
        """``(solref, impedance)`` of an ODE row with ``erp``/``cfm`` on a body of inverse
        weight ``inv_weight``: :meth:`impedance` and :meth:`solref` together."""
        d = self.impedance(cfm, inv_weight)
        return self.solref(erp, d, restitution=restitution), d

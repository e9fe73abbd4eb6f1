"""Physics settings of the embedded world and where each number comes from.

SimSpark steps ODE once per 20 ms cycle with the exact big-matrix solver. MuJoCo needs a finer
timestep for the same contacts, so one 20 ms agent cycle is ``substeps`` MuJoCo steps. Commands,
drag forces and the accelerometer sample are applied once per cycle, as in SimSpark (spec §7.7).
``docs/physics.md`` lists every knowing difference from SimSpark and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

CYCLE_S = 0.02
"""One agent cycle = one SimSpark physics step, s."""
GRAVITY = 9.81
"""m/s² (spec §7.1)."""
SURFACE_LAYER = 0.001
"""ODE contact surface layer (m): resting bodies sink this deep into the ground (spec §7.1).
Reproduced by placing the ground's collision plane this far below z = 0."""

BALL_RADIUS = 0.042
BALL_MASS = 0.026
BALL_LINEAR_DRAG = 0.01
"""N·s/m (spec §5)."""
BALL_ANGULAR_DRAG = 0.00005
"""N·m·s/rad (spec §5)."""
BODY_LINEAR_DRAG = 0.01
"""Drag on every robot body, N·s/m (spec §7.5)."""
BODY_ANGULAR_DRAG = 0.01
"""Angular drag on every robot body, N·m·s/rad (spec §7.5)."""
MOTOR_MAX_TORQUE = 10.0
"""ODE motor FMax of every hinge, N·m (spec §2.4)."""

BALL_RESTITUTION = 0.8
"""Ball contact bounce (spec §5); ODE applies it above 0.8 m/s approach speed."""
BALL_BOUNCE_MIN_SPEED = 0.8
"""Approach speed above which ODE applies the ball's restitution, m/s."""


def damping_ratio_for_restitution(e: float) -> float:
    """Damping ratio ζ of a linear spring-damper contact with coefficient of restitution ``e``."""
    le = math.log(e)
    return -le / math.sqrt(math.pi**2 + le * le)


def spring_from_ode(erp: float, cfm: float, h: float = CYCLE_S) -> tuple[float, float]:
    """ODE (ERP, CFM) at step ``h`` → equivalent (k N/m, c N·s/m) per contact row (spec §7.4)."""
    return erp / (h * cfm), (1 - erp) / cfm


@dataclass(frozen=True)
class PhysicsConfig:
    """MuJoCo settings of the embedded world (defaults are the documented choice).

    Attributes:
        timestep: MuJoCo step, s; ``CYCLE_S`` must be a whole multiple of it.
        iterations: Newton solver iterations per step.
        robot_friction: Coulomb μ for robot contacts. ODE uses μ = ∞ with force-dependent slip
            (slip 0.005 m/s per N per row); a Nao cannot push hard enough sideways to slide at
            μ = 2, so this behaves the same while staying well conditioned.
        ball_friction: Coulomb μ ball–anything. ODE: μ = ∞ + slip 0.30 → a kicked ball starts to
            roll within a few ms; μ = 1 converts sliding to rolling within ~0.05 s.
    """

    timestep: float = 0.005
    solver: str = "PGS"
    """Projected Gauss-Seidel: exact for the force-bounded motor rows. Newton diverged on them
    as soon as two robots (or one robot and a free ball in one island) were solved together."""
    iterations: int = 50
    tolerance: float = 1e-10
    """Solver tolerance: the stiff motor rows need a converged solve (with MuJoCo's default the
    solver stops early and the robot creeps and falls)."""
    ls_iterations: int = 50
    robot_friction: float = 2.0
    ball_friction: float = 1.0

    @property
    def substeps(self) -> int:
        """MuJoCo steps per 20 ms cycle."""
        n = round(CYCLE_S / self.timestep)
        if n < 1 or abs(n * self.timestep - CYCLE_S) > 1e-9:
            raise ValueError(f"timestep {self.timestep} s must divide the 0.02 s cycle")
        return n

    def robot_ground_solref(self) -> str:
        """Robot–ground: ODE k ≈ 2e5 N/m per row and heavy damping (ERP 0.4, CFM 1e-4) is stiffer
        than any stable MuJoCo contact at this timestep, so we use the stiffest stable one
        (time constant 2·timestep), critically damped: no bounce, as in SimSpark."""
        return f"{2 * self.timestep:.6g} 1"

    def ball_solref(self, erp: float, cfm: float, *, bouncy: bool = True) -> str:
        """Direct (negative) solref ``"-k/m -c/m"`` for a ball contact with ODE ``erp``/``cfm``.

        Stiffness per unit ball mass from the ODE spring equivalent. ODE's bounce mode imposes
        restitution 0.8 when the approach speed exceeds 0.8 m/s and otherwise leaves the
        (over-damped) ODE spring: ``bouncy=True`` gives the damping of a spring with restitution
        0.8, ``bouncy=False`` ODE's own damping.
        """
        k, c = spring_from_ode(erp, cfm)
        k_acc = k / BALL_MASS
        if bouncy:
            b_acc = 2 * damping_ratio_for_restitution(BALL_RESTITUTION) * math.sqrt(k_acc)
        else:
            # ODE's damping is over-critical (ζ ≈ 2); MuJoCo's explicit reference acceleration is
            # unstable for b·timestep > 2, so it is capped at critical damping (no bounce either).
            b_acc = min(c / BALL_MASS, 2 * math.sqrt(k_acc))
        return f"{-k_acc:.6g} {-b_acc:.6g}"

    def ball_solref_values(self, erp: float, cfm: float, *, bouncy: bool) -> tuple[float, float]:
        """:meth:`ball_solref` as numbers (for switching a contact pair at run time)."""
        a, b = self.ball_solref(erp, cfm, bouncy=bouncy).split()
        return float(a), float(b)


# ODE mixed contact parameters (spec §7.4).
BALL_GROUND_ERP_CFM = (0.35, 0.05)
BALL_ROBOT_ERP_CFM = (0.55, 0.02505)
BALL_WALL_ERP_CFM = (0.50, 0.05)

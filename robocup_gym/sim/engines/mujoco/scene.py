"""Assemble the MJCF of a world: field, goals, walls, ball and any number of Naos.

Geometry from reference §6 (field 30 × 20 m, goals 2.1 × 0.6 × 0.8 m at x = ±15, walls) and §5
(ball).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from robocup_gym.robot.mjcf import robot_xml, self_collision_excludes
from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.field import FIELD_LINES, GOAL_BOXES, WALLS
from robocup_gym.sim.physics import (
    BALL_GROUND_ERP_CFM,
    BALL_MASS,
    BALL_RADIUS,
    BALL_RESTITUTION,
    BALL_ROBOT_ERP_CFM,
    GROUND_PLANE_Z,
    JOINT_STOP_ERP_CFM,
    MOTOR_MAX_TORQUE,
    ROBOT_GROUND_ERP_CFM,
    PhysicsConfig,
)

FIELD_LENGTH = 30.0
FIELD_WIDTH = 20.0
GOAL_WIDTH = 2.1
GOAL_DEPTH = 0.6
GOAL_HEIGHT = 0.8

TEAM_COLOURS = {"left": "0.2 0.4 0.95 1", "right": "0.95 0.3 0.2 1", None: "0.5 0.5 0.5 1"}


@dataclass(frozen=True)
class RobotSlot:
    """One robot in the scene: its name prefix, robot type and team (for colours)."""

    prefix: str
    type_index: int = 0
    team: str | None = "left"


def _box(name: str, pos, size, rgba: str = "0.9 0.9 0.9 1", cls: str = "static") -> str:
    half = " ".join(f"{s / 2:.6g}" for s in size)
    p = " ".join(f"{x:.6g}" for x in pos)
    return (
        f'    <geom name="{name}" type="box" pos="{p}" size="{half}" class="{cls}" rgba="{rgba}"/>'
    )


def scene_xml(robots: list[RobotSlot], physics: PhysicsConfig | None = None) -> str:
    """The complete MJCF of a world with ``robots`` (may be empty), ball and field."""
    ph = physics or PhysicsConfig()
    ball_robot = _solref_str(ph, *BALL_ROBOT_ERP_CFM, 1.0 / BALL_MASS, BALL_RESTITUTION)
    ball_ground = _solref_str(ph, *BALL_GROUND_ERP_CFM, 1.0 / BALL_MASS, 0.0)
    # robot rows: a first guess of the impedance; apply_ode_softness() sets it per body
    robot = _solref_str(ph, *ROBOT_GROUND_ERP_CFM, 1.0, 0.0)
    stop_erp, stop_cfm = JOINT_STOP_ERP_CFM
    d_stop = ph.impedance(stop_cfm, 1.0)
    limit_ref = " ".join(f"{v:.6g}" for v in ph.solref(stop_erp, d_stop))
    dm = ph.motor_impedance
    bodies, excludes, pairs, sensors, frp = [], [], [], [], []
    for slot in robots:
        bodies.append(
            robot_xml(slot.prefix, slot.type_index, accent=TEAM_COLOURS.get(slot.team, ""))
        )
        excludes.append(self_collision_excludes(slot.prefix, nao_model(slot.type_index)))
        sensors.extend(_drag_sensors(slot))
        frp.extend(_frp_sensors(slot))
    sensors.extend(frp)  # after every robot's drag sensors (World reads those as one block)
    walls = [_box(name, pos, size, "0.5 0.5 0.5 1") for name, pos, size in WALLS]
    goals = [_box(name, pos, size) for name, pos, size in GOAL_BOXES]
    pairs.append(
        f'    <pair geom1="ball" geom2="ground" condim="3" '
        f'friction="{ph.ball_friction} {ph.ball_friction} 0.005 0.0001 0.0001" '
        f'solref="{ball_ground[0]}" solimp="{ball_ground[1]}"/>'
    )
    return f"""<mujoco model="robocup_gym">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{ph.timestep}" gravity="0 0 -9.81" integrator="Euler"
          solver="{ph.solver}" iterations="{ph.iterations}" ls_iterations="{ph.ls_iterations}"
          ls_tolerance="{ph.ls_tolerance}" tolerance="{ph.tolerance}" cone="elliptic"
          impratio="{ph.impratio}" jacobian="{ph.jacobian}">
    <flag autoreset="disable"/>
  </option>
  <size memory="16M"/>
  <visual>
    <global offwidth="1280" offheight="720"/>
    <quality shadowsize="2048"/>
  </visual>
  <default>
    <default class="robot">
      <geom condim="3" friction="{ph.robot_friction} 0.005 0.0001"
            solref="{robot[0]}" solimp="{robot[1]}" group="1"/>
    </default>
    <default class="visual">
      <geom contype="0" conaffinity="0" group="3" mass="0"/>
    </default>
    <default class="robot_joint">
      <joint limited="true" solreflimit="{limit_ref}" solimplimit="{d_stop:.6g} {d_stop:.6g} 0.001"
             frictionloss="{MOTOR_MAX_TORQUE}" solreffriction="{2 * ph.timestep:.6g} 1"
             solimpfriction="{dm:.6g} {dm:.6g} 0.001"/>
    </default>
    <default class="static">
      <geom condim="3" friction="{ph.robot_friction} 0.005 0.0001" solmix="0"
            solref="{robot[0]}" solimp="{robot[1]}" group="0"/>
    </default>
  </default>
  <asset>
    <texture name="grass" type="2d" builtin="checker" rgb1="0.2 0.55 0.2" rgb2="0.22 0.6 0.22"
             width="512" height="512"/>
    <material name="grass" texture="grass" texrepeat="15 10"/>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.6 0.75 0.95" rgb2="0.2 0.3 0.5"
             width="256" height="256"/>
  </asset>
  <worldbody>
    <light pos="-10 10 10" dir="0.5 -0.5 -1" diffuse="0.8 0.8 0.8"/>
    <light pos="10 -10 10" dir="-0.5 0.5 -1" diffuse="0.4 0.4 0.4"/>
    <geom name="ground" type="plane" pos="0 0 {GROUND_PLANE_Z}" size="25 25 0.1"
          material="grass" class="static" contype="4" conaffinity="1"/>
{chr(10).join(walls)}
{chr(10).join(goals)}
    <body name="ball" pos="0 0 {BALL_RADIUS}">
      <freejoint name="ball"/>
      <geom name="ball" type="sphere" size="{BALL_RADIUS}" mass="{BALL_MASS}" priority="1"
            contype="2" conaffinity="1" condim="3" friction="{ph.ball_friction} 0.005 0.0001"
            solref="{ball_robot[0]}" solimp="{ball_robot[1]}" rgba="1 0.9 0.9 1"/>
    </body>
{chr(10).join(bodies)}
  </worldbody>
  <contact>
{chr(10).join(pairs)}
{chr(10).join(excludes)}
  </contact>
  <sensor>
{chr(10).join(sensors)}
  </sensor>
</mujoco>
"""


FRP_GEOMS = {"rf": "rfoot", "lf": "lfoot", "rf1": "rtoe", "lf1": "ltoe"}
"""Force resistance perceptor name → the robot geom (= body) it measures (reference §4.6)."""


def frp_sensor_name(prefix: str, perceptor: str) -> str:
    """Name of the MuJoCo contact sensor behind a robot's ``FRP`` perceptor."""
    return f"{prefix}frp_{perceptor}"


def _frp_sensors(slot: RobotSlot) -> list[str]:
    """The force resistance perceptors (reference §4.6) as MuJoCo contact sensors, one per foot (and
    toe, type 4): ``reduce="netforce"`` sums the forces of all the geom's contacts of the step
    and reports them at the force-magnitude-weighted mean of the contact points, which is
    exactly SimSpark's ``FRP`` (``f`` and ``c``, world frame here; the world turns them into the
    foot frame). The foot is ``geom2``, so the force is the one acting on the foot. MuJoCo
    evaluates them after the constraint solve in ``mj_step2``, in C."""
    feet = ["rf", "lf"] + (["rf1", "lf1"] if nao_model(slot.type_index).robot_type.has_toes else [])
    p = slot.prefix
    return [
        f'    <contact name="{frp_sensor_name(p, f)}" geom2="{p}{FRP_GEOMS[f]}" '
        f'data="found force pos" reduce="netforce" num="1"/>'
        for f in feet
    ]


def _drag_sensors(slot: RobotSlot) -> list[str]:
    """Velocity sensors the body drag is computed from (reference §7.5): per robot body, in body
    order, the linear then the angular velocity of its centre of mass in world coordinates
    (``objtype="body"`` is the body's inertial frame). MuJoCo evaluates them in ``mj_step1``,
    so the drag of a cycle costs the world one vector operation."""
    out = []
    for b in nao_model(slot.type_index).bodies:
        name = slot.prefix + b.name
        out.append(f'    <framelinvel name="{name}_v" objtype="body" objname="{name}"/>')
        out.append(f'    <frameangvel name="{name}_w" objtype="body" objname="{name}"/>')
    return out


def _solref_str(
    ph: PhysicsConfig, erp: float, cfm: float, inv_weight: float, restitution: float
) -> tuple[str, str]:
    """(solref, solimp) attribute strings of an ODE row (see :mod:`robocup_gym.sim.physics`)."""
    (k, b), d = ph.ode_row(erp, cfm, inv_weight, restitution)
    return f"{k:.8g} {b:.8g}", f"{d:.8g} {d:.8g} 0.001"


def apply_ode_softness(model: mujoco.MjModel, physics: PhysicsConfig) -> None:
    """Give every robot geom the impedance that makes its ground contacts exactly as soft as
    ODE's (CFM 1e-4 at that body's inverse weight, ERP 0.4); see :func:`ode_impedance`.

    MuJoCo's regulariser is relative to its approximation of the constraint matrix diagonal, the
    body's inverse weight, which is known only once the model is compiled."""
    erp, cfm = ROBOT_GROUND_ERP_CFM
    robot = model.geom_group == 1
    for g in range(model.ngeom):
        if not robot[g]:
            continue
        solref, d = physics.ode_row(erp, cfm, float(model.body_invweight0[model.geom_bodyid[g], 0]))
        model.geom_solimp[g, :3] = (d, d, 0.001)
        model.geom_solref[g] = solref


def _field_lines_xml() -> list[str]:
    """White field lines as thin visual-only boxes (rendering only; vision uses the line table)."""
    out = []
    for i, (a, b) in enumerate(FIELD_LINES):
        ax, ay = a
        bx, by = b
        cx, cy = (ax + bx) / 2, (ay + by) / 2
        length = math.hypot(bx - ax, by - ay)
        yaw = math.atan2(by - ay, bx - ax)
        out.append(
            f'    <geom name="line{i}" type="box" pos="{cx:.5g} {cy:.5g} 0.0005" '
            f'size="{length / 2:.5g} 0.025 0.0005" euler="0 0 {yaw:.6g}" class="visual" '
            f'rgba="1 1 1 1"/>'
        )
    return out

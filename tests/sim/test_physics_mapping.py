"""The ODE → MuJoCo constraint mapping (robocup_gym.sim.physics) and the motor rows."""

import mujoco
import numpy as np
import pytest

from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.physics import CYCLE_S, PhysicsConfig, ode_impedance, ode_solref
from robocup_gym.sim.vision import VisionConfig


def standing_world(n_cycles: int = 10) -> World:
    w = World([0], vision=VisionConfig(noise=False), seed=0)
    w.place_robot(0, -1.0, 0.0)
    w.place_ball((3.0, 2.0))
    for _ in range(n_cycles):
        w.step({0: np.zeros(22)})
    mujoco.mj_forward(w.model, w.data)
    return w


def test_ode_impedance_and_solref_formulas():
    # d = A / (A + cfm/h); equal regularisers
    a, cfm = 38.46, 0.05
    d = ode_impedance(cfm, a)
    assert (1 - d) / d * a == pytest.approx(cfm / CYCLE_S)
    assert ode_impedance(1e-12, 1.0) == phys.MAX_IMPEDANCE  # capped at MuJoCo's hardest row
    # k = erp·d/h², b = (1+e)·d/h  →  reference acceleration −(1+e)/h·v − erp/h²·pos at imp d
    k, b = ode_solref(0.4, 0.99, restitution=0.8)
    assert -k / 0.99 == pytest.approx(0.4 / CYCLE_S**2)
    assert -b / 0.99 == pytest.approx(1.8 / CYCLE_S)
    assert PhysicsConfig().substeps == 1
    with pytest.raises(ValueError, match="divide"):
        _ = PhysicsConfig(timestep=0.003).substeps


def test_contact_rows_are_as_soft_as_odes():
    """MuJoCo's regulariser R of each contact row equals ODE's CFM/h, the friction rows' R
    equals ODE's force-dependent slip/h, and the reference pulls with ODE's ERP."""
    w = standing_world()
    m, d = w.model, w.data
    ground = m.geom("ground").id
    ball = m.geom("ball").id
    seen = set()
    for i in range(d.ncon):
        c = d.contact[i]
        if ground not in c.geom:
            continue
        row = c.efc_address
        k, b, imp, _ = d.efc_KBIP[row]
        if ball in c.geom:
            seen.add("ball")
            erp, cfm = phys.BALL_GROUND_ERP_CFM
        else:
            seen.add("robot")
            erp, cfm = phys.ROBOT_GROUND_ERP_CFM
            # friction rows: R = slip / h
            assert d.efc_R[row + 1] == pytest.approx(phys.ROBOT_SLIP / CYCLE_S, rel=1e-6)
        assert d.efc_R[row] == pytest.approx(cfm / CYCLE_S, rel=1e-6)
        assert k * imp == pytest.approx(erp / CYCLE_S**2, rel=1e-6)
        assert b == pytest.approx(1.0 / CYCLE_S, rel=1e-6)  # no bounce at rest
    assert seen == {"ball", "robot"}


def test_resting_ball_sinks_like_odes_spring():
    """ODE: 1 mm surface layer + the ball's own 0.73 mm spring sag (k = 350 N/m)."""
    w = standing_world(50)
    sag = phys.BALL_MASS * phys.GRAVITY / 350.0
    expected = phys.BALL_RADIUS - phys.SURFACE_LAYER - sag
    assert w.ball_position()[2] == pytest.approx(expected, abs=2e-4)


def test_motor_rows_lead_the_constraint_list_in_dof_order():
    w = standing_world()
    d = w.data
    dofs = np.sort(w.robots[0].qvel_joints)
    n = len(dofs)
    assert (d.efc_type[:n] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF).all()
    np.testing.assert_array_equal(d.efc_id[:n], dofs)
    assert d.efc_type[n] != mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF


def test_unloaded_motor_reaches_its_target_in_one_step_and_torque_is_bounded():
    w = World([0], dead_time_cycles=0, vision=VisionConfig(noise=False))
    w.place_robot(0, -1.0, 0.0)
    for _ in range(3):
        w.step({0: np.zeros(22)})
    i = w.robots[0].model.effector_names.index("lae1")  # shoulder: light load
    v = np.zeros(22)
    v[i] = 5.0
    w.step({0: v})
    assert w.joint_velocities(0)[i] == pytest.approx(5.0, rel=1e-3)
    # a knee bend of the standing leg needs more than 10 N·m: the rows saturate exactly there
    k = w.robots[0].model.effector_names.index("rle4")
    v = np.zeros(22)
    v[k] = -6.0
    w.step({0: v})
    forces = w.data.efc_force[:22]
    assert np.abs(forces).max() <= phys.MOTOR_MAX_TORQUE * (1 + 1e-9)
    assert np.isclose(np.abs(forces), phys.MOTOR_MAX_TORQUE, rtol=1e-6).any()


def test_robot_state_moves_between_worlds():
    a = World([0], vision=VisionConfig(noise=False))
    b = World([0], vision=VisionConfig(noise=False))
    for w in (a, b):
        w.place_robot(0, -1.0, 0.0)
    i = a.robots[0].model.effector_names.index("lae1")
    v = np.zeros(22)
    v[i] = 2.0
    a.command(0, v)
    a.step()
    a.step()  # after the dead time the command is the motor target
    assert a.robots[0].targets[i] == 2.0
    state = a.export_robot_state(0)
    b.place_robot(0, -1.0, 0.0, joint_angles_deg=a.joint_angles_deg(0))  # the pose moves too
    b.import_robot_state(0, state)
    before = b.joint_angles_deg(0)[i]
    b.step()
    b.step()
    # the imported target drives the new world's motor (arrays stay views into the world's)
    assert b.joint_angles_deg(0)[i] - before == pytest.approx(np.degrees(2.0 * 0.04), abs=0.3)
    assert b.robots[0].targets is not state["targets"]


def test_full_teams_of_mixed_types_build_and_stand():
    types = [0, 1, 2, 3, 4] * 4 + [0, 1]
    w = World(types, teams=["left"] * 11 + ["right"] * 11, vision=VisionConfig(noise=False))
    for _ in range(50):
        w.step()
    assert w.n_robots == 22
    assert all(w.torso_up(i)[2] > 0.99 for i in range(22))

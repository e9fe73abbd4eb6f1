"""What the world relies on in MuJoCo's internals, asserted on whichever MuJoCo is installed.

The joint motors (robocup_gym/sim/engines/mujoco/world.py, robocup_gym/robot/mjcf.py) are MuJoCo
dof friction-loss
rows whose reference acceleration the world shifts between ``mj_step1`` and ``mj_step2``. That needs
the rows first in the constraint list and in dof order (also checked at every World construction),
a row per dof with non-zero ``dof_frictionloss`` only (the world drops a motor's row at a stop by
zeroing it) and ``mj_step2`` solving with the ``efc_aref`` left by ``mj_step1`` and the world. Run
this file with every supported MuJoCo version (docs/reference/engines.md §2.7).
"""

import mujoco
import numpy as np
import pytest

import robocup_gym.sim.engines.mujoco.world as world_module
from robocup_gym.sim import physics as phys
from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.vision import VisionConfig

FRICTION_DOF = mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF


def settled_world(**kw) -> World:
    w = World([0], vision=VisionConfig(noise=False), seed=0, **kw)
    w.place_robot(0, -1.0, 0.0)
    w.place_ball((3.0, 2.0))
    for _ in range(3):
        w.step({0: np.zeros(22)})
    return w


def test_installed_mujoco_is_a_supported_version():
    major, minor = (int(x) for x in mujoco.__version__.split(".")[:2])
    assert (major, minor) >= (3, 4), mujoco.__version__


def test_step2_solves_with_the_reference_acceleration_set_after_step1():
    w = settled_world(dead_time_cycles=0)
    m, d = w.model, w.data
    dofs = w._motor_dofs_sorted
    n = len(dofs)
    r = w.robots[0]
    k = int(np.flatnonzero(dofs == r.qvel_joints[r.effector_names.index("lae1")])[0])
    mujoco.mj_step1(m, d)
    assert (d.efc_type[:n] == FRICTION_DOF).all()
    d.efc_aref[k] += w._motor_b[k] * 5.0  # shoulder motor row: target 5 rad/s instead of 0
    expected = d.efc_aref[:n].copy()
    mujoco.mj_step2(m, d)
    np.testing.assert_array_equal(d.efc_aref[:n], expected)  # not recomputed by mj_step2
    assert d.qvel[dofs[k]] == pytest.approx(5.0, rel=1e-2)  # and the solver used it


def test_a_motor_without_friction_loss_has_no_row_and_the_others_keep_dof_order():
    w = settled_world()
    m, d = w.model, w.data
    dofs = w._motor_dofs_sorted
    n = len(dofs)
    try:
        m.dof_frictionloss[dofs[3]] = 0.0
        mujoco.mj_forward(m, d)
        assert (d.efc_type[: n - 1] == FRICTION_DOF).all()
        np.testing.assert_array_equal(d.efc_id[: n - 1], np.delete(dofs, 3))
        assert d.efc_type[n - 1] != FRICTION_DOF
    finally:
        m.dof_frictionloss[dofs] = phys.MOTOR_MAX_TORQUE


def test_world_construction_rejects_a_constraint_layout_it_cannot_drive(monkeypatch):
    """An equality constraint's rows precede the friction-loss rows: the world must refuse it
    rather than shift the wrong rows' reference accelerations."""
    scene_xml = world_module.scene_xml

    def with_equality(slots, physics):
        extra = '  <equality><joint joint1="r0_he1"/></equality>\n</mujoco>'
        return scene_xml(slots, physics).replace("</mujoco>", extra)

    monkeypatch.setattr(world_module, "scene_xml", with_equality)
    with pytest.raises(RuntimeError, match=r"MuJoCo .*not the first constraint rows"):
        World([0])


def test_construction_check_leaves_the_reset_state():
    a = World([0], vision=VisionConfig(noise=False), seed=3)
    state = a.state()
    a.reset(seed=3)
    np.testing.assert_array_equal(a.state(), state)
    assert not a.data.qvel.any()

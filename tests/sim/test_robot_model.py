"""The Nao tables and the generated MJCF match the spec for every robot type."""

import math

import mujoco
import numpy as np
import pytest

from robocup_gym.robot.nao import nao_model, wire_perceptor_order
from robocup_gym.robot.types import is_type_number, robot_type
from robocup_gym.sim.engines.mujoco.scene import RobotSlot, scene_xml

SOLE = {0: 0.385, 1: 0.42164, 2: 0.385, 3: 0.440737, 4: 0.385}
COM = {
    0: (0, 0.0163, -0.0788),
    1: (0, 0.0200, -0.0880),
    3: (0, 0.0220, -0.0928),
    4: (0, 0.0155, -0.0789),
}


@pytest.mark.parametrize("t", range(5))
def test_mass_joints_and_geometry_per_type(t):
    m = nao_model(t)
    assert m.total_mass == pytest.approx(4.6071, abs=1e-6)
    n = 24 if t == 4 else 22
    assert len(m.joints) == n
    assert len(set(m.effector_names)) == n
    assert m.sole_height() == pytest.approx(SOLE[t], abs=1e-5)
    if t in COM:
        assert m.center_of_mass() == pytest.approx(COM[t], abs=1e-4)
    assert sorted(m.perceptor_names) == sorted(wire_perceptor_order(t))


def test_joint_table_values_type0():
    m = nao_model(0)
    rle1 = m.joint("rle1")
    assert rle1.perceptor == "rlj1"
    assert rle1.axis == pytest.approx((-math.sqrt(0.5), 0, math.sqrt(0.5)))
    assert (rle1.min_deg, rle1.max_deg) == (-90, 1)
    assert m.joint("lle2").min_deg == -25 and m.joint("rle2").min_deg == -45
    assert m.joint("rle4").anchor == pytest.approx((0.055, -0.005, -0.235))
    assert m.joint("rle6").anchor == pytest.approx((0.055, -0.005, -0.34))
    assert m.joint("he1").max_speed == pytest.approx(6.13954, abs=1e-5)
    assert m.joint("rle5").max_speed == pytest.approx(6.1395)
    assert all(j.max_torque == 10.0 for j in m.joints)


def test_type_differences():
    assert nao_model(2).joint("lle5").max_speed == pytest.approx(8.80667)
    assert nao_model(2).joint("lle6").max_speed == pytest.approx(3.47234)
    assert nao_model(3).joint("rle1").anchor[0] == pytest.approx(0.072954143)
    t4 = nao_model(4)
    assert t4.joint("rle7").anchor == pytest.approx((0.055, 0.069482, -0.385), abs=1e-5)
    assert t4.body("rfoot").mass + t4.body("rtoe").mass == pytest.approx(0.2)
    assert t4.joint("rle6").anchor[1] == pytest.approx(-0.022759, abs=1e-5)


def test_inertias_match_spec_table():
    m = nao_model(0)
    assert m.body("torso").inertia == pytest.approx((4.300e-3, 4.300e-3, 2.029e-3), rel=1e-3)
    assert m.body("neck").inertia == pytest.approx((4.498e-5, 4.498e-5, 5.400e-6), rel=1e-3)
    assert m.body("rshank").inertia == pytest.approx((3.188e-4, 3.469e-4, 2.119e-4), rel=1e-3)


def test_type_numbers_are_integers_0_to_4():
    """The one check of a Nao type number (EnvConfig's robot_type, GetUp's script_robot_type)."""
    assert all(is_type_number(t) for t in (0, 4, np.int64(2)))
    assert not any(is_type_number(t) for t in (5, -1, 2.0, True, "1", None))


def test_bad_type():
    with pytest.raises(ValueError, match="robot type"):
        robot_type(7)
    with pytest.raises(KeyError, match="valid effector names"):
        nao_model(0).joint("xyz")


@pytest.mark.parametrize("t", range(5))
def test_mjcf_compiles_with_spec_masses_and_limits(t):
    model = mujoco.MjModel.from_xml_string(scene_xml([RobotSlot("r0_", t)]))
    nao = nao_model(t)
    mass = sum(model.body(f"r0_{b.name}").mass[0] for b in nao.bodies)
    assert mass == pytest.approx(4.6071, abs=1e-6)
    for j in nao.joints:
        jid = model.joint(f"r0_{j.effector}").id
        assert np.degrees(model.jnt_range[jid]) == pytest.approx([j.min_deg, j.max_deg])
        assert model.jnt_axis[jid] == pytest.approx(np.array(j.axis) / np.linalg.norm(j.axis))
    assert model.geom("ball").size[0] == pytest.approx(0.042)
    assert model.body("ball").mass[0] == pytest.approx(0.026)

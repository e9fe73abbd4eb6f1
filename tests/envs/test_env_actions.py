"""Action modes move joints the commanded way; bad actions are clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_gym.envs import ActionMode


def _arm_env(make_env, mode, **kw):
    # shoulder pitches: free to move whatever the legs do
    return make_env(
        controlled_joints=("lae1", "rae1"),
        action_mode=mode,
        terminate_on_fall=False,
        max_episode_steps=200,
        **kw,
    )


def _angles(env):
    a = env.joint_angles_deg
    names = env.robot_model.effector_names
    return a[names.index("lae1")], a[names.index("rae1")]


@pytest.mark.parametrize(
    "mode, up",
    [
        ("velocity", [0.6, -0.6]),
        ("target_angle", [0.5, -0.5]),  # targets +60° / -60° from 0
        ("target_angle_max_speed", [0.5, 1.0, -0.5, 1.0]),
    ],
)
def test_each_mode_moves_joints_in_the_commanded_direction(make_env, mode, up):
    env = _arm_env(make_env, mode)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array(up, dtype=np.float32))
    left, right = _angles(env)
    assert left > 5.0 and right < -5.0
    # and back the other way
    back = -np.array(up, dtype=np.float32)
    if mode == "target_angle_max_speed":
        back[1::2] = 1.0
    for _ in range(15):
        env.step(back)
    left2, right2 = _angles(env)
    assert left2 < left - 5.0 and right2 > right + 5.0


def test_velocity_mode_scales_to_each_joints_max_speed(make_env):
    env = _arm_env(make_env, "velocity")
    env.reset(seed=0)
    for _ in range(4):
        env.step(np.array([0.5, -0.25], dtype=np.float32))
    vmax = env.robot_model.max_speeds[env.robot_model.effector_names.index("lae1")]
    q = env.joint_velocities
    names = env.robot_model.effector_names
    assert q[names.index("lae1")] == pytest.approx(0.5 * vmax, rel=0.05)
    assert q[names.index("rae1")] == pytest.approx(-0.25 * vmax, rel=0.05)


def test_target_angle_mode_reaches_the_target(make_env):
    env = _arm_env(make_env, "target_angle")
    env.reset(seed=0)
    # lae1 range [-120, 120]: 0.5 -> +60°, -0.25 -> -30°
    for _ in range(40):
        env.step(np.array([0.5, -0.25], dtype=np.float32))
    left, right = _angles(env)
    assert left == pytest.approx(60.0, abs=1.0)
    assert right == pytest.approx(-30.0, abs=1.0)


def test_target_angles_stay_off_the_stops(make_env):
    """A full action drives a joint to ``target_stop_margin_deg`` inside its stop, never onto it
    (where rcssserver3d ignores the joint's next command on a difference of rounding); with a
    margin of 0 onto it; a margin out of range is refused."""
    from robocup_gym.envs import EnvConfigError

    env = _arm_env(make_env, "target_angle")
    env.reset(seed=0)
    for _ in range(40):
        env.step(np.array([1.0, -1.0], dtype=np.float32))
    left, right = _angles(env)
    assert env.config.target_stop_margin_deg == 0.5
    assert left == pytest.approx(119.5, abs=0.05) and right == pytest.approx(-119.5, abs=0.05)
    onto = _arm_env(make_env, "target_angle", target_stop_margin_deg=0.0)
    assert onto._actions.targets_deg(np.array([1.0, -1.0])) == pytest.approx([120.0, -120.0])
    for bad in (-0.1, 6.0, float("nan")):
        with pytest.raises(EnvConfigError, match="target_stop_margin_deg"):
            _arm_env(make_env, "target_angle", target_stop_margin_deg=bad)


def test_target_angle_max_speed_limits_the_speed(make_env):
    env = _arm_env(make_env, "target_angle_max_speed")
    assert env.action_space.shape == (4,)
    assert env.action_labels == ["lae1/angle", "lae1/speed", "rae1/angle", "rae1/speed"]
    env.reset(seed=0)
    vmax = env.robot_model.max_speeds[2]
    # far target, speed action -0.5 -> limit 0.25 · vmax
    for _ in range(6):
        env.step(np.array([1.0, -0.5, 0.0, 1.0], dtype=np.float32))
    names = env.robot_model.effector_names
    speed = env.joint_velocities[names.index("lae1")]
    assert speed == pytest.approx(0.25 * vmax, rel=0.05)
    # speed action -1 -> limit 0: the joint stops
    for _ in range(4):
        env.step(np.array([1.0, -1.0, 0.0, 1.0], dtype=np.float32))
    assert abs(env.joint_velocities[names.index("lae1")]) < 0.05


def test_default_action_controls_all_but_the_head(make_env):
    env = make_env()
    assert env.action_mode is ActionMode.VELOCITY
    assert env.action_space.shape == (20,)
    assert not any(n.startswith("he") for n in env.controlled_joints)
    env4 = make_env(robot_type=4)
    assert env4.action_space.shape == (22,) and "rle7" in env4.controlled_joints


def test_uncontrolled_joints_are_held(make_env):
    env = make_env(
        controlled_joints=("lae1",), joint_start_deg={"rae1": 30.0}, terminate_on_fall=False
    )
    env.reset(seed=0)
    for _ in range(10):
        env.step(np.array([1.0], dtype=np.float32))
    _, right = _angles(env)
    assert right == pytest.approx(30.0, abs=1.0)


def test_out_of_range_actions_are_clipped(make_env):
    a, b = _arm_env(make_env, "velocity"), _arm_env(make_env, "velocity")
    a.reset(seed=0)
    b.reset(seed=0)
    for _ in range(3):
        a.step(np.array([5.0, -7.0], dtype=np.float32))
        b.step(np.array([1.0, -1.0], dtype=np.float32))
    np.testing.assert_allclose(a.joint_angles_deg, b.joint_angles_deg)


@pytest.mark.parametrize(
    "action, match",
    [
        (np.zeros(3), r"shape \(2,\).*got shape \(3,\)"),
        (np.zeros((1, 2)), r"shape \(2,\)"),
        (np.array([0.0, np.nan]), r"nan at index 1 \(rae1\)"),
        (np.array([np.inf, 0.0]), r"inf at index 0 \(lae1\)"),
        ("left", r"array of numbers"),
    ],
)
def test_bad_actions_raise_value_error(make_env, action, match):
    env = _arm_env(make_env, "velocity")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(action)


def test_action_noise_perturbs_the_command(make_env):
    env = _arm_env(make_env, "velocity", action_noise_std=0.3)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(2, dtype=np.float32))
    assert np.max(np.abs(_angles(env))) > 1.0  # a zero action alone would hold the arms at 0


def test_mirror_pairs_come_from_the_joint_axes():
    """A reflection across the sagittal plane turns a rotation about ``a`` by θ into one about
    ``M a`` by −θ: pitch joints (axis x) keep their sign, roll/yaw joints flip it; the right
    joint's range is then the left one's, mirrored."""
    from robocup_gym.robot.nao import nao_model

    for t in range(5):
        m = nao_model(t)
        signs = {m.joints[i].effector: s for i, _, s in m.mirror_pairs}
        assert signs == {
            "lae1": 1.0, "lae2": -1.0, "lae3": -1.0, "lae4": -1.0, "lle1": 1.0,
            "lle2": -1.0, "lle3": 1.0, "lle4": 1.0, "lle5": 1.0, "lle6": -1.0,
            **({"lle7": 1.0} if t == 4 else {}),
        }  # fmt: skip
        for i, k, s in m.mirror_pairs:
            assert m.joints[k].effector == "r" + m.joints[i].effector[1:]
            assert sorted(s * m.ranges_deg[i]) == pytest.approx(list(m.ranges_deg[k]))


@pytest.mark.parametrize("engine", ["mujoco", "ode"])
@pytest.mark.parametrize("mode", ["velocity", "target_angle"])
def test_mirrored_actions_move_the_robot_symmetrically(make_env, engine, mode):
    from robocup_gym.envs.tasks.getup import GetUp
    from robocup_gym.sim.engines.ode import available

    if engine == "ode" and not available():
        pytest.skip("no libode")
    # pose 0, the plain drop, is symmetric (the varied ones are not)
    env = make_env(GetUp, backend=engine, mirror_actions=True, action_mode=mode, lying_poses=1)
    assert env.action_space.shape == (10,)
    assert env.action_labels[0] == "lae1+rae1" and env.action_labels[-1] == "lle6+rle6"
    env.reset(seed=0, options={"start_side": "back"})
    rng = np.random.default_rng(3)
    for _ in range(60):
        env.step(rng.uniform(-1, 1, 10))
    q = env.perception.joint_angles_deg
    pairs = env.robot_model.mirror_pairs
    assert max(abs(q[i] - s * q[k]) for i, k, s in pairs) < 1e-3  # deg
    moved = max(abs(q[i]) for i, _, _ in pairs)
    assert moved > 10.0  # the joints did move, mirrored
    assert abs(env.ground_truth.torso_pos[1]) < 1e-4  # no sideways drift: the motion is symmetric
    toes = make_env(GetUp, backend=engine, mirror_actions=True, robot_type=4)
    assert toes.action_space.shape == (11,)


def test_mirrored_actions_are_refused_where_they_cannot_work(make_env):
    from robocup_gym.envs import EnvConfigError

    with pytest.raises(EnvConfigError, match="mirror_actions works on the Nao"):
        make_env(mirror_actions=True, action_mode="target_angle_max_speed")

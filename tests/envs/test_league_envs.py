"""The tasks on the league's robots (RCSSServerMJ's Booster T1 and K1), in-process: every
registered environment on every robot, the robots' defaults, the PD action modes, the command
timing and the clear errors. Skipped where the optional ``rcsssmj`` is not installed (CI has it)."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
import pytest

pytest.importorskip("rcsssmj", reason="the optional rcsssmj package is not installed")

from gymnasium.utils.env_checker import check_env

import robocup_gym.envs
from robocup_gym.backends import (
    BackendDivergedError,
    BackendNotAvailableError,
    RobotPose,
    make_backend,
)
from robocup_gym.envs import EnvConfigError, GetUp, VelocityKick, Walk
from robocup_gym.envs.observations import torso_axes
from robocup_gym.robot.league import (
    league_robot,
    league_robot_names,
)
from robocup_gym.types import AgentCommand, PDCommand

ROBOTS = tuple(league_robot_names())
"""Every robot the installed rcsssmj ships (0.2.1: K1, T1 and a MuJoCo ant)."""


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("env_id", robocup_gym.envs.REGISTERED_IDS)
def test_every_task_passes_check_env_on_every_league_robot(env_id, robot):
    env = gymnasium.make(env_id, robot=robot)
    try:
        check_env(env.unwrapped, skip_render_check=True)
        u = env.unwrapped
        assert u.backend.name == "rcsssmj" and u.robot_model.name == robot
        names = league_robot(robot).effector_names
        # every joint but the head's (he1, he2)
        assert env.action_space.shape == (sum(not n.startswith("he") for n in names),)
        obs, _ = env.reset(seed=3)
        assert np.isfinite(obs).all()
    finally:
        env.close()


def test_a_league_robot_takes_its_own_defaults_and_explicit_options_win():
    env = VelocityKick(robot="T1")
    c = env.config
    t1 = league_robot("T1")
    assert c.action_mode.value == "target_angle"
    assert "foot_force" not in c.observations and "joint_pos" in c.observations
    assert c.fall_height == pytest.approx(0.65 * t1.standing_torso_height, abs=1e-3)
    x, y = c.robot_start_pos
    # the ball rests in front of the right foot
    assert c.ball_start_pos[2] == pytest.approx(t1.ball_radius)
    assert c.ball_start_pos[1] == pytest.approx(y + t1.right_foot_offset[1])
    assert c.ball_start_pos[0] > x + t1.right_foot_offset[0] + t1.ball_radius
    _, info = env.reset(seed=0)
    assert info["torso_pos"][2] == pytest.approx(t1.standing_torso_height, abs=0.01)
    env.close()
    env = VelocityKick(robot="T1", fall_height=0.2, action_mode="torque")
    assert env.config.fall_height == 0.2 and env.config.action_mode.value == "torque"
    env.close()
    assert VelocityKick.default_config("K1").robot == "K1"


def test_bad_league_options_are_clear_errors():
    with pytest.raises(EnvConfigError, match=r"unknown robot 'T2'.*'nao'.*'T1'"):
        VelocityKick(robot="T2")
    with pytest.raises(EnvConfigError, match=r"action_mode 'velocity' is for the Nao.*'torque'"):
        VelocityKick(robot="T1", action_mode="velocity")
    with pytest.raises(EnvConfigError, match="'torque' is for the league's robots"):
        VelocityKick(action_mode="torque")
    with pytest.raises(EnvConfigError, match=r"foot_force.*FRP.*T1 has none"):
        VelocityKick(robot="T1", observations=("joint_pos", "foot_force"))
    with pytest.raises(BackendNotAvailableError, match=r"'rcsssmj' in-process.*not on 'ode'"):
        VelocityKick(robot="T1", engine="ode")
    with pytest.raises(EnvConfigError, match=r"unknown joint 'LKneePitch' in joint_start_deg"):
        VelocityKick(robot="T1", joint_start_deg={"LKneePitch": 10.0})
    env = VelocityKick(robot="T1")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action contains nan at index 3 \(lae4\)"):
        env.step(np.r_[np.zeros(3), np.nan, np.zeros(17)])
    env.close()
    backend = make_backend("rcsssmj", robot="T1")
    backend.reset_episode(RobotPose(0.0, 0.0), (1.0, 0.0))
    with pytest.raises(ValueError, match="PD joint commands"):
        backend.step(AgentCommand(np.zeros(23)))
    with pytest.raises(ValueError, match=r"unknown joint 'knee'"):
        backend.step(AgentCommand(joint_pd={"knee": PDCommand(0.0)}))
    with pytest.raises(ValueError, match="kp must be finite"):
        PDCommand(0.0, 0.0, math.inf)
    with pytest.raises(ValueError, match=r"target of lle4 \(Left_Knee_Pitch\) is -10°, outside"):
        backend.step(AgentCommand(joint_pd={"lle4": PDCommand(-10.0, 0.0, 20.0, 1.0)}))
    with pytest.raises(ValueError, match="gains of he1 must be >= 0"):
        backend.step(AgentCommand(joint_pd={"he1": PDCommand(0.0, 0.0, -1.0, 1.0)}))
    with pytest.raises(ValueError, match=r"torque of lle4 is 100 N·m, outside .* \[-60, 60\]"):
        backend.step(AgentCommand(joint_pd={"lle4": PDCommand(10.0, 0.0, 0.0, 0.0, 100.0)}))
    backend.step(AgentCommand(joint_pd={"lle4": PDCommand(10.0, 0.0, 20.0, 1.0)}))
    backend.close()


def _knee_after(mode: str, action_value: float, cycles: int = 15) -> float:
    # target angles over each joint's whole range (Walk's default spans the start pose ± 30°)
    env = Walk(robot="T1", action_mode=mode, terminate_on_fall=False, target_around_start_deg=None)
    env.reset(seed=0)
    a = np.zeros(env.action_space.shape)
    labels = env.action_labels
    k = next(i for i, n in enumerate(labels) if n.startswith("lle4"))
    a[k] = action_value
    if mode == "target_angle_gains":
        a[k + 1] = a[k + 2] = 0.0  # default gains
    for _ in range(cycles):
        env.step(a)
    knee = env.perception.joint("q_llj4")
    env.close()
    return knee


def test_pd_action_modes_drive_the_joint_where_they_say():
    lo, hi = league_robot("T1").joint("Left_Knee_Pitch").range_deg
    # target angle: +1 is the top of the range, -1 the bottom (0°: straight)
    bent = _knee_after("target_angle", 0.5)
    assert bent > 0.5 * (lo + hi) and bent > 60.0
    assert _knee_after("target_angle", -1.0) < 5.0
    assert _knee_after("target_angle_gains", 0.5) > 60.0
    # torque: positive torque bends the knee (its range is [0, 134]°), negative keeps it at 0
    assert _knee_after("torque", 0.5, cycles=10) > 20.0
    assert _knee_after("torque", -0.5, cycles=10) < 2.0
    env = Walk(robot="K1", action_mode="target_angle_gains")
    assert env.action_space.shape == (60,) and env.action_labels[:3] == [
        "lae1/angle",
        "lae1/kp",
        "lae1/kd",
    ]
    env.close()


def test_a_command_acts_after_one_cycle_as_on_the_server():
    b = make_backend("rcsssmj", robot="T1")
    hold = {n: PDCommand(0.0, 0.0, 100.0, 5.0) for n in b.robot_model.effector_names}
    b.reset_episode(RobotPose(0.0, 0.0), (2.0, 0.0))
    b.step(AgentCommand(joint_pd=hold))
    b.step(AgentCommand(joint_pd=hold))
    kick = dict(hold, he1=PDCommand(60.0, 0.0, 100.0, 5.0))
    first = b.step(AgentCommand(joint_pd=kick)).joint("q_hj1")
    second = b.step(AgentCommand(joint_pd=kick)).joint("q_hj1")
    third = b.step(AgentCommand(joint_pd=kick)).joint("q_hj1")
    assert abs(first) < 0.05  # the world stepped once more with the old command
    assert second > 1.0 and third > second  # then the head turns towards 60°
    b.close()


def test_seeded_resets_repeat_exactly():
    env = Walk(robot="T1", terminate_on_fall=False)
    runs = []
    for _ in range(2):
        obs, _ = env.reset(seed=5)
        rng = np.random.default_rng(0)
        trace = [obs]
        for _ in range(20):
            trace.append(env.step(rng.uniform(-1, 1, env.action_space.shape))[0])
        runs.append(np.array(trace))
    np.testing.assert_array_equal(runs[0], runs[1])
    env.close()


def test_walk_sees_the_feet_on_the_ground_and_getup_lies_on_the_side_asked():
    env = Walk(robot="T1")
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape))
    assert env.ground_truth.feet_contact == {"lf": True, "rf": True}
    env.close()
    env = GetUp(robot="K1")
    for side, sign in (("front", -1.0), ("back", 1.0)):
        _, info = env.reset(seed=0, options={"start_side": side})
        forward_z = torso_axes(env.ground_truth.torso_quat)[2]
        assert sign * forward_z > 0.7, (side, forward_z)  # facing the ground / the sky
        assert info["torso_pos"][2] < env.config.success_height and not env._is_up()
    assert env.config.success_height == pytest.approx(
        0.73 * league_robot("K1").standing_torso_height, abs=1e-3
    )
    assert env.config.height_cap == pytest.approx(
        1.04 * league_robot("K1").standing_torso_height, abs=1e-3
    )
    env.close()


def test_the_k1_ball_contact_failure_of_rcsssmj_is_a_clear_truncation():
    """rcsssmj 0.2.1 fails when the ball touches one of the K1's unnamed geometries; the backend
    reports it as a diverged episode with the reason, and the next reset works."""
    b = make_backend("rcsssmj", robot="K1")
    b.reset_episode(RobotPose(0.0, 0.0), (0.0, 0.0, 1.5))  # dropped onto the head
    with pytest.raises(BackendDivergedError, match="geometry has no name"):
        for _ in range(50):
            b.step(AgentCommand())
    p = b.reset_episode(RobotPose(0.0, 0.0), (2.0, 0.0))
    assert p.ground_truth.torso_pos[2] > 0.4
    b.step(AgentCommand())
    b.close()


def test_perceptions_made_from_objects_equal_the_parsed_messages():
    """The in-process backend reads rcsssmj's perception objects (with vision) or the sensor
    arrays (without) instead of writing and parsing the message: over 200 cycles (vision every
    second one) every value is the parsed one."""
    from robocup_gym.backends.league_backend import perception_from_objects
    from robocup_gym.protocol.league import parse_league_perception
    from robocup_gym.sim.engines.rcsssmj import LeagueWorld

    world = LeagueWorld([("T1", "A", 1)])
    names = league_robot("T1").perceptor_names
    rng = np.random.default_rng(0)
    seen = 0
    for _ in range(200):
        world.command(
            0,
            {
                n: PDCommand(float(rng.uniform(-20, 20)), 0.0, 20.0, 1.0)
                for n in world.effector_names(0)
            },
        )
        message = world.perceive()[0]
        a = parse_league_perception(message, names)
        b = perception_from_objects(world.agents[0].perceptions, names)
        r = world.readings(0)  # the vectorised reading the backend uses without vision
        np.testing.assert_array_equal(r["q_deg"], a.joint_angles_deg)
        np.testing.assert_array_equal(r["dq_deg_s"], a.joint_velocities_deg_s)
        np.testing.assert_array_equal([-r["gyro"][1], r["gyro"][0], r["gyro"][2]], a.gyro)
        np.testing.assert_array_equal([-r["accel"][1], r["accel"][0], r["accel"][2]], a.accel)
        np.testing.assert_array_equal(r["pos"], a.raw_torso_pos)
        np.testing.assert_array_equal(r["quat"], a.raw_torso_quat)
        assert r["time"] == a.time and r["game"].play_mode == a.game.play_mode
        for field in ("joint_angles_deg", "joint_velocities_deg_s", "gyro", "accel"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
        np.testing.assert_array_equal(a.raw_torso_pos, b.raw_torso_pos)
        np.testing.assert_array_equal(a.raw_torso_quat, b.raw_torso_quat)
        assert (a.time, a.game) == (b.time, b.game)
        assert (a.vision is None) == (b.vision is None)
        if a.vision is not None:
            seen += 1
            assert a.vision.objects.keys() == b.vision.objects.keys()
            for k in a.vision.objects:
                np.testing.assert_array_equal(a.vision.objects[k], b.vision.objects[k])
        world.step()
    assert seen == 100


def test_a_league_robot_renders_where_opengl_is():
    """``render()`` draws the league world from its own model (a child process, so that the
    OpenGL backend can be chosen; skipped without OpenGL)."""
    import os
    import subprocess
    import sys

    code = (
        "from robocup_gym.envs import VelocityKick\n"
        "e = VelocityKick(robot='T1', render_mode='rgb_array'); e.reset(seed=0)\n"
        "img = e.render(); e.close()\n"
        "assert img.shape == (360, 480, 3) and img.std() > 10, (img.shape, img.std())\n"
        "print('ok')\n"
    )
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    probe = "import mujoco; mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'), 8, 8)"
    if subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True).returncode:
        pytest.skip("no OpenGL for MuJoCo's offscreen renderer here (set MUJOCO_GL=egl/osmesa)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    # (MuJoCo 3.5 prints rcsssmj's join warning about controls to stdout first)
    assert out.returncode == 0 and out.stdout.strip().splitlines()[-1] == "ok", out.stderr[-2000:]


def test_the_training_assist_lifts_a_league_robot():
    """``TorsoAssist`` on the in-process league backend: the push acts through MuJoCo's
    ``xfrc_applied`` on the T1's torso, with the weight taken from its model."""
    from robocup_gym.envs.assist import TorsoAssist

    heights = {}
    for share in (0.0, 1.5):
        env = TorsoAssist(gymnasium.make("RobocupGym/GetUp-v0", robot="T1"), share, 10_000)
        try:
            assert env.weight_n == pytest.approx(league_robot("T1").total_mass * 9.81)
            assert 20.0 < league_robot("T1").total_mass < 60.0  # kg
            env.reset(seed=0, options={"start_side": "back"})
            z0 = float(env.unwrapped.ground_truth.torso_pos[2])
            for _ in range(30):
                env.step(np.zeros(env.action_space.shape))
            heights[share] = float(env.unwrapped.ground_truth.torso_pos[2]) - z0
        finally:
            env.close()
    # (zero actions are mid-range PD targets: the limbs move a little on their own)
    assert heights[1.5] > heights[0.0] + 0.3, heights


def test_mirrored_actions_are_the_naos_only():
    with pytest.raises(EnvConfigError, match="mirror_actions works on the Nao"):
        gymnasium.make("RobocupGym/GetUp-v0", robot="T1", mirror_actions=True)


def test_the_reference_gait_is_the_naos_only():
    env = Walk(robot="T1")
    assert env.config.reference_gait is False and env._gait is False
    env.close()
    with pytest.raises(EnvConfigError, match="reference_gait is a stepping pattern for the Nao"):
        Walk(robot="T1", reference_gait=True)

"""A player places itself and the ball from its own perceptors: the landmarks its vision sees,
its head joints, its accelerometer and gyroscope."""

import dataclasses
import math

import numpy as np
import pytest

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.engines.ode.world import OdeWorld
from robocup_gym.sim.pose import heading_to_quat
from robocup_gym.sim.rotations import axis_angle_quat, quat_multiply, quat_to_matrix
from robocup_gym.sim.vision import VisionConfig, polar
from robocup_gym.soccer.localisation import Localiser, head_frame_vector, locate


def _world(noise: bool) -> OdeWorld:
    w = OdeWorld([0], vision=VisionConfig(noise=noise), seed=1)
    w.set_team(0, "left", "A", 1)
    return w


def _errors(w: OdeWorld, rng: np.random.Generator, n: int, tilt_deg: float = 0.0):
    """Place the robot at ``n`` random poses (head turned, torso tilted by ``tilt_deg`` about a
    random horizontal axis) and localise from one See; yields (landmarks, position error m,
    heading error deg, ball error m) for each pose where a fix came."""
    for _ in range(n):
        x, y, h = rng.uniform(-13, 13), rng.uniform(-9, 9), rng.uniform(-180, 180)
        head = {"he1": rng.uniform(-60, 60), "he2": rng.uniform(-30, 30)}
        axis = (math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a), 0.0)
        quat = quat_multiply(axis_angle_quat(axis, math.radians(tilt_deg)), heading_to_quat(h))
        w.place_robot(0, x, y, z=0.5, joint_angles_deg=head, quat=quat)
        w.place_ball((x + rng.uniform(-2, 2), y + rng.uniform(-2, 2), 0.042))
        p = w.perceive(0, vision=True)
        # the accelerometer of a robot at rest: gravity, in the torso frame
        accel = quat_to_matrix(w.torso_quat(0)).T @ np.array([0.0, 0.0, 9.81])
        p = dataclasses.replace(p, accel=accel)
        loc = Localiser(nao_model(0))
        fix = loc.update(p)
        if fix is None:
            continue
        torso = w.torso_position(0)
        ball = None
        if loc.ball_xy is not None:
            ball = float(np.hypot(*(loc.ball_xy - p.ground_truth.ball_pos[:2])))
        yield (
            fix.landmarks,
            math.hypot(fix.x - torso[0], fix.y - torso[1]),
            abs((fix.heading_deg - h + 180.0) % 360.0 - 180.0),
            ball,
        )


def test_polar_coordinates_go_back_to_the_head_frame():
    rel = np.array([[0.3, 2.0, -0.4], [-1.0, 0.5, 0.2], [0.0, -3.0, 0.0]])
    for r, pol in zip(rel, polar(rel), strict=True):
        assert np.allclose(head_frame_vector(pol), r, atol=1e-12)


@pytest.mark.parametrize("tilt_deg", [0.0, 12.0])
def test_exact_vision_places_the_robot_and_the_ball_exactly(tilt_deg):
    """Without the server's noise: every pose with two or more landmarks in view is placed
    within 5 mm (the head's pitch moves its centre by up to 2.5 mm, which the fix does not
    model), its heading (of the torso untilted) to a hundredth of a degree, and the ball with
    it, whatever the head's turn and the torso's tilt."""
    results = list(_errors(_world(False), np.random.default_rng(0), 30, tilt_deg))
    assert len(results) >= 15 and all(r[0] >= 2 for r in results)
    for _, pos, heading, ball in results:
        assert pos < 5e-3 and heading < 0.02
        assert ball is None or ball < 5e-3
    assert sum(r[3] is not None for r in results) >= 5


def test_noisy_vision_places_the_robot_within_centimetres():
    """With rcssserver3d's noise (distance 0.0965 %, angles 0.15° and 0.12°, a 5 mm calibration
    offset per robot), one See."""
    results = list(_errors(_world(True), np.random.default_rng(1), 40))
    pos = np.array([r[1] for r in results])
    heading = np.array([r[2] for r in results])
    assert len(results) >= 20
    assert np.median(pos) < 0.05 and pos.max() < 0.3
    assert np.median(heading) < 0.5 and heading.max() < 2.0


def test_one_landmark_and_the_carried_heading_place_the_robot():
    head = np.zeros(3)
    # the robot at (2, 1) facing +y (heading 90°): a landmark 3 m ahead, 1 m to the left in its
    # level frame (x right, y forward) is at (1, 4) in the world
    offsets = {"G1L": np.array([-1.0, 3.0, 0.0])}
    fix = locate(offsets, head, heading_deg=90.0)
    g = (-15.0, 1.05)
    assert fix is not None and fix.landmarks == 1
    assert (fix.x, fix.y) == pytest.approx((g[0] + 1.0, g[1] - 3.0))
    assert locate(offsets, head) is None  # no heading carried: no fix
    assert locate({"B": np.array([0.0, 1.0, 0.0])}, head, heading_deg=0.0) is None


def test_the_gyroscope_turns_the_heading_between_sees():
    w = _world(False)
    w.place_robot(0, -5.0, 2.0, heading_deg=30.0)
    loc = Localiser(nao_model(0))
    fix = loc.update(w.perceive(0, vision=True))
    assert fix is not None and fix.heading_deg == pytest.approx(30.0, abs=0.01)
    p = dataclasses.replace(w.perceive(0, vision=False), gyro=np.array([0.0, 0.0, 50.0]))
    for _ in range(10):  # 0.2 s at 50 deg/s
        fix = loc.update(p)
    assert fix.heading_deg == pytest.approx(40.0, abs=0.01)
    assert (fix.x, fix.y) == pytest.approx((-5.0, 2.0), abs=2e-3)  # held
    assert loc.cycles_since_fix == 10
    loc.reset()
    assert loc.fix is None and loc.ball_xy is None


def test_the_estimate_follows_a_walking_robot():
    """The shipped walk at 0.5 m/s for 4 s on the default engine with the server's vision
    noise, four walks: the estimate's position, heading and velocity (leg odometry) against
    ground truth, their medians over every step (one walk's median position error ranges over
    3–15 cm with the noise's draw)."""
    from robocup_gym.backends import make_backend
    from robocup_gym.envs.observations import heading_frame
    from robocup_gym.soccer.localisation import Estimator
    from robocup_gym.train.pretrained import pretrained_env, pretrained_policy

    policy = pretrained_policy("walk")
    backend = make_backend("ode", vision=True)
    env = pretrained_env(policy, backend, {"command_change_steps": 0}).unwrapped
    pos, heading, vel = [], [], []
    try:
        for seed in range(1, 5):
            obs, _ = env.reset(seed=seed, options={"velocity_command": (0.5, 0.0, 0.0)})
            start = env.ground_truth
            est = Estimator(env.robot_model)
            c, s = heading_frame(start.torso_quat)
            est.place(start.torso_pos[0], start.torso_pos[1], math.degrees(math.atan2(s, c)))
            for _ in range(200):
                obs, *_ = env.step(policy(obs[None])[0])
                gt, e = env.ground_truth, est.update(env.perception)
                pos.append(float(np.hypot(*(e.torso_pos[:2] - gt.torso_pos[:2]))))
                (c1, s1), (c2, s2) = heading_frame(gt.torso_quat), heading_frame(e.torso_quat)
                heading.append(abs(math.degrees(math.atan2(c1 * s2 - s1 * c2, c1 * c2 + s1 * s2))))
                vel.append(float(np.hypot(*(e.torso_vel[:2] - gt.torso_vel[:2]))))
                assert abs(e.torso_pos[2] - gt.torso_pos[2]) < 0.02  # the height, from kinematics
            assert gt.torso_pos[0] - start.torso_pos[0] > 1.5  # it walked
    finally:
        env.close()
    assert np.median(pos) < 0.1 and np.median(heading) < 0.5 and np.median(vel) < 0.1

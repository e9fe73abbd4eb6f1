"""rcssserver3d's self-collision rule (reference §9.7): the separating-axis test as the server
writes it, the boxes and pairs of each Nao type, and the rule in a running world: the joints of
the colliding parts take no command for 1 s, and not again within 3 s; a paused game and a world
with the rule off freeze nothing. Where a real rcssserver3d is installed, a motion that makes the
right forearm hit the torso is replayed on it: the in-process world follows it to rounding with
the rule and leaves it by degrees without."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robocup_gym.sim import self_collision as sc
from robocup_gym.sim.engines.mujoco.world import World
from robocup_gym.sim.engines.ode import OdeWorld
from robocup_gym.sim.physics import CYCLE_S

# From the standing start of VelocityKick-v0 (joints at 0): this action (max-speed fractions, the
# environment's order) swings the right forearm into the torso 0.3 s in.
FOREARM_INTO_TORSO = [
    0.32, -0.51, 0.54, -0.58, 0.66, -0.87, 0.65, -0.67, -0.25, -0.37,
    0.38, -0.64, -0.21, -0.99, -0.48, -0.16, -0.79, 0.27, -0.24, 0.45,
]  # fmt: skip


def server_test(positions, rotations, half, pairs, tol=sc.TOLERANCE_M):
    """The server's ``BoxCollider::CheckCollisions`` written out: 15 axes, the 9 cross products
    not normalised, the tolerance added to the distance, each axis's scaled projections."""
    out = []
    for a, b in pairs:
        axes_a, axes_b = rotations[a].T, rotations[b].T  # rows = axes
        rel = positions[b] - positions[a]
        axes = [*axes_a, *axes_b, *(np.cross(x, y) for x in axes_a for y in axes_b)]
        separated = False
        for axis in axes:
            extent = sum(abs((axes_a[k] * half[a][k]) @ axis) for k in range(3))
            extent += sum(abs((axes_b[k] * half[b][k]) @ axis) for k in range(3))
            if abs(rel @ axis) + tol > extent:
                separated = True
                break
        out.append(not separated)
    return np.array(out)


def random_rotations(rng, n):
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        1,
    )


def test_the_test_decides_as_the_server_writes_it():
    rng = np.random.default_rng(0)
    n = 2000
    positions = rng.uniform(-0.1, 0.1, (n, 3))
    rotations = random_rotations(rng, n)
    half = rng.uniform(0.02, 0.12, (n, 3))
    pairs = np.arange(n).reshape(-1, 2)
    want = server_test(positions, rotations, half, pairs)
    assert 0.1 < want.mean() < 0.9  # both decisions are exercised
    np.testing.assert_array_equal(
        sc.colliding(positions, rotations, half, pairs, compiled=False), want
    )
    np.testing.assert_array_equal(sc.colliding(positions, rotations, half, pairs), want)


def test_boxes_with_a_common_axis_never_collide():
    """The server's unnormalised cross product of two parallel axes is zero, and the tolerance
    alone then separates: two boxes with one axis in common never count, however deep."""
    half = np.array([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05]])
    pairs = np.array([[0, 1]])
    turn = np.array([[np.cos(0.5), -np.sin(0.5), 0], [np.sin(0.5), np.cos(0.5), 0], [0, 0, 1]])
    inside = np.zeros((2, 3))
    assert not sc.colliding(inside, np.stack([np.eye(3), turn]), half, pairs)[0]
    c, s = np.cos([0.7, 0.8, 0.6]), np.sin([0.7, 0.8, 0.6])
    tilt = (
        np.array([[c[0], -s[0], 0], [s[0], c[0], 0], [0, 0, 1]])
        @ np.array([[1, 0, 0], [0, c[1], -s[1]], [0, s[1], c[1]]])
        @ np.array([[c[2], 0, s[2]], [0, 1, 0], [-s[2], 0, c[2]]])
    )  # no axis in common with the first box
    assert sc.colliding(inside, np.stack([np.eye(3), tilt]), half, pairs)[0]
    apart = np.array([[0.0, 0.0, 0.0], [0.11, 0.0, 0.0]])
    assert not sc.colliding(apart, np.stack([np.eye(3), tilt]), half, pairs)[0]


@pytest.mark.parametrize("robot_type", range(5))
def test_each_type_s_boxes_pairs_and_frozen_joints(robot_type):
    boxes = sc.box_set(robot_type)
    names = {frozenset(p) for p in boxes.names}
    n = 13 if robot_type == 4 else 11
    assert len(boxes.bodies) == n
    skipped = {
        frozenset(p)
        for p in [
            ("rthigh", "torso"),
            ("lthigh", "torso"),
            ("rshank", "rthigh"),
            ("lfoot", "lshank"),
        ]
    }
    assert not names & skipped
    assert len(names) == n * (n - 1) // 2 - (8 if robot_type == 4 else 6)
    assert frozenset(("rshank", "lthigh")) in names  # another leg's parts are tested
    from robocup_gym.robot.nao import nao_model

    effectors = nao_model(robot_type).effector_names
    frozen = {
        p: {e for e, f in zip(effectors, row, strict=True) if f}
        for p, row in zip(boxes.names, boxes.freeze, strict=True)
    }
    arm = {f"rae{k}" for k in range(1, 5)}
    leg = {f"lle{k}" for k in range(1, 8 if robot_type == 4 else 7)}
    assert frozen[("torso", "rlowerarm")] == arm
    pair = next(p for p in boxes.names if set(p) == {"rlowerarm", "lthigh"})
    assert frozen[pair] == arm | leg


def forearm_world(
    rule: bool = True, play_mode: str = "PlayOn", engine: str = "ode"
) -> tuple[OdeWorld, list]:
    """The VelocityKick start's zero pose, then the forearm motion, joint velocities in rad/s."""
    world = OdeWorld([0]) if engine == "ode" else World([0])
    world.self_collision_rule = rule
    world.set_game(play_mode=play_mode)
    world.place_robot(0, -1.0, 0.0)
    model = world.robots[0].model
    order = [f"lae{k}" for k in range(1, 5)] + [f"lle{k}" for k in range(1, 7)]
    order += [f"rle{k}" for k in range(1, 7)] + [f"rae{k}" for k in range(1, 5)]
    speeds = {j.effector: j.max_speed for j in model.joints}
    command = {e: a * speeds[e] for e, a in zip(order, FOREARM_INTO_TORSO, strict=True)}
    return world, command


def run(world, command, cycles):
    angles, hits = [], []
    for _ in range(cycles):
        world.step({0: command})
        angles.append(world.joint_angles_deg(0))
        hits.append(list(world.self_collisions.collisions))
    return np.array(angles), hits


@pytest.mark.parametrize("engine", ["ode", "mujoco"])
def test_a_collision_freezes_the_parts_joints_for_one_second(engine):
    world, command = forearm_world(engine=engine)
    angles, hits = run(world, command, 200)
    first = next(k for k, h in enumerate(hits) if h)
    assert hits[first] == [(0, "torso", "rlowerarm")]
    rae = [world.robots[0].model.effector_names.index(f"rae{k}") for k in range(1, 5)]
    lae = [world.robots[0].model.effector_names.index(f"lae{k}") for k in range(1, 5)]
    frozen_for = round(sc.FROZEN_S / CYCLE_S)
    # commands from the next cycle on are replaced by 0: the arm stops within a few cycles and
    # stays until the second is up; the other arm goes on
    rate = np.abs(np.diff(angles, axis=0))
    still = rate[first + 6 : first + frozen_for, :][:, rae]
    assert still.max() < 0.2, still.max()
    assert rate[first + 6 : first + frozen_for, lae].max() > 1.0 or np.ptp(angles[:, lae]) > 20
    # released after 1 s: the arm moves again (its commands are taken), not frozen again before 3 s
    moved_again = rate[first + frozen_for + 2 : first + frozen_for + 20][:, rae].max()
    assert moved_again > 1.0, moved_again
    assert world.self_collisions.frozen(0) is None or not world.self_collisions.frozen(0)[rae].all()


@pytest.mark.parametrize("case", ["rule off", "paused"])
def test_no_freeze_with_the_rule_off_or_the_game_paused(case):
    mode = "BeforeKickOff" if case == "paused" else "PlayOn"
    world, command = forearm_world(rule=case != "rule off", play_mode=mode)
    on, _ = run(*forearm_world(), 40)
    angles, hits = run(world, command, 40)
    assert not any(hits)
    assert np.abs(angles - on).max() > 5.0  # the arm went on where the rule stopped it


def test_a_clock_set_back_releases_every_joint():
    world, command = forearm_world()
    run(world, command, 25)
    assert world.self_collisions.frozen(0) is not None
    world.set_game(game_time=0.0)
    world.step({0: command})
    assert world.self_collisions.frozen(0) is None or world.self_collisions.collisions


def test_a_real_server_freezes_as_the_in_process_world(real_rcssserver3d):
    """The motion on VelocityKick-v0 from its standing start: on a real rcssserver3d and
    in-process with the rule, the joint angles agree within 0.05° for the 50 cycles before the
    robot lands (the forearm hits the torso at 0.3 s); without the rule they part by degrees."""
    from robocup_gym.train.tasks import make_env

    traces = {}
    for name, backend, rule in (
        ("real", "rcssserver3d", True),
        ("on", "ode", True),
        ("off", "ode", False),
    ):
        env = make_env(
            "RobocupGym/VelocityKick-v0",
            backend=backend,
            env_kwargs={
                "max_episode_steps": 60,
                "terminate_on_fall": False,
                "self_collisions": rule,
            },
        )
        try:
            env.reset(seed=0)
            trace = []
            for _ in range(50):
                env.step(np.array(FOREARM_INTO_TORSO, np.float32))
                trace.append(np.asarray(env.unwrapped.perception.joint_angles_deg, float))
        finally:
            env.close()
        traces[name] = np.array(trace)
    on = np.abs(traces["on"] - traces["real"]).max()
    off = np.abs(traces["off"] - traces["real"]).max()
    assert on < 0.05, json.dumps({"on": float(on), "off": float(off)})
    assert off > 5.0


@pytest.mark.parametrize("rules", [True, False])
def test_serve_applies_the_rule_unless_its_referee_is_off(rules):
    """``robocup-gym serve`` runs the rule in every world it builds as robots join, as a real
    server does; ``--no-rules`` (``rules=False``) switches it off with the referee."""
    from robocup_gym.server import SimServer

    server = SimServer(0, 0, "127.0.0.1", sync=True, real_time=False, rules=rules)
    server.world_host.change_robots([(1, 0), (2, 3)], [])
    assert server.world.n_robots == 2
    assert server.world.self_collision_rule is rules


def test_a_collision_that_freezes_joints_anew_is_a_foul_once():
    """The server records a self-collision foul for each colliding pair that freezes a joint
    not frozen in the last 3 s: the forearm's first collision is one; the same collision in the
    cycles after it (its joints frozen already) is none."""
    world, command = forearm_world()
    fouls = []
    for _ in range(120):
        world.step({0: command})
        fouls.append(list(world.self_collisions.fouls))
    first = next(k for k, f in enumerate(fouls) if f)
    assert fouls[first] == [0]
    assert not any(fouls[first + 1 : first + 50])


def test_the_rule_with_nobody_on_the_field():
    """When the last player leaves a running game on ``serve``, the world steps on with the rule
    on and nothing to test (the rule's state cleared)."""
    from robocup_gym.server import SimServer

    server = SimServer(0, 0, "127.0.0.1", sync=True, real_time=False)
    server.world_host.change_robots([(1, 0)], [])
    server.world.set_game(play_mode="PlayOn", game_time=1.0)
    server.world.step()
    server.world_host.change_robots([], [1])
    world = server.world
    world.set_game(play_mode="PlayOn", game_time=1.02)
    assert world.n_robots == 0 and world.self_collision_rule
    for _ in range(3):
        world.step()
    assert world.self_collisions.collisions == [] and world.self_collisions.fouls == []

"""A scripted kick over the network moves the ball exactly as the same kick in-process, on
either engine."""

from __future__ import annotations

import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim import make_world
from robocup_gym.sim.vision import VisionConfig

# the kick_D command sequence of the real-server capture (shortened rest phase)
SEQUENCE = [
    (50, {}),
    (5, {"rle3": -6.14, "rle4": -6.14}),
    (6, {"rle3": 6.14, "rle4": -6.14}),
    (14, {"rle3": 6.14, "rle4": 6.14}),
    (60, {}),
]


def _snapshot(world) -> dict:
    """What it takes to continue the served world's robot and ball in another world."""
    return {
        "robot": world.export_robot_state(0),
        "ball": (world.ball_position(), world.ball_velocity(), world.ball_angular_velocity()),
        "divergences": None,
    }


def test_kick_over_the_network_equals_in_process(make_server, clients):
    server = make_server(vision_noise=False, rules=True)
    snaps: dict[int, dict] = {}

    def on_cycle(srv) -> None:
        if srv.world.n_robots == 1:
            snap = _snapshot(srv.world)
            snap["divergences"] = srv.world_host.divergences
            snaps[round(srv.world.time / 0.02)] = snap

    server.on_cycle = on_cycle
    mon = clients.monitor(server)
    agent = clients.agent(server)
    agent.handshake("Kick", 1, 0)
    names = nao_model(0).effector_names
    zero = "".join(f"({n} 0.00000)" for n in names)

    def step(msg: str) -> str:
        agent.send(msg + "(syn)")
        return agent.recv()

    for _ in range(40):  # the robot lands and comes to rest: ODE's auto-disable sleeps it
        step(zero)
    mon.send("(playMode PlayOn)(agent (unum 1) (team Left) (move -1.0 0.0 0.385 -90.0))")
    for _ in range(25):
        step(zero)
    mon.send("(ball (pos -0.8 -0.055 0.042) (vel 0 0 0))")
    for _ in range(3):
        last = step(zero)
    # the reply to this percept (time T) is applied in the step after the one that ended at
    # T + 0.02: the state to start from in-process is the one at the end of that cycle
    t_cycle = round(float(last.split(")")[0].split()[-1]) / 0.02) + 1
    commands = []
    for cycles, vel in SEQUENCE:
        cmd = {n: vel.get(n, 0.0) for n in names}
        text = "".join(f"({n} {cmd[n]:.5f})" for n in names)
        for _ in range(cycles):
            commands.append(cmd)
            step(text)
    step(zero)  # the cycle of the last command has completed
    start = snaps[t_cycle]
    end = snaps[t_cycle + len(commands)]
    # asleep when the state moves over: ODE's auto-disable counters, which no export carries,
    # then start afresh in both worlds when the first command wakes the robot
    assert server.engine != "ode" or not any(b[4] for b in start["robot"]["bodies"])
    assert end["divergences"] == start["divergences"], "the served world diverged in the kick"
    net = end["ball"][0] - start["ball"][0]

    world = make_world(
        [0], engine=server.engine, dead_time_cycles=0, vision=VisionConfig(noise=False)
    )
    world.import_robot_state(0, start["robot"])
    world.place_ball(*start["ball"])
    for cmd in commands:
        world.step({0: cmd})  # a SimulationDivergedError fails the test
    local = world.ball_position() - start["ball"][0]
    assert np.hypot(*local[:2]) > 0.3, f"the kick should move the ball, moved {local}"
    # the same to rounding: the robot's state moves between worlds exactly (only the ball's
    # orientation, which no force depends on, starts again from the identity)
    np.testing.assert_allclose(net, local, atol=1e-9)

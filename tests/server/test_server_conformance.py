"""What clients written for the real server do, byte for byte: the handshake orders rcssserver3d
accepts, and trainer commands that act in the next cycle."""

from __future__ import annotations

import time

import numpy as np
import pytest

from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import nao_model
from robocup_gym.server import SimServer
from robocup_gym.server.client import AgentClient, MonitorClient

from . import kick_procedure
from .conftest import HOST

SCENE = "(scene rsg/agent/nao/nao_hetero.rsg 0)"


@pytest.fixture
def server(make_server):
    return make_server()


def _answer(c: AgentClient, timeout: float = 3.0) -> str:
    return c.recv(timeout=timeout)


def test_syn_while_waiting_for_the_robot_then_init_alone(server):
    """A client for the real server keeps sending (syn) until its first percept (the real server
    otherwise stalls ~2 s), then sends (init) without (syn): it must get the answer (it hung)."""
    with AgentClient(HOST, server.agent_port, timeout=3.0) as c:
        c.send(SCENE)
        first = None
        for _ in range(200):
            try:
                first = c.recv(timeout=0.01)
                break
            except TimeoutError:
                c.send("(syn)")
        assert first is not None
        c.send("(init (unum 1)(teamname Syn))")
        parse_perception(_answer(c))  # the answer to init (it hung here)
        numbers = []
        for _ in range(4):  # from here on one percept per (syn); GS announces the number
            c.send("(syn)")
            numbers.append(parse_perception(_answer(c)).game.unum)
        assert 1 in numbers


@pytest.mark.parametrize(
    "messages",
    [
        [SCENE + "(syn)", "(init (unum 2)(teamname A))(syn)"],  # everything with (syn)
        [SCENE, "(init (unum 2)(teamname A))"],  # FC Portugal: no (syn) in the handshake
        ["(syn)", SCENE, "(init (unum 2)(teamname A))(syn)"],  # (syn) before scene: ignored
        [SCENE + "(init (unum 2)(teamname A))(syn)"],  # scene and init in one message
    ],
    ids=["with-syn", "without-syn", "syn-before-scene", "one-message"],
)
def test_every_handshake_order_gets_its_percepts(server, messages):
    with AgentClient(HOST, server.agent_port, timeout=3.0) as c:
        for m in messages:
            c.send(m)
            if m == "(syn)":
                continue  # no robot yet: nothing to answer
            _answer(c)
        got_number = False
        for _ in range(4):
            c.send("(syn)")
            p = parse_perception(_answer(c))
            got_number |= p.game.unum == 2
        assert got_number or server.world.n_robots == 1


def _before_a_monitor_cycle(c: AgentClient) -> None:
    """Answer percepts until the next cycle reads the monitor port (every second cycle: after the
    percept of an odd cycle), so that a trainer command sent now acts in it."""
    while round(parse_perception(_answer(c)).time / 0.02) % 2 == 0:
        c.send("(syn)")


def test_trainer_commands_act_on_the_next_monitor_cycle(make_server):
    """serve reads the trainer's commands on monitor cycles (every second cycle), as
    rcssserver3d: a command in before the agent's (syn) lets a monitor cycle run acts in it;
    in before any other cycle, in the cycle after."""
    server = make_server(monitor_interval=2)
    with (
        AgentClient(HOST, server.agent_port, timeout=3.0) as c,
        MonitorClient(HOST, server.monitor_port, timeout=3.0) as m,
    ):
        c.handshake("T", 1)
        m.send("(playMode PlayOn)")  # before kick-off the referee keeps the ball on the spot
        for _ in range(3):
            c.send("(syn)")
            _answer(c)
        for x in (1.0, 2.0):
            c.send("(syn)")
            _before_a_monitor_cycle(c)
            m.send(f"(ball (pos {x} 1 0.042)(vel 0 0 0))")
            time.sleep(0.05)  # the command is in before the agent's (syn) lets the cycle run
            c.send("(syn)")
            _answer(c)
            np.testing.assert_allclose(server.world.ball_position()[:2], (x, 1.0), atol=0.01)
        for x in (3.0, 4.0):  # after an even cycle's percept: a cycle later
            c.send("(syn)")
            _before_a_monitor_cycle(c)
            c.send("(syn)")
            _answer(c)
            m.send(f"(ball (pos {x} 1 0.042)(vel 0 0 0))")
            time.sleep(0.05)
            c.send("(syn)")
            _answer(c)
            assert abs(server.world.ball_position()[0] - x) > 0.5
            c.send("(syn)")
            _answer(c)
            np.testing.assert_allclose(server.world.ball_position()[:2], (x, 1.0), atol=0.01)


def test_percepts_with_two_or_three_decimals(make_server):
    """2 as upstream rcssserver3d 0.7.3, 3 as the SPL fork (``--decimals``)."""
    import re

    for decimals in (2, 3):
        server = make_server(decimals=decimals)
        with AgentClient(HOST, server.agent_port, timeout=3.0) as c:
            c.handshake("D", 1)
            c.send("(syn)")
            text = _answer(c)
        value = re.search(r"\(HJ \(n hj1\) \(ax (-?\d+\.\d+)\)\)", text).group(1)
        assert len(value.split(".")[1]) == decimals


def test_allowed_robot_types_and_type_limits(make_server, caplog):
    import logging

    from .conftest import run_agents

    server = make_server(robot_types=(0,))
    with AgentClient(HOST, server.agent_port, timeout=1.0) as c, caplog.at_level(logging.WARNING):
        c.send("(scene rsg/agent/nao/nao_hetero.rsg 2)(syn)")
        with pytest.raises(TimeoutError):
            c.recv(timeout=0.5)  # no robot of a type the server does not allow
    assert server.world.n_robots == 0
    # without the league's type rules, eleven robots of one type are a team
    server = make_server(type_limits=False)
    out = run_agents(server, [("Same", u, 0) for u in range(1, 12)], 3)
    assert all("(unum" in "".join(msgs) for msgs in out)
    with pytest.raises(ValueError, match="robot_types must be a non-empty subset"):
        make_server(robot_types=(7,))
    with pytest.raises(ValueError, match="decimals must be 2"):
        make_server(decimals=5)


def test_serve_reads_a_config_file_and_flags_win(tmp_path, monkeypatch, capsys):
    import robocup_gym.server.__main__ as server_main

    seen = {}
    monkeypatch.setattr(server_main, "serve", lambda **kw: seen.update(kw))
    cfg = tmp_path / "serve.toml"
    cfg.write_text(
        'sync = true\nreal-time = false\nagent-port = 0\nmonitor-port = 0\nhost = "127.0.0.1"\n'
        "decimals = 3\nrobot-types = [0, 4]\ntype-limits = false\nsync-timeout = 2.5\n"
    )
    assert server_main.main(["--config", str(cfg), "--decimals", "2"]) == 0
    assert seen["sync"] is True and seen["real_time"] is False and seen["host"] == "127.0.0.1"
    assert seen["decimals"] == 2  # the flag wins over the file
    assert seen["robot_types"] == (0, 4) and seen["type_limits"] is False
    assert seen["sync_timeout"] == 2.5
    assert seen["engine"] == "ode" and seen["rules"] is True and seen["vision_noise"] is True
    # rcssserver3d-style switches, also in their `no-` spellings
    cfg.write_text("no-rules = true\nvision-noise = false\nfull-vision = true\nengine = 'mujoco'\n")
    assert server_main.main(["--config", str(cfg)]) == 0
    assert seen["rules"] is False and seen["vision_noise"] is False
    assert seen["view_cone_deg"] == 360.0 and seen["engine"] == "mujoco"
    assert server_main.main(["--config", str(cfg), "--rules", "--vision-noise"]) == 0
    assert seen["rules"] is True and seen["vision_noise"] is True
    bad = tmp_path / "bad.toml"
    for text, expected in (
        ("nosuch = 1\n", "unknown option 'nosuch'"),
        ("agent-port = 70000\n", "70000 is not a port number"),
        ("sync = 3\n", "sync must be true or false"),
        ("sync = \n", "not valid TOML"),
        ("no-rules = 1\n", "no-rules must be true or false"),
        ("engine = 'bullet'\n", "engine must be one of"),
    ):
        bad.write_text(text)
        with pytest.raises(SystemExit) as exit_:
            server_main.main(["--config", str(bad)])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and expected in err and len(err.strip().splitlines()) == 1


def test_a_robot_moved_at_rest_hangs_asleep_until_a_motor_wakes_it(server):
    """rcssserver3d (fixtures README): after a trainer move a resting robot (ODE's auto-disable
    has put it to sleep) hangs where it was put (accelerometer 9.81, gyro 0, no foot contact),
    until its first non-zero joint velocity; then it lands. (The torso's height is read by the
    server's own thread at the end of every cycle: read from the test's thread it could meet
    the world in the middle of a step.)"""
    heights: list[float] = []
    with (
        AgentClient(HOST, server.agent_port, timeout=3.0) as c,
        MonitorClient(HOST, server.monitor_port, timeout=3.0) as m,
    ):
        c.handshake("Hover", 1)
        i = server.world_host.index(server.agents[0].key)
        server.on_cycle = lambda s: heights.append(float(s.world.torso_position(i)[2]))
        for _ in range(40):  # it lands and comes to rest
            c.send("(syn)")
            _answer(c)
        m.send("(playMode PlayOn)(agent (unum 1) (team Left) (move -1.0 0.0 0.386 -90.0))")
        time.sleep(0.05)
        percepts = []
        for _ in range(6):
            c.send("(syn)")
            percepts.append(parse_perception(_answer(c)))
        last = percepts[-1]
        assert not last.force_sensors  # no foot contact
        np.testing.assert_allclose(last.accel, [0.0, 0.0, 9.81], atol=0.01)
        np.testing.assert_allclose(last.gyro, 0.0, atol=1e-9)
        c.send("(he1 0.5)(syn)")  # the first non-zero joint velocity wakes it
        for _ in range(5):
            _answer(c)
            c.send("(syn)")
        _answer(c)
    moved = next(k for k, z in enumerate(heights) if z == pytest.approx(0.386, abs=1e-7))
    hanging = heights[moved : moved + 5]  # until the wake acts
    assert hanging == pytest.approx([0.386] * 5, abs=1e-7), heights[moved - 2 :]
    assert heights[-1] < 0.385  # landed


def test_a_robot_moved_while_it_moves_falls_where_it_is_put(make_server):
    """A robot that is not at rest (here: just created, falling to its start) is awake when the
    trainer moves it: it falls from where it was put and lands two cycles later, as on
    rcssserver3d."""
    # a trainer command acts in the cycle it comes before (with the default of every second
    # cycle, whether that is the next cycle or the one after turns on the cycle in which the
    # agent happened to connect, which the server's idle pacing leaves to the clock)
    server = make_server(monitor_interval=1)
    with (
        AgentClient(HOST, server.agent_port, timeout=3.0) as c,
        MonitorClient(HOST, server.monitor_port, timeout=3.0) as m,
    ):
        c.handshake("Drop", 1)
        m.send("(playMode PlayOn)(agent (unum 1) (team Left) (move -1.0 0.0 0.386 -90.0))")
        time.sleep(0.05)
        feet = []
        for _ in range(5):
            c.send("(syn)")
            feet.append(bool(parse_perception(_answer(c)).force_sensors))
        assert feet == [False, False, True, True, True]


def test_the_forks_rot_turns_the_robot_about_its_torso(make_server):
    """The SPL fork's ``(agent … (rot rx ry rz))``: serve turns the robot rigidly about its
    torso centre to ``Rx·Ry·Rz``, as the fork does (joints kept)."""
    from robocup_gym.protocol.trainer import quat_from_rot

    server = make_server()
    with (
        AgentClient(HOST, server.agent_port, timeout=3.0) as c,
        MonitorClient(HOST, server.monitor_port, timeout=3.0) as m,
    ):
        c.handshake("T", 1)
        c.send("(syn)")
        _before_a_monitor_cycle(c)
        joints = server.world.joint_angles_deg(0).copy()
        m.send("(agent (unum 1) (team Left) (pos -2 1 0.5) (rot -80 0 -90))")
        time.sleep(0.05)
        c.send("(syn)")
        _answer(c)
        q = server.world.torso_quat(0)
        want = quat_from_rot((-80.0, 0.0, -90.0))
        assert min(np.abs(q - want).max(), np.abs(q + want).max()) < 0.02  # one cycle falling
        np.testing.assert_allclose(server.world.torso_position(0)[:2], (-2.0, 1.0), atol=0.01)
        np.testing.assert_allclose(server.world.joint_angles_deg(0), joints, atol=0.5)


@pytest.mark.parametrize("trainer_first", [True, False], ids=["trainer-first", "agent-first"])
def test_the_real_servers_kick_procedure_gives_its_result(trainer_first):
    """The client of the real server's scripted kick (``kick_D.json``'s procedure, its messages
    byte for byte; ``kick_procedure.py``) against ``serve`` on SimSpark's physics: the resting
    robot moved by the trainer hangs without foot contact until its first motor command, the ball
    first moves in cycle 64 ± 1 and travels the real server's 2.307 m (to 1 mm), in either order
    of trainer and agent messages."""
    server = SimServer(0, 0, HOST, sync=True, real_time=False, seed=1, engine="ode")
    server.start_in_thread()
    try:
        run = kick_procedure.run(
            HOST, server.agent_port, server.monitor_port, trainer_first=trainer_first
        )
    finally:
        server.stop()
    fixture = kick_procedure.FIXTURE
    for accel in run.accel_before:  # asleep: no gravity felt, no contact
        np.testing.assert_allclose(accel, [0.0, 0.0, 9.81], atol=1e-9)
    still = fixture["command_sequence"][0]["cycles"]
    assert not any(run.feet[: still + 1]), "foot contact while the moved robot should hang"
    assert run.feet[still + 2] == {"lf", "rf"}  # it lands two cycles after the first command
    assert abs(run.first_ball_movement() - fixture["ball_first_moves_at_cycle"]) <= 1
    assert run.ball_travel() == pytest.approx(fixture["ball_displacement_xy_m"], abs=1e-3)


def test_the_kick_procedure_on_a_real_server_equals_serve(real_rcssserver3d):
    """Where a real rcssserver3d is installed: the same client against it and against ``serve``
    sees the same foot contacts in every cycle until the kick (none while the robot hangs, then
    its landing) and the same ball travel (to 0.5 mm: the real server repeats its own result
    only to ~0.3 mm, and single foot contacts in the kick and the fall that follows flip from
    run to run)."""
    from robocup_gym.backends.process import ServerProcess

    real = ServerProcess(real_rcssserver3d, monitor_step=0.04)
    agent_port, monitor_port = real.start()
    try:
        real_run = kick_procedure.run(HOST, agent_port, monitor_port)
    finally:
        real.stop()
    server = SimServer(0, 0, HOST, sync=True, real_time=False, seed=1, engine="ode")
    server.start_in_thread()
    try:
        served = kick_procedure.run(HOST, server.agent_port, server.monitor_port)
    finally:
        server.stop()
    kick = kick_procedure.FIXTURE["ball_first_moves_at_cycle"]
    assert served.feet[: kick - 5] == real_run.feet[: kick - 5]
    assert served.ball_travel() == pytest.approx(real_run.ball_travel(), abs=5e-4)


def _trainer_delay(agent_port: int, monitor_port: int, cycles_first: int) -> tuple[int, int]:
    """An agent plays ``cycles_first`` zero cycles, then a trainer sends ``(playMode PlayOn)``
    after a percept and before its answer. Returns the cycle number of that percept (simulation
    time / 0.02) and how many percepts later the game clock first shows running (2 when the
    command acts in the next cycle: a percept shows the world of the cycle before it)."""
    names = nao_model(0).effector_names
    zero = "".join(f"({n} 0.00)" for n in names) + "(syn)"
    with AgentClient(HOST, agent_port, timeout=20.0) as agent:
        agent.handshake("Left", 1, 0)
        for _ in range(cycles_first):
            agent.send(zero)
            percept = agent.recv()
        monitor = MonitorClient(HOST, monitor_port, timeout=20.0)
        try:
            for _ in range(4):
                agent.send(zero)
                percept = agent.recv()
            cycle = round(parse_perception(percept).time / 0.02)
            monitor.send("(playMode PlayOn)")
            for k in range(1, 5):
                agent.send(zero)
                if parse_perception(agent.recv()).game.game_time > 0.0:
                    return cycle, k
        finally:
            monitor.close()
    raise AssertionError("the game clock did not run within 4 cycles of PlayOn")


@pytest.mark.parametrize("cycles_first", [20, 21])
def test_a_trainer_command_takes_effect_on_the_next_monitor_cycle(cycles_first):
    """The monitor port is read every second cycle (the monitor step, 0.04 s): a trainer's
    command sent after the percept of an even cycle takes effect a cycle later than one sent
    after an odd cycle's, as on rcssserver3d (and measured there:
    ``test_trainer_commands_wait_for_a_monitor_cycle_on_a_real_server``)."""
    server = SimServer(0, 0, HOST, sync=True, real_time=False, seed=1, engine="ode")
    server.start_in_thread()
    try:
        cycle, delay = _trainer_delay(server.agent_port, server.monitor_port, cycles_first)
    finally:
        server.stop()
    assert delay == (3 if cycle % 2 == 0 else 2), (cycle, delay)


def test_trainer_commands_wait_for_a_monitor_cycle_on_a_real_server(real_rcssserver3d):
    """Where a real rcssserver3d is installed: the same rule on it (which parity a run's
    cycles fall on depends on how long the server cycled before the agent came)."""
    from robocup_gym.backends.process import ServerProcess

    for cycles_first in (20, 21, 20, 21):
        real = ServerProcess(real_rcssserver3d, monitor_step=0.04)
        agent_port, monitor_port = real.start()
        try:
            cycle, delay = _trainer_delay(agent_port, monitor_port, cycles_first)
        finally:
            real.stop()
        assert delay == (3 if cycle % 2 == 0 else 2), (cycle, delay)


def test_a_trainer_that_closes_at_once_still_acts(make_server):
    """A trainer that sends a command and closes its connection at once (before the next
    monitor cycle): the command still acts, as on rcssserver3d, which reads a monitor's data and
    its end together."""
    server = make_server(monitor_interval=2)
    with AgentClient(HOST, server.agent_port, timeout=3.0) as c:
        c.handshake("T", 1)
        c.send("(syn)")
        _before_a_monitor_cycle(c)
        c.send("(syn)")
        _answer(c)  # the next cycle is not a monitor cycle
        with MonitorClient(HOST, server.monitor_port, timeout=3.0) as m:
            m.send("(playMode PlayOn)(ball (pos 3 -2 0.042)(vel 0 0 0))")
        time.sleep(0.1)  # closed before the cycles run
        for _ in range(2):
            c.send("(syn)")
            _answer(c)
        np.testing.assert_allclose(server.world.ball_position()[:2], (3.0, -2.0), atol=0.01)

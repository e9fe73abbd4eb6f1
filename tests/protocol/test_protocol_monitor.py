"""Monitor stream: the real-server captures, scene-graph tracking across deltas, writers."""

from __future__ import annotations

import numpy as np
import pytest
from protocol_helpers import MONITOR

from robocup_gym.protocol.constants import DEFAULT_ENVIRONMENT, PLAY_MODES
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.monitor import (
    MonitorState,
    format_environment,
    format_game_state,
    format_monitor_frame,
    format_monitor_message,
    parse_monitor_message,
)
from robocup_gym.protocol.scenegraph import (
    DeltaEncoder,
    SceneGraph,
    SceneNode,
    format_full_scene,
    format_light,
    format_slt,
    format_smn,
    format_static_mesh,
    format_trf,
    parse_scene_nodes,
    slt_matrix,
)
from robocup_gym.protocol.sexpr import parse

# Torso pose columns of the robot in the first delta (MONITOR[3]), read off the text.
TORSO_DELTA1_POS = [-0.952624, -0.0224792, 0.385065]


def test_fixture_frames_header_and_kinds() -> None:
    frames = [parse_monitor_message(m) for m in MONITOR]
    assert [f.full for f in frames] == [True, True, True, False, False, False]
    assert all(f.version == (0, 1) for f in frames)
    info = frames[0].info
    assert info.constants["FieldLength"] == 30
    assert info.constants["FieldWidth"] == 20
    assert info.constants["GoalWidth"] == 2.1
    assert info.constants["BallRadius"] == 0.042
    assert info.constants["PassModeDuration"] == 4
    assert info.play_modes == PLAY_MODES
    assert (info.time, info.half, info.score_left, info.score_right) == (0.0, 1, 0, 0)
    assert info.play_mode == 0
    assert info.team_left is None
    assert frames[2].info.team_left == "Probe"
    assert frames[3].info.time == 0.0
    assert frames[3].info.play_modes is None and frames[3].info.constants == {}
    assert [len(f.scene) for f in frames] == [36, 37, 37, 37, 37, 37]


def test_fixture_frames_round_trip_byte_for_byte() -> None:
    for msg in MONITOR:
        assert format_monitor_frame(parse_monitor_message(msg)) == msg


def test_full_scene_nodes() -> None:
    nodes = parse_monitor_message(MONITOR[0]).scene
    light = nodes[0]
    assert isinstance(light, SceneNode) and light.kind == "TRF"
    np.testing.assert_array_equal(light.slt[:3, 3], [-10, 10, 10])
    assert light.children[0].kind == "Light"
    assert light.children[0].props["setAmbient"] == ("0.8", "0.8", "0.8", "1")
    field_mesh = nodes[2].children[0]
    assert field_mesh.kind == "StaticMesh"
    assert field_mesh.model == "models/naosoccerfield.obj"
    np.testing.assert_array_equal(field_mesh.scale, [2.5, 1, 2.5])
    # SLT is column-major: first column = local x axis = (-1, -8.74228e-08, -3.82137e-15).
    np.testing.assert_allclose(nodes[2].slt[:3, 0], [-1, -8.74228e-08, -3.82137e-15])
    border = nodes[6].children[0]
    assert (border.kind, border.model, border.materials) == ("SMN", "StdUnitBox", ("matGrey",))
    goal = nodes[4].children[0].children[0]
    assert "setTransparent" in goal.props and goal.visible


def test_robot_appears_after_init_and_is_tracked_through_deltas() -> None:
    state = MonitorState()
    state.update(MONITOR[0])
    assert state.scene.agents() == {}
    np.testing.assert_allclose(state.scene.ball_position(), [0, 0, 0.0402764])
    state.update(MONITOR[1])  # after scene: robot without team materials
    assert state.scene.agents() == {}
    state.update(MONITOR[2])  # after init: matNum1 + matLeft
    assert state.info.team_left == "Probe"
    assert state.play_mode_name == "BeforeKickOff"
    assert state.scene.agents() == {("left", 1): 36}
    robot = state.scene.nodes[36]
    torso_mesh = robot.children[0].children[0].children[0]
    assert torso_mesh.model == "models/naobody0.obj"
    assert torso_mesh.materials == ("matNum1", "matLeft", "matType0", "naowhite")
    world = state.scene.world_transforms()
    np.testing.assert_allclose(world[(36, 0)][:3, 3], [-0.950633, -0.0224738, 0.396076])
    # The mesh wrapper is rotated by Euler(-90, 0, 180) relative to the torso body.
    wrapper = world[(36, 0, 0)]
    np.testing.assert_allclose(wrapper[:3, 3], world[(36, 0)][:3, 3])
    np.testing.assert_allclose(
        wrapper[:3, :3], world[(36, 0)][:3, :3] @ robot.children[0].children[0].slt[:3, :3]
    )
    before_head = world[(36, 2)].copy()
    state.update(MONITOR[3])
    world = state.scene.world_transforms()
    np.testing.assert_allclose(world[(36, 0)][:3, 3], TORSO_DELTA1_POS)
    assert not np.allclose(world[(36, 2)], before_head)
    np.testing.assert_allclose(state.scene.ball_position(), [0, 0, 0.0417605])
    # Nodes the delta does not mention keep their matrices.
    np.testing.assert_array_equal(world[(0,)][:3, 3], [-10, 10, 10])
    for msg in MONITOR[4:]:
        state.update(msg)
    assert state.frames == 6
    last = parse_monitor_message(MONITOR[5]).scene[36].children[0].slt  # type: ignore[union-attr]
    np.testing.assert_array_equal(state.scene.nodes[36].children[0].slt, last)
    # setVisible in deltas is applied (idempotently).
    selection = state.scene.nodes[36].children[0].children[1].children[0]
    assert selection.kind == "SMN" and not selection.visible


def test_delta_before_full_is_ignored_and_mismatch_raises() -> None:
    state = MonitorState()
    state.update(MONITOR[3])
    assert not state.has_scene
    state.update(MONITOR[0])  # 36 top-level nodes, the delta has 37
    with pytest.raises(ProtocolError, match="delta does not match"):
        state.update(MONITOR[3])


def test_malformed_frames() -> None:
    with pytest.raises(ProtocolError, match="3 expressions"):
        parse_monitor_message("((time 0))(RSG 0 1)")
    with pytest.raises(ProtocolError, match="RSG 0 1"):
        parse_monitor_message("((RSMP 1 0))(gt 0)((nd))")
    with pytest.raises(ProtocolError, match="needs a type"):
        parse_monitor_message("((time 0))(RSG 0 1)((nd (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1)))")
    with pytest.raises(ProtocolError, match="16 numbers"):
        parse_monitor_message("((time 0))(RSG 0 1)((nd TRF (SLT 1 0 0)))")
    with pytest.raises(ProtocolError):
        parse_monitor_message(MONITOR[3][:-2])


def test_environment_writer_matches_the_server() -> None:
    head = format_environment(DEFAULT_ENVIRONMENT, PLAY_MODES)
    dynamic = format_game_state(0, half=1, score_left=0, score_right=0, play_mode="BeforeKickOff")
    assert MONITOR[0].startswith("(" + head + dynamic + ")(RSG 0 1)")
    with_team = format_game_state(
        0, team_left="Probe", half=1, score_left=0, score_right=0, play_mode=0
    )
    assert MONITOR[2].startswith("(" + head + with_team + ")(RSG 0 1)")
    assert format_game_state(127.42, play_mode=3) == "(time 127.42)(play_mode 3)"
    assert format_game_state(1.5, extra=[("foul", (1, 0, 1, 7))]) == "(time 1.5)(foul 1 0 1 7)"


def test_node_writers_match_the_server() -> None:
    light = format_trf(
        slt_matrix([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -10, 10, 10, 1]),
        format_light((1, 1, 1, 1), (0.8, 0.8, 0.8, 1), (0.1, 0.1, 0.1, 1)),
    )
    assert MONITOR[0].startswith(light, MONITOR[0].index("((nd ") + 1)
    border = format_smn("StdUnitBox", (1, 51, 1), "matGrey")
    assert border == "(nd SMN (setVisible 1) (load StdUnitBox) (sSc 1 51 1) (sMat matGrey))"
    assert border in MONITOR[0]
    capsule = format_smn("StdCapsule", (1, 1, 1), "matDarkGrey", load_params=(0.015, 0.08))
    assert capsule in MONITOR[2]
    select = format_smn(
        "StdUnitCylinder",
        (0.2, 0.2, 0.02),
        "matSelect",
        load_params=(1, 1),
        visible=False,
        transparent=True,
    )
    assert select in MONITOR[2]
    goal = format_static_mesh(
        "models/leftsoccergoal.obj", (2.18, 0.88, 0.68), ["naogoalnet", "white"], transparent=True
    )
    assert goal in MONITOR[0]
    assert format_slt(np.eye(4)) == "(SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1)"
    m = np.eye(4)
    m[:3, 3] = (1.5, -2, 0.042)
    assert format_slt(m) == "(SLT 1 0 0 0 0 1 0 0 0 0 1 0 1.5 -2 0.042 1)"


def test_delta_encoder_writes_what_a_client_can_track() -> None:
    nodes = parse_monitor_message(MONITOR[2]).scene
    assert all(isinstance(n, SceneNode) for n in nodes)
    enc = DeltaEncoder()
    full = enc.full(nodes)  # type: ignore[arg-type]
    assert full == format_full_scene(nodes)  # type: ignore[arg-type]
    client = MonitorState()
    client.update(format_monitor_message(format_game_state(0), full, full=True))
    # Nothing moved: every transform and mesh is written bare, lights as (nd).
    quiet = enc.delta(nodes)  # type: ignore[arg-type]
    assert "SLT" not in quiet and "setVisible" not in quiet
    assert quiet.startswith("((nd(nd))(nd(nd))(nd(nd StaticMesh))")
    # Move the ball by 2 mm (below the threshold) and the torso by 1 cm (above it).
    ball, torso = nodes[35], nodes[36].children[0]
    ball.slt = ball.slt.copy()
    ball.slt[0, 3] += 0.002
    torso.slt = torso.slt.copy()
    torso.slt[:3, 3] += (0.01, 0.0, -0.01)
    selection = torso.children[1].children[0]
    selection.props["setVisible"] = ("1",)
    delta = enc.delta(nodes)  # type: ignore[arg-type]
    assert delta.count("SLT") == 1 and delta.count("(setVisible 1)") == 1
    client.update(format_monitor_message(format_game_state(0.04), delta, full=False))
    np.testing.assert_allclose(client.scene.node((36, 0)).slt, torso.slt, atol=1e-6)
    assert client.scene.node((36, 0, 1, 0)).visible
    assert client.info.time == 0.04
    # The small ball move accumulates until it exceeds the threshold.
    ball.slt[0, 3] += 0.004
    assert enc.delta(nodes).count("SLT") == 1  # type: ignore[arg-type]
    nodes.append(SceneNode("TRF", np.eye(4)))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="structure changed"):
        enc.delta(nodes)  # type: ignore[arg-type]


def test_monitor_message_writer() -> None:
    with pytest.raises(ValueError, match="empty"):
        format_monitor_message("", "()", full=True)
    m = np.eye(4)
    m[:3, 3] = (1, 2, 3)
    scene = "(" + format_trf(m, format_trf(m)) + ")"
    text = format_monitor_message(format_game_state(1), scene, full=True)
    assert text == (
        "((time 1))(RSG 0 1)((nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1)"
        "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1))))"
    )
    graph = SceneGraph(parse_scene_nodes(parse(text)[2]))  # type: ignore[arg-type]
    world = graph.world_transforms()
    np.testing.assert_array_equal(world[(0,)][:3, 3], [1, 2, 3])
    np.testing.assert_array_equal(world[(0, 0)][:3, 3], [2, 4, 6])

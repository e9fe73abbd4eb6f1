"""The rcssserver3d (SimSpark) wire protocol: framing, S-expressions, percepts, commands, monitor.

Modules:

* :mod:`.framing` — 4-byte length prefix, incremental :class:`FrameDecoder`, socket helpers;
* :mod:`.sexpr` — fast S-expression reader/writer;
* :mod:`.perceptors` — percept text ↔ :class:`~robocup_gym.types.Perception`;
* :mod:`.effectors` — agent commands (client formatting, server parsing);
* :mod:`.trainer` — monitor/trainer commands;
* :mod:`.monitor`, :mod:`.scenegraph` — the monitor stream and its scene graph;
* :mod:`.values` — C-compatible number parsing and formatting; :mod:`.constants`.

Units on the wire: joint angles in degrees, joint velocity commands in rad/s (see
:mod:`robocup_gym.types`). See ``docs/protocol.md`` for examples.
"""

from robocup_gym.protocol.constants import (
    DEFAULT_AGENT_PORT,
    DEFAULT_ENVIRONMENT,
    DEFAULT_MONITOR_PORT,
    PLAY_MODES,
    play_mode_id,
)
from robocup_gym.protocol.effectors import (
    AgentAction,
    Beam,
    Hinge,
    Init,
    Pass,
    Say,
    Scene,
    Syn,
    Unknown,
    format_action,
    format_actions,
    format_command,
    format_init,
    format_scene,
    parse_agent_message,
)
from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.framing import (
    FrameDecoder,
    encode_frame,
    recv_frame,
    send_frame,
)
from robocup_gym.protocol.monitor import (
    MonitorFrame,
    MonitorState,
    format_environment,
    format_game_state,
    format_monitor_message,
    parse_monitor_message,
)
from robocup_gym.protocol.perceptors import format_perception, parse_perception
from robocup_gym.protocol.scenegraph import DeltaEncoder, SceneGraph, SceneNode
from robocup_gym.protocol.trainer import (
    TrainerCommand,
    format_trainer_command,
    parse_trainer_message,
)

__all__ = [
    "DEFAULT_AGENT_PORT",
    "DEFAULT_ENVIRONMENT",
    "DEFAULT_MONITOR_PORT",
    "PLAY_MODES",
    "AgentAction",
    "Beam",
    "DeltaEncoder",
    "FrameDecoder",
    "Hinge",
    "Init",
    "MonitorFrame",
    "MonitorState",
    "Pass",
    "ProtocolError",
    "Say",
    "Scene",
    "SceneGraph",
    "SceneNode",
    "Syn",
    "TrainerCommand",
    "Unknown",
    "encode_frame",
    "format_action",
    "format_actions",
    "format_command",
    "format_environment",
    "format_game_state",
    "format_init",
    "format_monitor_message",
    "format_perception",
    "format_scene",
    "format_trainer_command",
    "parse_agent_message",
    "parse_monitor_message",
    "parse_perception",
    "parse_trainer_message",
    "play_mode_id",
    "recv_frame",
    "send_frame",
]

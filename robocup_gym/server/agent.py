"""Per-connection state of an agent (wire reference §3, §4, §6)."""

from __future__ import annotations

from dataclasses import dataclass, field

from robocup_gym.server.wire import Connection

GRACE_PERCEPTS = 1
"""Sync mode: the first percept after ``scene`` is sent without waiting (clients block on it)."""


@dataclass
class AgentState:
    """Everything the server knows about one agent connection."""

    conn: Connection
    robot_type: int | None = None
    """Type of the robot once ``scene`` was accepted (it exists from the next physics phase)."""
    has_robot: bool = False
    killed: bool = False
    """Robot removed by the trainer ``(kill)``; the connection stays open, nothing is sent."""
    side: str | None = None
    team_name: str | None = None
    unum: int | None = None
    synced: bool = False
    ever_synced: bool = False
    """Sent ``(syn)`` since its robot exists. Until then (the handshake: ``scene`` → percept →
    ``init`` → percept) every message counts as ``(syn)`` in sync mode. The real server instead
    lets the first 5 cycles after connecting pass unsynced, which sends a client that replies
    slower than the server cycles two percepts for its first message and leaves it one percept
    behind for good; here every handshake message gets exactly one percept, and FC Portugal's
    ``init`` without ``(syn)`` still gets its answer. An ``init`` counts as ``(syn)`` even after
    a ``(syn)``: clients for the real server keep sending ``(syn)`` while they wait for their
    robot (it otherwise stalls ~2 s before the first percept), then send ``init`` alone."""
    percepts_sent: int = 0
    percept: bytes | None = None
    """Frame computed at the end of the last cycle, sent at the start of the next."""
    # actions read this cycle, realised in the physics phase
    scene_type: int | None = None
    init: tuple[int, str] | None = None
    beam: tuple[float, float, float] | None = None
    want_pass: bool = False
    joints: dict[str, float] = field(default_factory=dict)

    @property
    def key(self) -> int:
        return self.conn.cid

    @property
    def waited_for(self) -> bool:
        """Does sync mode wait for this agent's ``(syn)``? Only for a live robot that was sent its
        first percept (never for a connection without robot: that deadlocks the real server)."""
        return (
            self.conn.alive
            and self.has_robot
            and not self.killed
            and self.percepts_sent >= GRACE_PERCEPTS
        )

    def clear_actions(self) -> None:
        self.scene_type = None
        self.init = None
        self.beam = None
        self.want_pass = False
        if self.joints:
            self.joints = {}

"""Ground truth of a real rcssserver3d from its monitor stream: where the ball and the learning
robot's torso are in each frame, and their velocities (wire reference §7). Full frames go
through the general scene-graph parser; delta frames are only scanned (see
:class:`MonitorTracker`)."""

from __future__ import annotations

import collections
import logging
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.monitor import MonitorState

log = logging.getLogger("robocup_gym.backends.rcssserver3d")

TIME_TOLERANCE_S = 0.006
"""Tolerance when matching a monitor frame's game time to a percept's (2–3 decimals on the wire)."""
FROZEN_CLOCK_MODES = frozenset({"BeforeKickOff", "GameOver"})
"""Play modes in which the game clock stands still (ground truth then cannot be matched by time)."""


@dataclass
class GroundTruthSnapshot:
    """What one monitor frame says about the ball and the learning robot's torso."""

    game_time: float
    """The frame's ``(time …)`` (game time, s)."""
    ball_pos: np.ndarray
    torso: np.ndarray | None
    """Torso world transform (4×4; columns: torso x = right, y = forward, z = up, position)."""
    ball_vel: np.ndarray
    torso_vel: np.ndarray


class _VelocityTrack:
    """Finite-difference velocity of a body whose pose only comes when it moved (monitor deltas
    resend a transform after a change of more than 0.005, wire reference §7.4).

    ``v = (p_last_change - p_change_before) / (t_now - t_change_before)``: the exact mean velocity
    between the last two updates when the body was just resent, falling off while no update comes.
    """

    def __init__(self) -> None:
        self.restart(None, None, np.zeros(3))

    def restart(self, t: float | None, p: np.ndarray | None, v: np.ndarray) -> None:
        self.t_last = t
        self.p_last = None if p is None else p.copy()
        self.t_prev: float | None = None
        self.p_prev: np.ndarray | None = None
        self.t_now = t
        self.vel = np.asarray(v, dtype=float).copy()

    def update(self, t: float, p: np.ndarray) -> np.ndarray:
        if self.t_now is not None and t < self.t_now - 1e-9:  # the game clock was set back
            self.restart(t, p, np.zeros(3))
            return self.vel
        self.t_now = t
        if self.p_last is None:
            self.t_last, self.p_last = t, p.copy()
            return self.vel
        if np.any(p != self.p_last):
            if t > (self.t_last or 0.0) + 1e-9 or self.p_prev is None:
                self.t_prev, self.p_prev = self.t_last, self.p_last
            self.t_last, self.p_last = t, p.copy()
        if self.p_prev is not None and self.t_prev is not None and t > self.t_prev + 1e-9:
            self.vel = (self.p_last - self.p_prev) / (t - self.t_prev)
        return self.vel


_ND = re.compile(r"\(nd\b")
"""A scene node's opening: nodes are numbered by the order of these (depth-first pre-order)."""
_SLT_AT = re.compile(r"\s*\(SLT ([^()]*)\)")
_TIME = re.compile(r"\(time ([^()\s]+)\)")


class MonitorTracker:
    """Follows the monitor stream: the ball's and the learning robot's torso transforms, with a
    short history of snapshots.

    Full frames (``RSG``) go through the general parser (:class:`MonitorState`), which also
    locates the ball and the torso in the scene graph. Delta frames (``RDS``, every cycle) are
    only scanned: a delta mirrors the last full scene node for node (wire reference §7.4), so
    only the ``SLT`` of the nodes on the ball's and the torso's paths are read, found by their
    position in the depth-first order. A delta whose node count differs from the full scene means
    a full frame was missed (:attr:`need_full`).
    """

    def __init__(self) -> None:
        self.state = MonitorState()
        self.snapshots: collections.deque[GroundTruthSnapshot] = collections.deque(maxlen=16)
        self.agent: tuple[str, int] | None = None
        """(side, unum) of the learning robot once known."""
        self.frames = 0
        self.errors = 0
        self.need_full = False
        self.full_requested = False
        self.time = 0.0
        self._has_scene = False
        self._n_nodes = 0
        self._ball_path: tuple[int, ...] | None = None
        self._torso_path: tuple[int, ...] | None = None
        self._slt: dict[tuple[int, ...], np.ndarray | None] = {}
        self._ordinals: list[tuple[int, tuple[int, ...]]] = []
        self._ball = _VelocityTrack()
        self._torso = _VelocityTrack()

    @property
    def has_agent(self) -> bool:
        return self._torso_path is not None

    def set_agent(self, side: str, unum: int) -> None:
        """Follow robot ``(side, unum)`` (looked up again in the last full scene)."""
        self.agent = (side, unum)
        if self._has_scene:
            self._locate()

    def newest(self) -> GroundTruthSnapshot | None:
        return self.snapshots[-1] if self.snapshots else None

    def feed(self, payload: bytes | str) -> None:
        """Apply one monitor frame; one that does not fit (a missed full frame) sets
        :attr:`need_full` (the caller then sends ``(reqfullstate)``)."""
        text = payload if isinstance(payload, str) else payload.decode("latin-1")
        k = text.find("(RDS ")
        try:
            if k >= 0:
                if not self._has_scene or self.need_full:
                    return  # nothing to apply it to (as RoboViz: deltas before a full frame)
                self._delta(text, k)
            else:
                self._full(text)
        except (ProtocolError, ValueError, IndexError) as exc:
            self.errors += 1
            if not self.need_full:
                log.warning("monitor stream out of step (%s); requesting a full frame", exc)
            self.need_full = True
            return
        self.frames += 1
        self._snapshot()

    def _full(self, text: str) -> None:
        state = MonitorState()
        frame = state.update(text)
        if not frame.full:  # pragma: no cover - guarded by the caller
            raise ProtocolError("expected a full frame")
        self.state = state
        self.time = state.info.time if state.info.time is not None else self.time
        self._has_scene = True
        self.need_full = self.full_requested = False
        self._locate()

    def _delta(self, text: str, header: int) -> None:
        m = _TIME.search(text, 0, header)
        if m is not None:
            self.time = float(m.group(1))
        # A delta has exactly the nodes of the last full scene in the same order (wire reference
        # §7.4), so the k-th "(nd" of the delta is the k-th node of the scene's depth-first walk. A
        # transform that moved carries "(nd (SLT …)" right after its opening.
        starts = [nd.start() for nd in _ND.finditer(text, header)]
        if len(starts) != self._n_nodes:
            raise ProtocolError(
                f"delta has {len(starts)} scene nodes, the last full scene {self._n_nodes} "
                "(missed a full frame?)"
            )
        for ordinal, key in self._ordinals:
            got = _SLT_AT.match(text, starts[ordinal] + 3)
            if got is not None:
                values = np.array(got.group(1).split(), dtype=float)
                if values.size != 16:
                    raise ProtocolError(f"SLT needs 16 numbers, got {values.size}")
                self._slt[key] = values.reshape(4, 4).T

    def _locate(self) -> None:
        """Find the ball and the learning robot's torso in a new full scene."""
        scene = self.state.scene
        self._n_nodes = sum(1 for _ in scene.walk())
        balls = scene.find_meshes("soccerball.obj")
        self._ball_path = balls[0][0][:-1] if balls else None
        self._torso_path = None
        if self.agent is not None:
            top = scene.agents().get(self.agent)
            for path, node, _ in scene.walk() if top is not None else ():
                if path[0] != top or not node.is_mesh:
                    continue
                name = (node.model or "").rsplit("/", 1)[-1]
                if name.startswith("naobody") and name.endswith(".obj"):
                    # torso body transform > mesh wrapper transform > mesh (wire reference §7.5)
                    self._torso_path = path[:-2] if len(path) >= 3 else path[:-1]
                    break
        self._slt = {}
        for p in (self._ball_path, self._torso_path):
            for k in range(1, len(p) + 1) if p is not None else ():
                self._slt[p[:k]] = scene.node(p[:k]).slt
        order = {path: i for i, (path, _, _) in enumerate(scene.walk())}
        self._ordinals = [(order[key], key) for key in self._slt]

    def _matrix(self, path: tuple[int, ...]) -> np.ndarray:
        m = np.eye(4)
        for k in range(1, len(path) + 1):
            local = self._slt.get(path[:k])
            if local is not None:
                m = m @ local
        return m

    def _snapshot(self) -> None:
        if self._ball_path is None:
            return
        t = self.time
        ball = self._matrix(self._ball_path)[:3, 3].copy()
        torso = None if self._torso_path is None else self._matrix(self._torso_path)
        ball_vel = self._ball.update(t, ball).copy()
        if torso is not None:
            torso_vel = self._torso.update(t, torso[:3, 3].copy()).copy()
        else:
            torso_vel = np.zeros(3)
        self.snapshots.append(GroundTruthSnapshot(t, ball, torso, ball_vel, torso_vel))

    def restart_velocities(
        self, ball_vel: Sequence[float], game_time: float, clock_running: bool
    ) -> None:
        """After a reset: forget the motion history; the ball moves at ``ball_vel`` in the
        snapshot the reset's percept (``game_time``) is matched with (:meth:`select`). Snapshots
        after it (a frame may run one cycle ahead) get velocities estimated from there on."""
        s = self.select(game_time, clock_running)
        if s is None:
            return
        snaps = list(self.snapshots)
        start = next(k for k, x in enumerate(snaps) if x is s)
        s.ball_vel = np.asarray(ball_vel, dtype=float).copy()
        s.torso_vel = np.zeros(3)
        self._ball.restart(s.game_time, s.ball_pos, s.ball_vel)
        self._torso.restart(s.game_time, None if s.torso is None else s.torso[:3, 3], np.zeros(3))
        for x in snaps[start + 1 :]:
            x.ball_vel = self._ball.update(x.game_time, x.ball_pos).copy()
            if x.torso is not None:
                x.torso_vel = self._torso.update(x.game_time, x.torso[:3, 3].copy()).copy()

    def select(self, game_time: float, clock_running: bool) -> GroundTruthSnapshot | None:
        """The snapshot describing the same cycle as a percept with ``game_time``: the newest
        whose time is not later (frames may run one cycle ahead of percepts, wire reference §2); the
        newest of all when the clock stands still or every frame is later (clock set back)."""
        if not self.snapshots:
            return None
        if clock_running:
            for s in reversed(self.snapshots):
                if s.game_time <= game_time + TIME_TOLERANCE_S:
                    return s
        return self.snapshots[-1]

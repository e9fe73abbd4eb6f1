"""What the server does with an agent's messages (wire reference §3): ``scene`` creates its
robot, ``init`` gives it a team and number (the rules of
:class:`~robocup_gym.sim.teams.TeamRegistry`), hinge velocities, ``beam``, ``say``, ``pass``
and ``syn`` act as on rcssserver3d. A mixin of :class:`~robocup_gym.server.server.SimServer`."""

from __future__ import annotations

import logging
import math
import re

from robocup_gym.protocol import effectors as fx
from robocup_gym.robot.nao import nao_model
from robocup_gym.server.agent import AgentState
from robocup_gym.server.wire import agent_actions, fast_joint_message
from robocup_gym.sim.teams import InitError

log = logging.getLogger("robocup_gym.server")

SCENE_PATHS = ("rsg/agent/nao/nao_hetero.rsg", "rsg/agent/nao/nao.rsg")
"""The robot models a ``scene`` may load (``nao.rsg`` is type 0)."""
_CLIPPED = "%s: velocity %g rad/s is beyond the joint's maximum speed ±%g rad/s; clipped"
_NOT_A_NUMBER = re.compile(rb"\(([a-z]{2,3}\d)\s+([^\s()]+)\s*\)")
"""``(name value)`` items of an agent message, to find values that are not numbers."""
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:inf|nan)", re.I)


def _name(act: object) -> str:
    if isinstance(act, fx.Unknown):
        return act.name
    return type(act).__name__.lower()


class AgentMessages:
    """Agent-message handling of :class:`~robocup_gym.server.server.SimServer`."""

    def _process_agents(self) -> None:
        for a in self.agents:
            if not a.conn.inbox:
                continue
            frames, a.conn.inbox = a.conn.inbox, []
            for frame in frames:
                try:
                    self._agent_frame(a, frame)
                except Exception:
                    log.exception("%r: error while handling %r", a.conn, frame[:200])

    def _agent_frame(self, a: AgentState, frame: bytes) -> None:
        if a.has_robot and not a.killed:
            fast = fast_joint_message(frame)
            if fast is not None:
                items, syn = fast
                limits = self._speed_limits(a)
                joints = a.joints
                for name, value in items:
                    vmax = limits.get(name)
                    if vmax is not None:
                        v = float(value)
                        if math.isfinite(v):  # "1e999" reads as inf
                            joints[name] = v
                            if v > vmax or v < -vmax:
                                a.conn.warn(_CLIPPED, name, v, vmax)
                        else:
                            a.conn.warn("ignored non-finite velocity for %s", name)
                    else:
                        a.conn.warn(
                            "ignored %s: not an effector of a type %s robot", name, a.robot_type
                        )
                if syn:
                    a.synced = a.ever_synced = True
                elif not a.ever_synced:
                    a.synced = True
                return
        actions, ok = agent_actions(frame)
        if not ok:
            a.conn.warn(
                "malformed message (unbalanced parentheses), complete parts used: %r", frame[:120]
            )
        conn = a.conn
        for name, value in _NOT_A_NUMBER.findall(frame):
            if _NUMBER.fullmatch(value) is None:
                conn.warn(
                    "%s: %r is not a number; read as 0 rad/s (as rcssserver3d's atof does)",
                    name.decode("latin-1"),
                    value.decode("latin-1"),
                )
        for act in actions:
            if type(act) is fx.Hinge:
                if a.has_robot and not a.killed:
                    vmax = self._speed_limits(a).get(act.effector)
                    if vmax is not None:
                        v = act.velocity
                        if math.isfinite(v):
                            a.joints[act.effector] = v
                            if v > vmax or v < -vmax:
                                conn.warn(_CLIPPED, act.effector, v, vmax)
                        else:
                            conn.warn("ignored non-finite velocity for %s", act.effector)
                    else:
                        conn.warn(
                            "ignored %s: no such joint on a type %s robot",
                            act.effector,
                            a.robot_type,
                        )
                continue
            if type(act) is fx.Syn:
                if a.has_robot:
                    a.synced = a.ever_synced = True
                continue
            if not a.has_robot:
                if type(act) is fx.Scene and a.robot_type is None:
                    self._scene(a, act)
                elif type(act) is fx.Scene:
                    conn.warn("second scene ignored")
                else:
                    conn.warn("%s ignored: no robot yet (send scene first)", _name(act))
                continue
            if a.killed:
                continue
            if type(act) is fx.Beam:
                if math.isfinite(act.x) and math.isfinite(act.y) and math.isfinite(act.rot):
                    a.beam = (act.x, act.y, act.rot)
                else:
                    conn.warn("beam (%r, %r, %r) ignored: not finite", act.x, act.y, act.rot)
            elif type(act) is fx.Say:
                i = self.world_host.index(a.key)
                if i is not None:
                    self.world.say(i, act.text)
            elif type(act) is fx.Init:
                if a.side is not None:
                    conn.warn("second init ignored (already #%s of %s)", a.unum, a.team_name)
                else:
                    a.init = (act.unum, act.teamname)
            elif type(act) is fx.Pass:
                a.want_pass = True
            elif type(act) is fx.Scene:
                conn.warn("second scene ignored")
            else:
                conn.warn("unknown command %r ignored", _name(act))
        if a.has_robot and (not a.ever_synced or any(type(x) is fx.Init for x in actions)):
            # the handshake: every message counts as (syn) until the first (syn), and an
            # ``init`` always does (see AgentState): a client that kept sending (syn) while it
            # waited for its robot must still get the answer to the ``init`` that follows
            a.synced = True

    def _speed_limits(self, a: AgentState) -> dict[str, float]:
        """Effector name → the joint's maximum speed (rad/s) for the agent's robot type."""
        t = a.robot_type or 0
        limits = self._limits_cache.get(t)
        if limits is None:
            m = nao_model(t)
            limits = self._limits_cache[t] = {
                name: float(v) for name, v in zip(m.effector_names, m.max_speeds, strict=True)
            }
        return limits

    def _scene(self, a: AgentState, act: fx.Scene) -> None:
        path = act.path.lstrip("/")
        if not any(path == p or path.endswith("/" + p) for p in SCENE_PATHS):
            a.conn.warn("scene %r not available (only %s)", act.path, " and ".join(SCENE_PATHS))
            return
        t = act.robot_type
        if t is None or not 0 <= t <= 4:
            a.conn.warn("scene %r: robot type %r not in 0..4", act.path, act.args[:1])
            return
        if t not in self.referee.teams.robot_types:
            allowed = ", ".join(map(str, sorted(self.referee.teams.robot_types)))
            a.conn.warn(
                "scene %r: robot type %s is not allowed here (allowed: %s)", act.path, t, allowed
            )
            return
        a.robot_type = int(t)
        a.scene_type = int(t)

    def _init(self, a: AgentState, unum: int, team: str) -> None:
        host = self.world_host
        i = host.index(a.key)
        if i is None:
            return
        try:
            side, unum = self.referee.teams.register(team, unum, a.robot_type or 0)
        except InitError as exc:
            # The real server teleports the robot to (0, 0, 10) and keeps it; a 10 m drop can
            # destabilise the whole simulation and the robot would stay in the world for good.
            # Here it is removed (next physics step) and the agent's connection closed.
            log.warning(
                "%r: init rejected: %s; its robot is removed and the connection closed", a.conn, exc
            )
            a.killed = True
            a.conn.alive = False
            return
        world = self.world
        world.set_team(i, side, team, unum)
        x, y, z, heading = self.referee.teams.next_slot(side)
        world.place_robot(i, x, y, z=z, heading_deg=heading)
        slot = host.slot(a.key)
        if slot is not None:
            slot.team = side
            slot.home = (x, y, z, heading)
        a.side, a.unum, a.team_name = side, unum, team
        log.info("%r is #%d of %s (%s)", a.conn, unum, team, side)

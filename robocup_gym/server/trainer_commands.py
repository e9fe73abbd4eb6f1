"""What the server does with a monitor connection's trainer commands (wire reference §6): play mode,
moves of robots and the ball, kick-off, time, selecting and killing agents, as rcssserver3d. A
mixin of :class:`~robocup_gym.server.server.SimServer`."""

from __future__ import annotations

import logging
import math

from robocup_gym.protocol import trainer as tc
from robocup_gym.server.agent import AgentState
from robocup_gym.server.wire import Connection, trainer_commands
from robocup_gym.sim.teams import Player

log = logging.getLogger("robocup_gym.server")


class TrainerCommands:
    """Trainer-command handling of :class:`~robocup_gym.server.server.SimServer`."""

    # ------------------------------------------------------------------ monitors / trainer
    def _process_monitors(self) -> None:
        for m in self.monitors:
            if not m.conn.inbox:
                continue
            frames, m.conn.inbox = m.conn.inbox, []
            for frame in frames:
                try:
                    cmds, ok = trainer_commands(frame)
                    if not ok:
                        m.conn.warn("malformed message, complete parts used: %r", frame[:120])
                    for cmd in cmds:
                        self._trainer(m.conn, cmd)
                except Exception:
                    log.exception("%r: error while handling %r", m.conn, frame[:200])

    def _find(self, side: str | None, unum: int | None) -> AgentState | None:
        if side is None or unum is None:
            return None
        side = side.lower()
        for a in self.agents:
            if a.side == side and a.unum == unum and a.has_robot and not a.killed:
                return a
        return None

    def _trainer(self, conn: Connection, cmd: tc.TrainerCommand) -> None:
        host, ref = self.world_host, self.referee
        kind = type(cmd)
        if kind is tc.BallCmd:
            values = [*(cmd.pos or ()), *(cmd.vel or ())]
            if all(math.isfinite(v) for v in values):
                host.set_ball(cmd.pos, cmd.vel)
            else:
                conn.warn("ball command ignored: not finite (pos %r, vel %r)", cmd.pos, cmd.vel)
        elif kind is tc.AgentCmd:
            if cmd.unum is None or cmd.team is None:
                self.selected = None
                return
            a = self._find(cmd.team, cmd.unum)
            i = None if a is None else host.index(a.key)
            if i is None:
                conn.warn("agent command for unknown player %s %s", cmd.team, cmd.unum)
                return
            if cmd.pos is not None:
                if all(math.isfinite(v) for v in cmd.pos):
                    host.teleport(i, cmd.pos)
                else:
                    conn.warn("agent pos %r ignored: not finite", cmd.pos)
            if cmd.move is not None:
                x, y, z, yaw = cmd.move
                if all(math.isfinite(v) for v in cmd.move):
                    host.teleport(i, (x, y, z), heading_deg=yaw + 90.0)
                else:
                    conn.warn("agent move %r ignored: not finite", cmd.move)
            if cmd.rot is not None:  # the SPL fork's: turn about the torso centre
                if all(math.isfinite(v) for v in cmd.rot):
                    host.teleport(i, rot_deg=cmd.rot)
                else:
                    conn.warn("agent rot %r ignored: not finite", cmd.rot)
        elif kind is tc.PlayModeCmd:
            ref.set_play_mode(cmd.mode)
        elif kind is tc.KickOffCmd:
            ref.kick_off(cmd.team)
        elif kind is tc.DropBallCmd:
            ref.drop_ball()
        elif kind is tc.TimeCmd:
            if cmd.time >= 0 and math.isfinite(cmd.time):
                self.world.set_game(game_time=cmd.time)
            else:
                conn.warn("time %r ignored: the game time must be finite and >= 0", cmd.time)
        elif kind is tc.ScoreCmd:
            self.world.set_game(score_left=cmd.left, score_right=cmd.right)
        elif kind is tc.SelectCmd:
            self._select(cmd)
        elif kind is tc.KillCmd:
            a = self._target(cmd.unum, cmd.team)
            if a is not None:
                log.info("trainer kills %s #%s", a.side, a.unum)
                self._release(a)
                a.killed = True
        elif kind is tc.ReposCmd:
            a = self._target(cmd.unum, cmd.team)
            i = None if a is None else host.index(a.key)
            if a is not None and i is not None:
                ref.players = self._players()
                ref.repos(Player(a.key, i, a.side, a.unum))  # type: ignore[arg-type]
        elif kind is tc.ReqFullStateCmd:
            self._full_requested = True
        elif kind is tc.KillSimCmd:
            log.info("(killsim) from %r: shutting down", conn)
            self.request_stop()
        elif kind is tc.InvalidCmd:
            conn.warn("malformed %s command ignored: %s", cmd.name, cmd.reason)
        elif kind is tc.UnknownCmd:
            conn.warn("unknown trainer command %r ignored", cmd.name)

    def _target(self, unum: int | None, team: str | None) -> AgentState | None:
        if unum is None or team is None:
            if self.selected is None:
                return None
            return self._find(*self.selected)
        return self._find(team, unum)

    def _select(self, cmd: tc.SelectCmd) -> None:
        if cmd.unum == -1:
            self.selected = None
        elif cmd.unum is not None and cmd.team is not None:
            if self._find(cmd.team, cmd.unum) is not None:
                self.selected = (cmd.team.lower(), cmd.unum)
        else:
            players = sorted(
                (a.side, a.unum) for a in self.agents if a.side and a.has_robot and not a.killed
            )
            if not players:
                self.selected = None
                return
            if self.selected in players:
                self.selected = players[(players.index(self.selected) + 1) % len(players)]
            else:
                self.selected = players[0]  # type: ignore[assignment]

    def _release(self, a: AgentState) -> None:
        if a.side is not None and a.unum is not None and not a.killed:
            self.referee.teams.release(a.side, a.unum)

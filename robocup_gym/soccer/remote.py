"""A team on a server: ``robocup-gym team POLICY --host H --port P --team NAME --players N``.

Each player is its own agent connection (``scene``, ``init`` with its uniform number, then a
command every cycle), as a real team's players are, on ``robocup-gym serve`` or a real
rcssserver3d. The players run in one process and share nothing a server would not tell them
except their own estimates (no ``say``/``hear`` yet).

A player knows only what its perceptors tell it: its state and the ball come from its
:class:`~robocup_gym.soccer.localisation.Estimator` (landmarks seen, head joints, gyroscope,
accelerometer), never from ground truth, which competition servers do not send. The skills are
the game's (:class:`~robocup_gym.soccer.skills.SkillSet`: the shipped walk and get-up, the
scripted kick) reading that estimate; the team decides every ``decision_cycles`` cycles as in
the in-process game (a scripted team from :meth:`ServerTeam.team_view`, a learnt one from its
players' observations, the privileged part filled from the estimates: its teammates' and the
ball's, and the opponents where its players last saw them).

Before kick-off and after a goal every player beams to its place in the kick-off formation
(:func:`~robocup_gym.soccer.formation.kickoff_positions`) and stands. The game starts when the
server's referee (or a trainer, RoboViz, …) says kick-off; the team plays until ``GameOver``,
``seconds`` of game time, or the server closes the connections.
"""

from __future__ import annotations

import contextlib
import select
import socket
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.envs.observations import heading_frame
from robocup_gym.protocol.effectors import format_command, format_init, format_scene
from robocup_gym.protocol.framing import (
    FrameDecoder,
    connect,
    decode_payload,
    recv_frame,
    send_frame,
)
from robocup_gym.protocol.perceptors import parse_perception
from robocup_gym.robot.nao import nao_model
from robocup_gym.robot.types import is_type_number
from robocup_gym.sim.referee import BEAM_MODES, next_kickoff_side
from robocup_gym.soccer.formation import kickoff_positions
from robocup_gym.soccer.localisation import Estimator, level_offsets
from robocup_gym.soccer.scripted import TeamView
from robocup_gym.soccer.skills import (
    DEFAULT_WALK,
    SkillSet,
    checked_action,
    skills_of_teams,
    walk_of_teams,
)
from robocup_gym.types import AgentCommand, Perception, is_integer

__all__ = ["RemotePlayer", "ServerTeam", "TeamResult", "check_server_walk"]


def check_server_walk(*teams: Any) -> None:
    """Refuse a team trained with a walk other than the one its players walk with on a
    server (:data:`~robocup_gym.soccer.skills.DEFAULT_WALK`).

    Raises:
        ValueError: such a team (or two teams trained with different walks).
    """
    walk = walk_of_teams(*teams)
    if walk != DEFAULT_WALK:
        raise ValueError(
            f"a team was trained with the walk {walk!r}; on a server the players walk with "
            f"{DEFAULT_WALK} (play it in-process: robocup-gym match)"
        )


HEAD_TILT_DEG = -30.0
"""Where a walking player on a server holds its head (``hj2``, deg; negative looks down). The
camera's view cone reaches 60° either side of its axis: with the head level a ball closer than
~0.3 m lies below it, and a player walking onto the ball would steer by an estimate that no
longer sees it; tilted 30° down, the ball at the feet stays in view and so do the landmarks on
the horizon."""
HEAD_GAIN = 10.0
"""The head's joint velocity (rad/s) per radian from :data:`HEAD_TILT_DEG`."""


class ServerGoneError(ConnectionError):
    """The server closed a player's connection or stopped answering."""


class RemotePlayer:
    """One player's connection: ``scene`` and ``init``, then one percept and one command a cycle.

    Raises:
        ConnectionError: nothing listens at ``host:port``, or the server closes the connection.
    """

    def __init__(
        self,
        host: str,
        port: int,
        team: str,
        unum: int,
        robot_type: int,
        *,
        timeout: float = 10.0,
        connect_s: float = 5.0,
    ) -> None:
        self.team, self.unum, self.robot_type = team, int(unum), int(robot_type)
        self.timeout = float(timeout)
        try:
            self.sock: socket.socket = connect(host, int(port), retry_s=connect_s)
        except OSError as exc:
            raise ConnectionError(
                f"no server at {host}:{port} ({exc.strerror or exc}); start one with "
                "`robocup-gym serve` or rcssserver3d"
            ) from None
        self.decoder = FrameDecoder()
        self.side: str | None = None
        self.model = nao_model(self.robot_type)
        effectors = [j.effector for j in self.model.joints]
        self._head = (effectors.index("he1"), effectors.index("he2"))
        self.estimator = Estimator(self.model)
        self.last: Perception | None = None
        self.stage = "scene"
        """Handshake: ``scene`` sent, ``init`` sent, ``ready`` (the server told side and
        number)."""
        self._send(format_scene(self.robot_type))

    def handshake_step(self) -> None:
        """Read the percept waiting and answer it with the handshake's next message."""
        p = self.perceive()
        if self.stage == "scene":
            self._send(format_init(self.unum, self.team))
            self.stage = "init"
            return
        if self.stage == "init" and self.side is not None and p.game.play_mode:
            self.stage = "ready"
        self.answer()

    def answer(self) -> None:
        """Answer the percept read last with ``(syn)`` alone (a joined player before the
        game)."""
        self._send("")

    def _send(self, text: str) -> None:
        if not text.endswith("(syn)"):
            text += "(syn)"
        try:
            send_frame(self.sock, text, self.timeout)
        except OSError as exc:
            raise ServerGoneError(f"player {self.unum}: the server is gone ({exc})") from None

    def _recv(self) -> str:
        try:
            return decode_payload(recv_frame(self.sock, self.decoder, self.timeout))
        except (ConnectionError, TimeoutError) as exc:
            raise ServerGoneError(f"player {self.unum}: the server is gone ({exc})") from None

    def perceive(self) -> Perception:
        """The newest percept (older ones waiting in the socket are skipped: a team that fell
        behind a real-time server acts on what is now), its ground truth set to the player's
        own estimate.

        The side and number the server says once, after ``init``, are taken from a skipped
        percept too: a server in sync mode does not wait for a player in its first cycles, so
        that percept may come with the next one behind it."""
        texts = [self._recv()]
        while True:
            frame = self.decoder.pop_frame()
            if frame is None:
                if not select.select([self.sock], [], [], 0.0)[0]:
                    break
                texts.append(self._recv())
            else:
                texts.append(decode_payload(frame))
        for text in texts[:-1]:
            if "(unum" in text:
                self._identify(parse_perception(text, robot_type=self.robot_type))
        p = parse_perception(texts[-1], robot_type=self.robot_type)
        self._identify(p)
        p.ground_truth = self.estimator.update(p)
        self.last = p
        return p

    def _identify(self, p: Perception) -> None:
        """Take the side and number the server told."""
        if p.game.team_side is not None:
            self.side = p.game.team_side
        if p.game.unum is not None:
            self.unum = p.game.unum

    def send(self, command: AgentCommand) -> None:
        self._send(format_command(command, self.robot_type, sync=True))

    def holding_the_head(self, command: AgentCommand) -> AgentCommand:
        """``command`` (a walk's, which leaves the head alone) with the head turned to the
        front and tilted to :data:`HEAD_TILT_DEG`."""
        joints = self.model.joints
        v = command.joint_velocities
        if isinstance(v, np.ndarray):
            v = np.array(v, dtype=float)
        else:  # by name: into the canonical order
            v = np.array([float(v.get(j.effector, 0.0)) for j in joints])
        for i, target in ((self._head[0], 0.0), (self._head[1], HEAD_TILT_DEG)):
            now = self.last.joint(joints[i].perceptor) if self.last is not None else 0.0
            limit = joints[i].max_speed
            v[i] = np.clip(HEAD_GAIN * np.radians(target - now), -limit, limit)
        return AgentCommand(v, command.joint_pd, command.beam, command.say)

    def beam(self, x: float, y: float, heading_deg: float) -> AgentCommand:
        """The command that beams to ``(x, y, heading)`` (own team's frame) and standing still
        there; the estimate starts from that pose (world frame)."""
        s = -1.0 if self.side == "right" else 1.0
        self.estimator.place(s * x, s * y, heading_deg + (180.0 if s < 0 else 0.0))
        return AgentCommand(np.zeros(len(self.model.joints)), beam=(x, y, heading_deg))

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()


@dataclass
class TeamResult:
    """How a team's game on a server went, from its side."""

    team: str
    side: str
    goals_for: int = 0
    goals_against: int = 0
    game_time: float = 0.0
    cycles: int = 0
    end: str = ""
    """Why it ended: ``GameOver``, ``time`` or the server's going."""
    falls: int = 0
    """Times a player went down (its get-up started)."""
    events: list[str] = field(default_factory=list)

    @property
    def summary(self) -> dict[str, Any]:
        return {
            "team": self.team,
            "side": self.side,
            "goals_for": self.goals_for,
            "goals_against": self.goals_against,
            "game_time": round(self.game_time, 2),
            "cycles": self.cycles,
            "falls": self.falls,
            "end": self.end,
        }


class ServerTeam:
    """``players`` agents on a server, playing with ``team`` (``team(self, agents, obs) →
    {agent: skill action}``, as the in-process game calls it).

    Args:
        team: The team (:func:`robocup_gym.soccer.match.make_team`).
        host, port: The server's agent port.
        name: The team's name (``init``).
        players: How many players (uniform numbers 1…N; number 1 keeps goal in a team of
            several).
        robot_types: Their Nao types (default 0, 1, 2, 3, 4 in turn … as the in-process game).
        decision_cycles: Cycles between the team's decisions (the skill actions' 10).
        timeout: Seconds to wait for a percept before the server counts as gone (and, up to
            5 s, for a server that is still starting to take the connection).
        seed: Seeds the skills (each start of play draws its skills' seeds from it); with a
            server in sync mode started with a seed, a game is then the same every time on one
            machine. ``None``: fresh randomness.
        alongside: A team already on the server that this one joins beside, from the same
            thread (its players are held and answered while this team's join, so that both
            teams are in fixed cycles: it must not play meanwhile).
    """

    def __init__(
        self,
        team: Callable[..., dict[str, np.ndarray]],
        host: str = "127.0.0.1",
        port: int = 3100,
        name: str = "RoboCupGym",
        players: int = 2,
        robot_types: Sequence[int] | None = None,
        *,
        decision_cycles: int = 10,
        timeout: float = 10.0,
        seed: int | None = None,
        alongside: ServerTeam | None = None,
    ) -> None:
        if not (is_integer(players) and 1 <= players <= 11):
            raise ValueError(f"a team has 1-11 players, got {players!r}")
        if not (is_integer(port) and 1 <= port <= 65535):
            raise ValueError(f"port must be a port number 1-65535, got {port!r}")
        types = list(robot_types) if robot_types is not None else [k % 4 for k in range(players)]
        if len(types) != players or not all(map(is_type_number, types)):
            raise ValueError(f"give {players} robot types of 0-4, got {robot_types!r}")
        check_server_walk(team)
        self.team = team
        self.name = name
        self.decision_cycles = int(decision_cycles)
        self._rng = np.random.default_rng(seed)
        self.players: list[RemotePlayer] = []
        self._alongside = list(alongside.players) if alongside is not None else []
        try:
            for k in range(players):  # one at a time: see _handshake
                waiting = self._hold()
                self.players.append(
                    RemotePlayer(
                        host,
                        port,
                        name,
                        k + 1,
                        int(types[k]),
                        timeout=timeout,
                        connect_s=min(float(timeout), 5.0),
                    )
                )
                for p in waiting:
                    p.answer()
                self._handshake(timeout)
        except BaseException:
            self.close()
            raise
        self.skills = SkillSet(  # the self-collision rule as every server applies it
            types, self_collisions=True, motions=skills_of_teams(team)
        )
        self._observers: dict[str, Any] = {}
        self._opponents: dict[int, np.ndarray] = {}
        """Where the team's players last saw each opponent (by uniform number), world (x, y)."""

    @property
    def skill_action_labels(self) -> tuple[str, ...]:
        """The values of the team's skill actions (the walk's, then its motion skills')."""
        return self.skills.action_labels

    def _hold(self) -> list[RemotePlayer]:
        """Read the joined players' next percept and leave it unanswered: a server in sync mode
        then waits for them, so a player that connects now joins in that cycle on every machine
        and under any load (answered at once, the server would run on meanwhile, and the cycle
        in which the next player's ``scene`` lands would vary, and with it the whole game)."""
        held = self.players + self._alongside
        for p in held:
            p.perceive()
        return held

    def _handshake(self, timeout: float) -> None:
        """Answer every player's percepts as they come (a server in sync mode waits for each
        connected player's reply before the next cycle) until the server has told every player
        its side and number.

        The team calls this after each new player's ``scene``, so the players join one at a
        time. A robot enters the world at the centre of the field and stays there until its
        ``init`` places it at the touchline; robots that enter together lie inside one another,
        and rcssserver3d's physics step on that heap takes seconds a cycle (5 at once: 5-10 s
        to join, 11: not within a minute; one at a time, 11 join in a few seconds).

        It returns when every player has answered the same cycle's percept: a player that had
        answered it while another's was still on its way would wait for the next percept, which
        the server sends only once the other has answered, and the team answers all its
        players together."""
        deadline = time.monotonic() + timeout
        everyone = self.players + self._alongside

        def behind() -> list[RemotePlayer]:
            if any(p.stage != "ready" for p in everyone):
                return everyone
            newest = max(p.last.time for p in everyone)
            return [p for p in everyone if p.last.time < newest]

        while players := behind():
            left = deadline - time.monotonic()
            if left <= 0:
                raise ServerGoneError(
                    f"the server did not take all {len(self.players)} players within "
                    f"{timeout:g} s (is the team full, or another team named {self.name!r} "
                    "playing?)"
                )
            by_sock = {p.sock: p for p in players}
            ready = {p.sock for p in players if p.decoder.pending}
            ready |= set(select.select(list(by_sock), [], [], min(left, 0.5))[0])
            for sock in ready:
                by_sock[sock].handshake_step()

    # ------------------------------------------------------------------ what teams ask
    @property
    def side(self) -> str:
        return self.players[0].side or "left"

    @property
    def agents(self) -> list[str]:
        return [f"{self.side}_{p.unum}" for p in self.players]

    def goalkeepers(self) -> set[str]:
        """Uniform number 1 of a team of several."""
        return {self.agents[0]} if len(self.players) > 1 else set()

    def side_of(self, agent: str) -> str:
        return self.side

    def team_view(self, agents: list[str]) -> TeamView:
        """What a scripted team decides from: each player's own estimate, and the ball where the
        player that saw it last saw it."""
        gts = {a: p.last.ground_truth for a, p in zip(self.agents, self.players, strict=True)}
        seen = [p for p in self.players if p.estimator.localiser.ball_xy is not None]
        ball = np.zeros(2)
        if seen:
            freshest = min(seen, key=lambda p: p.estimator.localiser.cycles_since_ball)
            ball = freshest.estimator.localiser.ball_xy.copy()
        return TeamView(
            side=self.side,
            ball=ball,
            positions={a: gts[a].torso_pos[:2].copy() for a in agents},
            headings={a: heading_frame(gts[a].torso_quat) for a in agents},
            keepers=self.goalkeepers() & set(agents),
            play_mode=self.players[0].last.game.play_mode,
            opponents=np.array(list(self._opponents.values()), dtype=float).reshape(-1, 2),
        )

    # ------------------------------------------------------------------ observations
    def _see_opponents(self, p: RemotePlayer) -> None:
        v = p.last.vision
        loc = p.estimator.localiser
        if v is None or loc.fix is None:
            return
        offsets = level_offsets(
            {
                pl.unum: pl.parts["head"]
                for pl in v.players
                if pl.team != self.name and "head" in pl.parts
            },
            p.last.joint("hj1"),
            p.last.joint("hj2"),
            p.estimator.up,
        )
        for unum, rel in offsets.items():
            self._opponents[int(unum)] = loc.seen_at(rel)

    def _observations(self) -> dict[str, np.ndarray] | None:
        privileged = getattr(self.team, "privileged", None)
        if privileged is None:  # a scripted team: no observations
            return None
        from robocup_gym.soccer.observations import PlayerObserver

        n = len(self.players)
        agents = self.agents
        if not self._observers:
            for a, p in zip(agents, self.players, strict=True):
                self._observers[a] = PlayerObserver(p.model, self.side, privileged, n - 1, n)
        mates = {
            a: p.last.ground_truth.torso_pos[:2] for a, p in zip(agents, self.players, strict=True)
        }
        ball = self.team_view(agents).ball
        out = {}
        for a, p in zip(agents, self.players, strict=True):
            others = None
            if privileged:
                opp = [self._opponents.get(u, np.zeros(2)) for u in range(1, n + 1)]
                others = np.array([mates[m] for m in agents if m != a] + opp)
                gt = p.last.ground_truth
                gt.ball_pos[:2] = ball  # the team's freshest sighting
            out[a] = self._observers[a](p.last, others)
        return out

    # ------------------------------------------------------------------ the game
    def play(
        self,
        seconds: float | None = None,
        on_event: Callable[[str], None] | None = None,
        on_cycle: Callable[[Perception], None] | None = None,
    ) -> TeamResult:
        """Play until ``GameOver``, ``seconds`` of game time (from the first percept) or the
        server's going; returns the result (the connections stay open: :meth:`close`).

        ``on_event`` is told the goals as text; ``on_cycle`` gets the first player's percept
        every cycle before the team answers it (on a server in sync mode a trainer command it
        sends is read in that cycle: with a monitor interval of 1 it takes effect there)."""
        result = TeamResult(self.name, self.side)

        def event(text: str) -> None:
            result.events.append(text)
            if on_event is not None:
                on_event(text)

        started = False
        start_time: float | None = None
        beamed_in: str | None = None
        labels = self.skills.action_labels
        actions = {k: np.zeros(len(labels)) for k in range(len(self.players))}
        score = (0, 0)
        try:
            while True:
                perceptions = {k: p.perceive() for k, p in enumerate(self.players)}
                first = perceptions[0]
                if on_cycle is not None:
                    on_cycle(first)
                g = first.game
                result.side = self.side
                if start_time is None:
                    start_time = g.game_time
                result.game_time = g.game_time
                result.cycles += 1
                own, other = (
                    (g.score_left, g.score_right)
                    if self.side == "left"
                    else (g.score_right, g.score_left)
                )
                if (own, other) != score:
                    who = self.name if own > score[0] else "the opponents"
                    event(f"{g.game_time:.1f} s: goal for {who}, {own}:{other}")
                    score = (own, other)
                result.goals_for, result.goals_against = score
                if g.play_mode == "GameOver":
                    result.end = "GameOver"
                    break
                if seconds is not None and g.game_time - start_time >= seconds:
                    result.end = "time"
                    break
                commands: dict[int, AgentCommand] = {}
                stopped = g.play_mode in BEAM_MODES  # the team beams to its formation and stands
                if stopped and beamed_in != g.play_mode:  # beam once per stop, then stand
                    # (a beam is in the team's own frame: as the left team's places)
                    kicker = next_kickoff_side(g.play_mode, g.game_time)
                    places = kickoff_positions("left", len(self.players), kicker == self.side)
                    for k, p in enumerate(self.players):
                        commands[k] = p.beam(*places[k])
                    beamed_in = g.play_mode
                    started = False
                else:
                    if not stopped:
                        beamed_in = None
                    if not started:
                        self.skills.reset(perceptions, int(self._rng.integers(2**31)))
                        started = True
                if started:
                    before = self.skills.modes()
                    self.skills.observe(perceptions)
                    result.falls += sum(
                        a != "get-up" and b == "get-up"
                        for a, b in zip(before, self.skills.modes(), strict=True)
                    )
                    if result.cycles % self.decision_cycles == 0:
                        for p in self.players:
                            self._see_opponents(p)
                        if stopped:
                            decided = {a: np.zeros(len(labels)) for a in self.agents}
                        else:
                            decided = self.team(self, self.agents, self._observations())
                        for k, a in enumerate(self.agents):
                            actions[k] = checked_action(
                                a,
                                decided.get(a, actions[k]),
                                labels,
                                self.skills.action_what,
                            )
                            self.skills.decide(k, actions[k])
                    modes = self.skills.modes()
                    for k, c in self.skills.commands().items():
                        if modes[k] == "walk":
                            c = self.players[k].holding_the_head(c)
                        commands.setdefault(k, c)
                for k, p in enumerate(self.players):
                    p.send(commands.get(k, AgentCommand()))
        except ServerGoneError as exc:
            result.end = f"the server went away ({exc})"
        return result

    def close(self) -> None:
        for p in self.players:
            p.close()

    def __enter__(self) -> ServerTeam:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

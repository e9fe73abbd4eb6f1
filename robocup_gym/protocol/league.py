"""RCSSServerMJ's agent protocol (the league's server since 2026): its perception messages into
the library's :class:`~robocup_gym.types.Perception`, and joint commands into wire text.

A perception message holds ``(time (now t))``, ``(GS (t …)(pm …)(tl …)(tr …)(sl …)(sr …))``, the
torso's ``(pos (n torso_pos) (p x y z))`` and ``(quat (n torso_quat) (q w x y z))``,
``(GYR (n …) (rt x y z))`` in deg/s, ``(ACC (n …) (a x y z))`` in m/s², one
``(HJ (n q_<joint>)(ax deg)(vx deg/s))`` per joint, ``(TCH n … val …)`` touch sensors and, every
second cycle, ``(See …)`` with polar ``(pol d θ φ)`` detections.

Frames: the league's models put the torso's x axis forward and y to the left; the library's
:class:`Perception` and :class:`~robocup_gym.types.GroundTruth` use SimSpark's torso axes (x to
the robot's right, y forward, z up) for every robot, so observations mean the same on the Nao
and on the T1. :func:`parse_league_perception` therefore turns the gyro and accelerometer into
those axes (``x_s = −y``, ``y_s = x``), and :func:`to_simspark_torso_quat` does the same for an
orientation. The raw values are in :attr:`LeaguePerception.raw_torso_pos` /
:attr:`LeaguePerception.raw_torso_quat` as sent.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.sexpr import SExpr, parse
from robocup_gym.types import GameState, PDCommand, Perception, SeenPlayer, Vision

__all__ = [
    "LeagueMonitorReader",
    "LeaguePerception",
    "format_pd_commands",
    "from_simspark_torso_quat",
    "league_perception",
    "parse_league_perception",
    "to_simspark_torso_quat",
]

_S = math.sqrt(0.5)


def to_simspark_torso_quat(q: Sequence[float]) -> np.ndarray:
    """A league robot's torso orientation ``(w, x, y, z)`` (x forward, y left) as the
    orientation of SimSpark's torso axes (x right, y forward, z up): ``q ⊗ rot_z(−90°)``."""
    w, x, y, z = (float(v) for v in q)
    # Hamilton product with (s, 0, 0, -s)
    return np.array([_S * (w + z), _S * (x - y), _S * (x + y), _S * (z - w)])


def from_simspark_torso_quat(q: Sequence[float]) -> np.ndarray:
    """The inverse of :func:`to_simspark_torso_quat`: SimSpark's torso axes to a league
    model's, ``q ⊗ rot_z(+90°)``."""
    w, x, y, z = (float(v) for v in q)
    # Hamilton product with (s, 0, 0, s)
    return np.array([_S * (w - z), _S * (x + y), _S * (y - x), _S * (z + w)])


@dataclass
class LeaguePerception(Perception):
    """A :class:`Perception` from RCSSServerMJ, with the torso pose perceptors it adds."""

    raw_torso_pos: np.ndarray | None = None
    """``pos`` perceptor: torso position, m, world frame, as sent."""
    raw_torso_quat: np.ndarray | None = None
    """``quat`` perceptor: torso orientation ``(w, x, y, z)`` in the model's axes, as sent."""
    touch: dict[str, bool] | None = None
    """``TCH`` sensors by name: whether each touches something."""


def _num(item: list[SExpr], i: int, what: str) -> float:
    try:
        return float(item[i])  # type: ignore[arg-type]
    except (IndexError, TypeError, ValueError):
        raise ProtocolError(f"malformed {what} in an RCSSServerMJ perception: {item!r}") from None


def _sub(expr: list[SExpr], key: str) -> list[SExpr] | None:
    for e in expr[1:]:
        if isinstance(e, list) and e and e[0] == key:
            return e
    return None


def _vec(expr: list[SExpr], key: str, n: int, what: str) -> np.ndarray:
    sub = _sub(expr, key)
    if sub is None or len(sub) != n + 1:
        raise ProtocolError(f"{what} without ({key} …{n} numbers) in an RCSSServerMJ perception")
    return np.array([_num(sub, i + 1, what) for i in range(n)])


def _see(expr: list[SExpr]) -> Vision:
    v = Vision()
    for item in expr[1:]:
        if not isinstance(item, list) or not item or not isinstance(item[0], str):
            raise ProtocolError(f"malformed See entry {item!r}")
        pol = _sub(item, "pol")
        if pol is not None:
            v.objects[item[0]] = np.array([_num(pol, i, "See pol") for i in (1, 2, 3)])
            continue
        team, ident = _sub(item, "team"), _sub(item, "id")
        if team is None or ident is None or len(team) < 2 or len(ident) < 2:
            raise ProtocolError(f"See entry {item[0]!r} is neither (pol …) nor a player")
        player = SeenPlayer(team=str(team[1]), unum=int(_num(ident, 1, "See id")))
        for part in item[1:]:
            if isinstance(part, list) and part and part[0] not in ("team", "id"):
                ppol = _sub(part, "pol")
                if ppol is not None:
                    player.parts[str(part[0])] = np.array(
                        [_num(ppol, i, "See pol") for i in (1, 2, 3)]
                    )
        v.players.append(player)
    return v


def parse_league_perception(
    msg: str | bytes | bytearray, joint_names: Sequence[str] | None = None
) -> LeaguePerception:
    """One RCSSServerMJ perception message as a :class:`LeaguePerception` (see the module
    docstring for units and frames).

    Args:
        msg: The message (without the 4-byte length prefix).
        joint_names: The ``HJ`` names in the order wanted (the robot's model order); ``None``:
            the order of the message.

    Raises:
        ProtocolError: malformed text, a perceptor without its values, or ``joint_names``
            that the message does not all have (naming the missing ones).
    """
    exprs = parse(msg)
    now = None
    game = GameState()
    gyro = accel = pos = quat = None
    hj_names: list[str] = []
    hj_ax: list[float] = []
    hj_vx: list[float] = []
    vision = None
    touch: dict[str, bool] = {}
    for e in exprs:
        if not isinstance(e, list) or not e:
            raise ProtocolError(f"unexpected top-level atom {e!r} in an RCSSServerMJ perception")
        head = e[0]
        if head == "time":
            sub = _sub(e, "now")
            if sub is None:
                raise ProtocolError("(time …) without (now t)")
            now = _num(sub, 1, "time")
        elif head == "GS":
            for item in e[1:]:
                if not isinstance(item, list) or len(item) < 2:
                    continue
                key, val = item[0], item[1]
                if key == "t":
                    game.game_time = _num(item, 1, "GS t")
                elif key == "pm":
                    game.play_mode = str(val)
                elif key == "sl":
                    game.score_left = int(_num(item, 1, "GS sl"))
                elif key == "sr":
                    game.score_right = int(_num(item, 1, "GS sr"))
                elif key == "unum":
                    game.unum = int(_num(item, 1, "GS unum"))
        elif head == "GYR":
            gyro = _vec(e, "rt", 3, "GYR")
        elif head == "ACC":
            accel = _vec(e, "a", 3, "ACC")
        elif head == "pos":
            pos = _vec(e, "p", 3, "pos")
        elif head == "quat":
            quat = _vec(e, "q", 4, "quat")
        elif head == "HJ":
            name = _sub(e, "n")
            if name is None or len(name) != 2:
                raise ProtocolError(f"HJ without (n name): {e!r}")
            hj_names.append(str(name[1]))
            hj_ax.append(float(_vec(e, "ax", 1, "HJ")[0]))
            vx = _sub(e, "vx")
            hj_vx.append(_num(vx, 1, "HJ vx") if vx is not None else math.nan)
        elif head == "TCH":
            # (TCH n <name> val <0|1>): flat, not nested
            try:
                touch[str(e[e.index("n") + 1])] = str(e[e.index("val") + 1]) not in ("0", "False")
            except (ValueError, IndexError):
                raise ProtocolError(f"malformed TCH {e!r}") from None
        elif head == "See":
            vision = _see(e)
        # other perceptors (hear, …) are not used by the environments and are skipped
    if now is None:
        raise ProtocolError("RCSSServerMJ perception without (time (now t))")
    if gyro is None or accel is None:
        raise ProtocolError("RCSSServerMJ perception without GYR and ACC")
    ax = np.array(hj_ax)
    vx = np.array(hj_vx)
    names = tuple(hj_names)
    if joint_names is not None:
        index = {n: i for i, n in enumerate(hj_names)}
        missing = [n for n in joint_names if n not in index]
        if missing:
            raise ProtocolError(f"the perception has no HJ for {', '.join(missing)}")
        order = [index[n] for n in joint_names]
        ax, vx, names = ax[order], vx[order], tuple(joint_names)
    return league_perception(
        time=now,
        game=game,
        gyro=gyro,
        accel=accel,
        joint_names=names,
        q_deg=ax,
        dq_deg_s=vx,
        pos=pos,
        quat=quat,
        vision=vision,
        touch=touch,
    )


def league_perception(
    *,
    time: float,
    game: GameState,
    gyro: Sequence[float],
    accel: Sequence[float],
    joint_names: Sequence[str],
    q_deg: np.ndarray,
    dq_deg_s: np.ndarray,
    pos: np.ndarray | None,
    quat: np.ndarray | None,
    vision: Vision | None = None,
    touch: dict[str, bool] | None = None,
) -> LeaguePerception:
    """A :class:`LeaguePerception` of the values RCSSServerMJ sends (the gyro, deg/s, and the
    accelerometer, m/s², in the model's axes: they are turned into SimSpark's torso axes here,
    ``x_s = −y``, ``y_s = x``); the one place the parser and the in-process world's readings
    make perceptions."""
    return LeaguePerception(
        time=time,
        game=game,
        gyro=np.array([-gyro[1], gyro[0], gyro[2]], dtype=float),
        accel=np.array([-accel[1], accel[0], accel[2]], dtype=float),
        joint_names=tuple(joint_names),
        joint_angles_deg=q_deg,
        joint_velocities_deg_s=dq_deg_s,
        vision=vision,
        raw_torso_pos=pos,
        raw_torso_quat=quat,
        touch={} if touch is None else touch,
    )


def format_pd_commands(commands: Mapping[str, PDCommand]) -> bytes:
    """The wire text of joint commands ``name → PDCommand`` (``(name q dq kp kd tau)``, degrees
    and degrees per second; numbers written exactly, as Python's ``repr``), then ``(syn)``."""
    parts = [
        f"({name} {c.q_deg!r} {c.dq_deg_s!r} {c.kp!r} {c.kd!r} {c.tau!r})"
        for name, c in commands.items()
    ]
    return ("".join(parts) + "(syn)").encode()


class LeagueMonitorReader:
    """Follows RCSSServerMJ's monitor stream (RSMP: ``((RSMP 1 0)((gt 1 0)<time>)((sg 1 0)
    full|diff <nodes>)…)``, every second cycle) and gives the ground truth a training backend
    needs from it: the ball's position (4 decimals, m) and the simulation time.

    The scene graph is the SimSpark monitor's node format with description nodes
    (``(nd DSC(ball) …)``); deltas are applied by position
    (:class:`~robocup_gym.protocol.scenegraph.SceneGraph`).
    """

    def __init__(self) -> None:
        from robocup_gym.protocol.scenegraph import SceneGraph

        self.graph = SceneGraph()
        self.time: float | None = None
        """Simulation time of the last message, s."""
        self.messages = 0

    def feed(self, message: bytes | str) -> None:
        """Take one monitor message.

        Raises:
            ProtocolError: not an RSMP message, or a delta before any full scene.
        """
        from robocup_gym.protocol.scenegraph import parse_delta_nodes, parse_scene_nodes

        exprs = parse(message)
        if (
            len(exprs) != 1
            or not isinstance(exprs[0], list)
            or not exprs[0]
            or not isinstance(exprs[0][0], list)
            or exprs[0][0][:1] != ["RSMP"]
        ):
            raise ProtocolError("not an RSMP monitor message (expected ((RSMP 1 0) …))")
        for part in exprs[0][1:]:
            if not isinstance(part, list) or not part or not isinstance(part[0], list):
                continue
            kind = part[0][0] if part[0] else None
            if kind == "gt" and len(part) > 1:
                self.time = _num(part, 1, "RSMP gt")
            elif kind == "sg" and len(part) > 1:
                if part[1] == "full":
                    self.graph.nodes = parse_scene_nodes(part[2:])
                elif part[1] == "diff":
                    if not self.graph.nodes:
                        raise ProtocolError("RSMP scene delta before any full scene")
                    self.graph.apply_delta(parse_delta_nodes(part[2:]))
        self.messages += 1

    def ball_position(self) -> np.ndarray | None:
        """The ball's centre (m, world frame) in the last scene, or ``None`` before one."""
        for _, node, world in self.graph.walk():
            if node.kind == "DSC" and "ball" in node.props:
                for child in node.children:
                    if child.slt is not None:
                        return (world @ child.slt)[:3, 3].copy()
        return None

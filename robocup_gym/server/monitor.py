"""The monitor stream (SparkMonitor format, wire reference §7): environment + ``RSG``/``RDS`` scene.

Every frame is three expressions: the environment/game-state list, ``(RSG 0 1)`` or ``(RDS 0 1)``,
and the scene graph. The scene is the one of rcssserver3d's soccer world (lights, field, sky box,
goals, borders, flag and line transforms, the ball) followed by one top-level subtree per agent
connection in connection order: an empty identity transform for a connection without robot, and
for a robot the flat list of SimSpark's body transforms (world pose of every body) with the Nao
meshes and materials RoboViz needs to find and draw the agent (``matNum<N>``, ``matLeft`` /
``matRight``, ``naobody<type>.obj`` …).

A full frame (``RSG``) is sent after any structural change (a connection, a robot imported or
removed, an ``init`` that changes materials) and on ``(reqfullstate)``; otherwise a delta (``RDS``)
of exactly the same shape repeats a transform only if one of its 16 numbers moved by more than
0.005 since it was last sent. Numbers use C++ stream formatting (``%g``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from robocup_gym.protocol.constants import DEFAULT_ENVIRONMENT, PLAY_MODES, play_mode_id
from robocup_gym.protocol.values import fmt_g

if TYPE_CHECKING:
    from robocup_gym.sim.kick_rules import KickRules

SLT_THRESHOLD = 0.005

_IDENTITY = "(SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1)"
_WRAP = "(SLT -1 3.82137e-15 8.74228e-08 -0 8.74228e-08 4.37114e-08 1 0 0 1 -4.37114e-08 0 0 0 0 1)"
_ROT_X = "-1 -8.74228e-08 -3.82137e-15 0 0 -4.37114e-08 1 0 -8.74228e-08 1 4.37114e-08 -0"
_GOAL_MESH_SLT = (
    "(SLT -4.37114e-08 1 4.37114e-08 0 0 -4.37114e-08 1 0 1 4.37114e-08 1.91069e-15 0 0.3 0 -0.4 1)"
)
_GOAL_PARTS = (
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 -1.07 0 1))"
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 1.07 0 1))"
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 -0.28 0 0 1))"
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0.42 1))"
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0.3 1.05 0.4 1))"
    "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 0.3 -1.05 0.4 1))"
)


def _goal(trf: str, model: str) -> str:
    return (
        f"(nd TRF {trf}(nd TRF {_GOAL_MESH_SLT}(nd StaticMesh (setVisible 1) (setTransparent) "
        f"(load models/{model}) (sSc 2.18 0.88 0.68)(resetMaterials naogoalnet white)))"
        f"{_GOAL_PARTS})"
    )


def _border(x: float, y: float, sx: float, sy: float) -> str:
    return (
        f"(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 {fmt_g(x)} {fmt_g(y)} 0 1)(nd SMN (setVisible 1) "
        f"(load StdUnitBox) (sSc {fmt_g(sx)} {fmt_g(sy)} 1) (sMat matGrey)))"
    )


#: The fixed part of the soccer scene, exactly as rcssserver3d 0.7.3 sends it (two lights, field,
#: sky box, goals, borders, 4 corner-flag and 21 field-line transforms).
STATIC_SCENE_FULL = "".join(
    [
        "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 -10 10 10 1)(nd Light (setDiffuse 1 1 1 1) "
        "(setAmbient 0.8 0.8 0.8 1) (setSpecular 0.1 0.1 0.1 1)))",
        "(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 10 -10 10 1)(nd Light (setDiffuse 1 1 1 1) "
        "(setAmbient 0 0 0 1) (setSpecular 0.1 0.1 0.1 1)))",
        f"(nd TRF (SLT {_ROT_X} 0 0 0 1)(nd StaticMesh (setVisible 1) "
        "(load models/naosoccerfield.obj) (sSc 2.5 1 2.5)(resetMaterials None_rcs-naofield.png)))",
        f"(nd TRF (SLT {_ROT_X} 0 0 0 1)(nd StaticMesh (setVisible 1) (load models/skybox.obj) "
        "(sSc 10 10 10)(resetMaterials "
        + " ".join(f"Material_skyrender_000{i}.tif" for i in range(1, 7))
        + ")))",
        _goal("(SLT 1 0 0 0 0 1 0 0 0 0 1 0 -15.3 0 0.4 1)", "leftsoccergoal.obj"),
        _goal(
            "(SLT -1 -8.74228e-08 -0 -0 8.74228e-08 -1 0 0 0 0 1 0 15.3 0 0.4 1)",
            "rightsoccergoal.obj",
        ),
        _border(-24.99, 0, 1, 51),
        _border(24.99, 0, 1, 51),
        _border(0, 25, 50.98, 1),
        _border(0, -25, 50.98, 1),
        *(
            f"(nd TRF (SLT 1 0 0 0 0 1 0 0 0 0 1 0 {x} {y} 0 1))"
            for x, y in ((-15, 10), (-15, -10), (15, 10), (15, -10))
        ),
        f"(nd TRF {_IDENTITY})" * 21,
    ]
)
#: The same part in a delta frame (nothing in it ever moves).
STATIC_SCENE_DELTA = (
    "(nd(nd))(nd(nd))(nd(nd StaticMesh))(nd(nd StaticMesh))"
    + "(nd(nd(nd StaticMesh))(nd)(nd)(nd)(nd)(nd)(nd))" * 2
    + "(nd(nd SMN))" * 4
    + "(nd)" * 25
)

ENVIRONMENT_HEADER = (
    "".join(f"({name} {fmt_g(value)})" for name, value in DEFAULT_ENVIRONMENT)
    + "(play_modes "
    + " ".join(PLAY_MODES)
    + ")"
)
"""The static environment predicates that open every full frame (§7.3)."""

_BALL_MESH = (
    "(nd StaticMesh (setVisible 1) (load models/soccerball.obj) (sSc 0.042 0.042 0.042)"
    "(resetMaterials soccerball_rcs-soccerball.png))"
)

# Bodies of a robot in SimSpark's scene order, with their visual: (body, kind, args).
#   kind "torso"/"head": mesh inside the rotated wrapper transform; "sphere": StdUnitSphere SMN;
#   "neck": capsule SMN; "mesh": StaticMesh (model, scale, materials with {team}/{num}/{type}).
_ARM = (
    ("{s}shoulder", "sphere", "matYellow"),
    (
        "{s}upperarm",
        "mesh",
        ("{s}upperarm{type}.obj", "0.07 0.07 0.07", "{team} matType{type} naowhite"),
    ),
    ("{s}elbow", "sphere", "matYellow"),
    ("{s}lowerarm", "mesh", ("{s}lowerarm.obj", "0.05 0.05 0.05", "{team} naowhite")),
)
_LEG = (
    ("{s}hip1", "sphere", "matYellow"),
    ("{s}hip2", "sphere", "matYellow"),
    ("{s}thigh", "mesh", ("{s}thigh.obj", "0.07 0.07 0.07", "{thighnum}{team} naowhite")),
    ("{s}shank", "mesh", ("{s}shank{type}.obj", "0.08 0.08 0.08", "{team} matType{type} naowhite")),
    ("{s}ankle", "sphere", "matRed"),
    ("{s}foot", "mesh", ("{s}foot.obj", "{footscale}", "{team} naowhite")),
)
_TOE = ("{s}toe", "mesh", ("{s}foot.obj", "{toescale}", "{team} naowhite"))


def _robot_layout(robot_type: int) -> list[tuple[str, str, object]]:
    out: list[tuple[str, str, object]] = [
        ("torso", "torso", None),
        ("neck", "neck", None),
        ("head", "head", None),
    ]
    for s in ("r", "l"):
        out += [(b.format(s=s), k, a) for b, k, a in _ARM]
    for s in ("r", "l"):
        out += [(b.format(s=s), k, a) for b, k, a in _LEG]
        if robot_type == 4:
            out.append((_TOE[0].format(s=s), _TOE[1], _TOE[2]))
    return out


def _transforms(pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """(n, 16) column-major 4×4 transforms (SparkMonitor's ``SLT``) of bodies with centres
    ``pos`` (n, 3) and rotations ``rot`` (n, 3, 3)."""
    out = np.zeros((len(pos), 16))
    out[:, 0:3] = rot[:, :, 0]  # column j = body axis j
    out[:, 4:7] = rot[:, :, 1]
    out[:, 8:11] = rot[:, :, 2]
    out[:, 12:15] = pos
    out[:, 15] = 1.0
    return out


def _fmt16(row: list[float]) -> str:
    return "(SLT " + " ".join([f"{v:g}" for v in row]) + ")"


@dataclass
class RobotView:
    """What the monitor needs to draw one agent connection."""

    key: int
    robot_index: int | None
    """Index in the World, ``None`` for a connection without robot (or a killed robot)."""
    robot_type: int = 0
    side: str | None = None
    unum: int | None = None
    selected: bool = False


class MonitorStream:
    """Builds monitor frames; one instance per server (all monitors get the same bytes)."""

    def __init__(self) -> None:
        self._layouts: dict[int, list[tuple[str, str, object]]] = {}
        self._sent: dict[int, np.ndarray] = {}
        """Per agent key: the SLT values last sent for its bodies, (n_bodies, 16)."""
        self._order: dict[int, np.ndarray] = {}
        """Per robot type: the model's body index of each body of the monitor layout."""
        self._ball_sent: np.ndarray | None = None
        self._structure: tuple | None = None
        self._env_sent: dict[str, object] = {}
        self._team_names_sent: set[str] = set()
        self.fouls: Sequence[tuple[int, int, str, int]] = ()
        """The referee's fouls (``Referee.fouls``); each goes out once, in the next frame."""
        self.kick_rules: KickRules | None = None
        """The referee's kick rules (``Referee.kicks``): in play, each frame carries how long
        a team is still barred from scoring after its pass mode."""
        self._last_foul = 0

    # ------------------------------------------------------------------ environment
    def _game_values(self, world, half: int, teams: dict[str, str]) -> dict[str, object]:
        g = world.game
        return {
            "team_left": teams.get("left"),
            "team_right": teams.get("right"),
            "half": half,
            "score_left": g.score_left,
            "score_right": g.score_right,
            "play_mode": play_mode_id(g.play_mode) if g.play_mode in PLAY_MODES else 21,
        }

    def _env_full(self, world, half: int, teams: dict[str, str]) -> str:
        vals = self._game_values(world, half, teams)
        parts = [ENVIRONMENT_HEADER, f"(time {fmt_g(world.game.game_time)})"]
        for key in ("team_left", "team_right"):
            if vals[key]:
                parts.append(f"({key} {vals[key]})")
        for key in ("half", "score_left", "score_right", "play_mode"):
            parts.append(f"({key} {vals[key]})")
        self._env_sent = dict(vals)
        parts.append(self._score_waits(world))
        parts.append(self._new_fouls())
        return "(" + "".join(parts) + ")"

    def _score_waits(self, world) -> str:
        """``(pass_mode_score_wait_left s)`` / ``…_right``: in play, while a team is barred
        from scoring after its pass mode (in every frame, full or delta)."""
        kicks = self.kick_rules
        if kicks is None or world.game.play_mode != "PlayOn":
            return ""
        out = []
        for side in ("left", "right"):
            wait = kicks.score_wait(side, world.game.game_time)
            if wait is not None:
                out.append(f"(pass_mode_score_wait_{side} {fmt_g(wait)})")
        return "".join(out)

    def _new_fouls(self) -> str:
        """``(foul index type team unum)`` of every foul not sent yet (team 1: left, 2: right)."""
        new = self.fouls[self._last_foul :]  # numbered from 1 in order
        if not new:
            return ""
        self._last_foul = new[-1][0]
        return "".join(f"(foul {i} {t} {1 if s == 'left' else 2} {u})" for i, t, s, u in new)

    def _env_delta(self, world, half: int, teams: dict[str, str]) -> str:
        vals = self._game_values(world, half, teams)
        parts = [f"(time {fmt_g(world.game.game_time)})"]
        for key in ("team_left", "team_right", "half", "score_left", "score_right", "play_mode"):
            v = vals[key]
            if v is not None and v != self._env_sent.get(key):
                parts.append(f"({key} {v})")
        self._env_sent = dict(vals)
        parts.append(self._score_waits(world))
        parts.append(self._new_fouls())
        return "(" + "".join(parts) + ")"

    # ------------------------------------------------------------------ scene
    def structure_of(self, robots: list[RobotView]) -> tuple:
        """Anything that requires a full frame when it changes."""
        return tuple(
            (r.key, r.robot_index is not None, r.robot_type, r.side, r.unum) for r in robots
        )

    def needs_full(self, robots: list[RobotView]) -> bool:
        return self.structure_of(robots) != self._structure

    def _poses(self, world, r: RobotView) -> np.ndarray:
        """(n_bodies, 16) column-major world transforms of the robot's bodies, layout order."""
        index = r.robot_index
        layout = self._layout(r.robot_type)
        order = self._order.get(r.robot_type)
        if order is None:  # layout position → position in the model's body list
            names = [b.name for b in world.robots[index].model.bodies]  # type: ignore[index]
            order = self._order[r.robot_type] = np.array([names.index(b) for b, _, _ in layout])
        pos, rot = world.body_frames(index)
        return _transforms(pos[order], rot[order])

    def _layout(self, robot_type: int) -> list[tuple[str, str, object]]:
        lay = self._layouts.get(robot_type)
        if lay is None:
            lay = self._layouts[robot_type] = _robot_layout(robot_type)
        return lay

    def _ball_pose(self, world) -> np.ndarray:
        pos, rot = world.ball_frame()
        return _transforms(pos[None], rot[None])[0]

    def _robot_full(self, r: RobotView, poses: np.ndarray) -> str:
        team = {"left": "matLeft", "right": "matRight"}.get(r.side or "", "matTeam")
        num = f"matNum{r.unum}" if r.unum is not None and r.side else "matNum"
        t = r.robot_type
        foot_len = 0.16 - 0.035517656 if t == 4 else 0.16
        subs = {
            "team": team,
            "type": t,
            "thighnum": "",
            "footscale": f"0.08 {fmt_g(0.08 * foot_len / 0.16)} 0.08"
            if t == 4
            else "0.08 0.08 0.08",
            "toescale": f"0.08 {fmt_g(0.08 * 0.035517656 / foot_len)} 0.04",
        }
        parts = [f"(nd TRF {_IDENTITY}"]
        for i, (body, kind, args) in enumerate(self._layout(t)):
            slt = _fmt16(poses[i].tolist())
            if kind == "torso":
                sel = 1 if r.selected else 0
                parts.append(
                    f"(nd TRF {slt}(nd TRF {_WRAP}(nd StaticMesh (setVisible 1) "
                    f"(load models/naobody{t}.obj) (sSc 0.1 0.1 0.1)"
                    f"(resetMaterials {num} {team} matType{t} naowhite)))"
                    f"(nd TRF {_IDENTITY}(nd SMN (setVisible {sel}) (setTransparent) "
                    "(load StdUnitCylinder 1 1) (sSc 0.2 0.2 0.02) (sMat matSelect))))"
                )
            elif kind == "neck":
                parts.append(
                    f"(nd TRF {slt}(nd SMN (setVisible 1) (load StdCapsule 0.015 0.08) "
                    "(sSc 1 1 1) (sMat matDarkGrey)))"
                )
            elif kind == "head":
                parts.append(
                    f"(nd TRF {slt}(nd TRF {_WRAP}(nd StaticMesh (setVisible 1) "
                    "(load models/naohead.obj) (sSc 0.1 0.1 0.1)"
                    f"(resetMaterials {team} naoblack naogrey naowhite))))"
                )
            elif kind == "sphere":
                parts.append(
                    f"(nd TRF {slt}(nd SMN (setVisible 1) (load StdUnitSphere) "
                    f"(sSc 0.01 0.01 0.01) (sMat {args})))"
                )
            else:
                model, scale, mats = args  # type: ignore[misc]
                s = body[0]
                subs["thighnum"] = f"{num} " if body == "rthigh" else ""
                model = model.format(s=s, **subs)
                scale = scale.format(**subs)
                mats = mats.format(**subs)
                parts.append(
                    f"(nd TRF {slt}(nd StaticMesh (setVisible 1) (load models/{model}) "
                    f"(sSc {scale})(resetMaterials {mats})))"
                )
        parts.append(")")
        return "".join(parts)

    def _robot_delta(self, r: RobotView, poses: np.ndarray, sent: np.ndarray) -> str:
        moved = np.abs(poses - sent).max(axis=1) > SLT_THRESHOLD
        parts = ["(nd"]
        for i, (_, kind, _) in enumerate(self._layout(r.robot_type)):
            if moved[i]:
                row = poses[i]
                sent[i] = row
                head = "(nd " + _fmt16(row.tolist())
            else:
                head = "(nd"
            if kind == "torso":
                sel = 1 if r.selected else 0
                parts.append(
                    f"{head}(nd(nd StaticMesh (setVisible 1)))(nd(nd SMN (setVisible {sel}))))"
                )
            elif kind == "head":
                parts.append(f"{head}(nd(nd StaticMesh (setVisible 1))))")
            elif kind == "mesh":
                parts.append(f"{head}(nd StaticMesh (setVisible 1)))")
            else:
                parts.append(f"{head}(nd SMN (setVisible 1)))")
        parts.append(")")
        return "".join(parts)

    # ------------------------------------------------------------------ frames
    def full_frame(self, world, robots: list[RobotView], half: int, teams: dict[str, str]) -> str:
        """A full frame; the delta state is reset to what it contains."""
        env = self._env_full(world, half, teams)
        ball = self._ball_pose(world)
        self._ball_sent = ball.copy()
        parts = [
            env,
            "(RSG 0 1)(",
            STATIC_SCENE_FULL,
            f"(nd TRF {_fmt16(ball.tolist())}{_BALL_MESH})",
        ]
        self._sent = {}
        for r in robots:
            if r.robot_index is None:
                parts.append(f"(nd TRF {_IDENTITY})")
                continue
            poses = self._poses(world, r)
            self._sent[r.key] = poses.copy()
            parts.append(self._robot_full(r, poses))
        parts.append(")")
        self._structure = self.structure_of(robots)
        return "".join(parts)

    def delta_frame(self, world, robots: list[RobotView], half: int, teams: dict[str, str]) -> str:
        """A delta frame relative to what was sent before (call only if not :meth:`needs_full`)."""
        env = self._env_delta(world, half, teams)
        ball = self._ball_pose(world)
        parts = [env, "(RDS 0 1)(", STATIC_SCENE_DELTA]
        if self._ball_sent is None or np.abs(ball - self._ball_sent).max() > SLT_THRESHOLD:
            self._ball_sent = ball
            parts.append(f"(nd {_fmt16(ball.tolist())}(nd StaticMesh))")
        else:
            parts.append("(nd(nd StaticMesh))")
        for r in robots:
            if r.robot_index is None:
                parts.append("(nd)")
                continue
            poses = self._poses(world, r)
            sent = self._sent.get(r.key)
            if sent is None or sent.shape != poses.shape:
                sent = self._sent[r.key] = poses + 1.0  # forces every transform
            parts.append(self._robot_delta(r, poses, sent))
        parts.append(")")
        return "".join(parts)

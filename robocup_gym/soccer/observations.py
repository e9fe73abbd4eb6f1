"""What a player observes: its own perceptors as a real server sends them, in [-1, 1].

Every value comes from the player's :class:`~robocup_gym.types.Perception` (joint angles, gyro,
accelerometer, foot pressure, restricted noisy vision every third cycle, the game state) and,
only with ``privileged=True`` (training aids a real agent does not have), from ground truth.
Angles seen are relative to the head; positions of the privileged part are in the player's team
frame (its own goal at x = −15 whichever side it plays on).

========================  ======  =========================================================
component                 size    values (raw → scaled to [-1, 1] by the range given)
========================  ======  =========================================================
``joint_pos``             n       each joint's angle, over the joint's range
``joint_vel``             n       change of each angle over the last cycle, ± max speed
``gyro``                  3       deg/s, ±500
``accel``                 3       m/s², ±50
``foot_force``            12      FRP of each foot: centre (±0.1 m), force (±100 N)
``ball``                  5       distance (0–20 m), horizontal and vertical angle (±180°,
                                  ±90°), seen in the last See (1/0), cycles since seen
                                  (0–150); held between See messages
``goals``                 12      own then opponent goal's two posts: distance, horizontal
                                  angle, seen (1/0)
``game``                  6       PlayOn, own set piece / kick-off, opponent's, other mode
                                  (one-hot); game time (0–600 s); score difference (±5)
``privileged`` (option)   10 + 2k own (x, y) (±15, ±10 m), heading (cos, sin), ball (x, y),
                                  ball velocity (x, y) (±10 m/s), own up axis z, own height
                                  (0–0.6 m); then (x, y) of every other player: teammates,
                                  then opponents, by uniform number (k of them)
========================  ======  =========================================================

``n`` is the robot's joint count (22, or 24 for type 4).
"""

from __future__ import annotations

import numpy as np

from robocup_gym.envs.observations import heading_frame, up_z
from robocup_gym.robot.nao import NaoModel
from robocup_gym.sim.physics import CYCLE_S
from robocup_gym.types import Perception

__all__ = ["PlayerObserver", "observation_labels"]

_FOOT = ("lf", "rf")
_POSTS = {"left": ("G1L", "G2L"), "right": ("G1R", "G2R")}
_SEEN_MAX_CYCLES = 150.0


def _set_piece_owner(play_mode: str) -> str | None:
    """The side a play mode favours (kick-off, kick-in, corner, goal kick, free kick, pass,
    goal: the side that scored), or ``None``."""
    pm = play_mode.lower()
    if pm.endswith("_left"):
        return "left"
    if pm.endswith("_right"):
        return "right"
    return None


def observation_labels(
    model: NaoModel, privileged: bool, mates: int = 0, opponents: int = 0
) -> list[str]:
    """One label per observation value, in order (``mates``, ``opponents``: the other players
    whose positions the privileged part has)."""
    labels = [f"joint_pos/{n}" for n in model.perceptor_names]
    labels += [f"joint_vel/{n}" for n in model.perceptor_names]
    labels += [f"gyro/{a}" for a in "xyz"] + [f"accel/{a}" for a in "xyz"]
    for f in _FOOT:
        labels += [f"foot_force/{f}_c{a}" for a in "xyz"] + [f"foot_force/{f}_f{a}" for a in "xyz"]
    labels += [f"ball/{k}" for k in ("distance", "horizontal", "vertical", "seen", "age")]
    for goal in ("own", "opp"):
        for post in (1, 2):
            labels += [f"goals/{goal}{post}_{k}" for k in ("distance", "horizontal", "seen")]
    labels += [f"game/{k}" for k in ("play_on", "ours", "theirs", "other", "time", "score")]
    if privileged:
        labels += [
            f"privileged/{k}"
            for k in (
                "x",
                "y",
                "heading_cos",
                "heading_sin",
                "ball_x",
                "ball_y",
                "ball_vx",
                "ball_vy",
                "up_z",
                "height",
            )
        ]
        for who, n in (("mate", mates), ("opponent", opponents)):
            for k in range(n):
                labels += [f"privileged/{who}{k + 1}_x", f"privileged/{who}{k + 1}_y"]
    return labels


class PlayerObserver:
    """Builds one player's observations, keeping what vision last showed.

    Args:
        model: The player's robot.
        side: ``"left"`` or ``"right"``.
        privileged: Add the ground-truth part (training only).
        mates, opponents: How many other players the privileged part places (their
            positions come with each call).
    """

    def __init__(
        self,
        model: NaoModel,
        side: str,
        privileged: bool = False,
        mates: int = 0,
        opponents: int = 0,
    ) -> None:
        self.model = model
        self.side = side
        self.opponent = "right" if side == "left" else "left"
        self.privileged = bool(privileged)
        self.others = (int(mates) + int(opponents)) if privileged else 0
        self.labels = observation_labels(model, privileged, mates, opponents)
        self.size = len(self.labels)
        lo = np.array([j.min_deg for j in model.joints], float)
        hi = np.array([j.max_deg for j in model.joints], float)
        self._mid, self._half = (hi + lo) / 2, np.maximum((hi - lo) / 2, 1e-9)
        self._max_speed = np.asarray(model.max_speeds, float)
        self.reset()

    def reset(self) -> None:
        """Forget the last episode (joint angles, what vision showed)."""
        self._last_angles: np.ndarray | None = None
        self._ball = np.zeros(3)
        self._ball_age = _SEEN_MAX_CYCLES
        self._posts = {name: np.zeros(3) for names in _POSTS.values() for name in names}
        self._post_seen = {name: False for name in self._posts}

    def __call__(self, p: Perception, others: np.ndarray | None = None) -> np.ndarray:
        """The observation of perception ``p``; ``others``: the world (x, y) of the other
        players (teammates, then opponents, by uniform number), for the privileged part."""
        out = np.empty(self.size, dtype=np.float32)
        n = len(self.model.joints)
        angles = np.asarray(p.joint_angles_deg, float)
        out[:n] = (angles - self._mid) / self._half
        if self._last_angles is None:
            vel = np.zeros(n)
        else:
            vel = np.radians(angles - self._last_angles) / CYCLE_S
        self._last_angles = angles
        out[n : 2 * n] = vel / self._max_speed
        k = 2 * n
        out[k : k + 3] = np.asarray(p.gyro, float) / 500.0
        out[k + 3 : k + 6] = np.asarray(p.accel, float) / 50.0
        k += 6
        for f in _FOOT:
            frp = p.force_sensors.get(f)
            if frp is None:
                out[k : k + 6] = 0.0
            else:
                out[k : k + 3] = np.asarray(frp.point, float) / 0.1
                out[k + 3 : k + 6] = np.asarray(frp.force, float) / 100.0
            k += 6
        k = self._vision(p, out, k)
        k = self._game(p, out, k)
        if self.privileged:
            k = self._ground_truth(p, out, k)
            if self.others:
                xy = np.asarray(others, float).reshape(self.others, 2)
                s = 1.0 if self.side == "left" else -1.0
                out[k : k + 2 * self.others] = (s * xy / (15.0, 10.0)).ravel()
                k += 2 * self.others
        assert k == self.size
        np.clip(out, -1.0, 1.0, out=out)
        return out

    def remember(self, p: Perception) -> None:
        """What a call with ``p`` keeps for the next one (the joint angles, what vision
        showed), without building the observation: a cycle whose observation nobody reads."""
        self._last_angles = np.asarray(p.joint_angles_deg, float)
        self._see(p)

    def _see(self, p: Perception) -> bool:
        """Keep what vision shows (the ball, the goal posts); whether it shows the ball."""
        v = p.vision
        seen_ball = False
        if v is not None:
            ball = v.objects.get("B")
            if ball is not None:
                self._ball = np.asarray(ball, float)
                seen_ball = True
            for name in self._posts:
                seen = v.objects.get(name)
                self._post_seen[name] = seen is not None
                if seen is not None:
                    self._posts[name] = np.asarray(seen, float)
        self._ball_age = 0.0 if seen_ball else min(self._ball_age + 1.0, _SEEN_MAX_CYCLES)
        return seen_ball

    def _vision(self, p: Perception, out: np.ndarray, k: int) -> int:
        seen_ball = self._see(p)
        d, h, vert = self._ball
        out[k : k + 5] = (
            d / 10.0 - 1.0,
            h / 180.0,
            vert / 90.0,
            1.0 if seen_ball else -1.0,
            self._ball_age / (_SEEN_MAX_CYCLES / 2) - 1.0,
        )
        k += 5
        for side in (self.side, self.opponent):
            for name in _POSTS[side]:
                d, h, _ = self._posts[name]
                out[k : k + 3] = (d / 15.0 - 1.0, h / 180.0, 1.0 if self._post_seen[name] else -1.0)
                k += 3
        return k

    def _game(self, p: Perception, out: np.ndarray, k: int) -> int:
        g = p.game
        owner = _set_piece_owner(g.play_mode)
        onehot = [-1.0] * 4
        if g.play_mode == "PlayOn":
            onehot[0] = 1.0
        elif owner == self.side:
            onehot[1] = 1.0
        elif owner == self.opponent:
            onehot[2] = 1.0
        else:
            onehot[3] = 1.0
        out[k : k + 4] = onehot
        own, other = (
            (g.score_left, g.score_right) if self.side == "left" else (g.score_right, g.score_left)
        )
        out[k + 4] = g.game_time / 300.0 - 1.0
        out[k + 5] = (own - other) / 5.0
        return k + 6

    def _ground_truth(self, p: Perception, out: np.ndarray, k: int) -> int:
        gt = p.ground_truth
        if gt is None:
            raise ValueError("privileged observations need ground truth in the perception")
        s = 1.0 if self.side == "left" else -1.0
        cos_h, sin_h = heading_frame(gt.torso_quat)  # world frame; the team frame turns by s
        out[k : k + 10] = (
            s * gt.torso_pos[0] / 15.0,
            s * gt.torso_pos[1] / 10.0,
            s * cos_h,
            s * sin_h,
            s * gt.ball_pos[0] / 15.0,
            s * gt.ball_pos[1] / 10.0,
            s * gt.ball_vel[0] / 10.0,
            s * gt.ball_vel[1] / 10.0,
            up_z(gt.torso_quat),
            gt.torso_pos[2] / 0.3 - 1.0,
        )
        return k + 10

"""rcssserver3d's self-collision rule (reference §9.7): while the game runs, a robot whose own
boxes overlap has the joints of the two parts frozen for a while.

Every cycle that is not paused (not BeforeKickOff and not a goal's pause), after the physics
step, every pair of a robot's box colliders (torso, upper and lower arms, thighs, shanks, feet,
toes; not a thigh with the torso, a shank with its thigh, a foot with its shank, a toe with its
foot) is tested with the server's separating-axis test: the pair collides when no axis separates
the boxes by more than ``-TOLERANCE_M``. The axes are the 3 + 3 box axes and their 9 cross
products, the latter *not normalised*, as the server computes them: a pair with two nearly
parallel axes (two boxes joined by one hinge, or any two boxes in the zero pose) never counts.

A collision freezes the joints listed on both boxes (an arm box: that arm's ``ae1``–``ae4``; a
leg box: that leg's ``le1``–``le6``, and ``le7`` on a type-4 robot; the torso: none): for
``FROZEN_S`` (1 s of game time) every command a frozen joint gets is replaced by 0 rad/s (a
command that came before keeps its target, as the server's disabled hinge effector does). A
joint that was frozen cannot be frozen again before ``FROZEN_S + THAW_S`` (3 s) have passed
since. Pausing the game releases every joint. Times are compared in single precision on the game
clock, as the server keeps them.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from robocup_gym.robot.nao import nao_model

__all__ = [
    "FROZEN_S",
    "THAW_S",
    "TOLERANCE_M",
    "BoxSet",
    "SelfCollisions",
    "box_set",
    "colliding",
]

TOLERANCE_M = 0.04
"""``SelfCollisionsTolerance``: how far two boxes must overlap on every axis to collide, m."""
FROZEN_S = 1.0
"""``SelfCollisionJointFrozenTime``: how long a joint stays frozen, s of game time."""
THAW_S = 2.0
"""``SelfCollisionJointThawTime``: after that, how long before it can be frozen again, s."""

_NOT_COLLIDE = {"thigh": "torso", "shank": "thigh", "foot": "shank", "toe": "foot"}
"""Each part and the part (of its own side; the torso) it is never tested against."""


@dataclass(frozen=True)
class BoxSet:
    """The box colliders of one robot type and the pairs the rule tests."""

    bodies: np.ndarray
    """Indices of the boxes in the model's bodies (``body_frames`` order)."""
    half: np.ndarray
    """Half edge lengths of each box, ``(n, 3)``, m."""
    pairs: np.ndarray
    """``(p, 2)`` indices into :attr:`bodies` of the pairs tested."""
    freeze: np.ndarray
    """``(p, n_joints)`` bool: the joints (canonical order) a collision of each pair freezes."""
    names: tuple[tuple[str, str], ...]
    """Each pair's body names."""


def _part(name: str) -> tuple[str, str]:
    """``(side prefix, part)`` of a body name: ``rthigh`` → ``("r", "thigh")``."""
    if name == "torso":
        return "", "torso"
    return name[0], name[1:]


@cache
def box_set(robot_type: int) -> BoxSet:
    """The boxes, tested pairs and frozen joints of a Nao of type ``robot_type`` (0–4)."""
    model = nao_model(robot_type)
    effectors = [j.effector for j in model.joints]
    boxes = [k for k, b in enumerate(model.bodies) if b.shape == "box" and b.collides]
    names = [model.bodies[k].name for k in boxes]

    def frozen_by(name: str) -> set[str]:
        side, part = _part(name)
        if part in ("upperarm", "lowerarm"):
            return {f"{side}ae{n}" for n in range(1, 5)}
        if part in ("thigh", "shank", "foot", "toe"):
            return {e for e in effectors if e.startswith(f"{side}le")}
        return set()

    pairs, freeze, pair_names = [], [], []
    for a in range(len(boxes)):
        for b in range(a + 1, len(boxes)):
            (sa, pa), (sb, pb) = _part(names[a]), _part(names[b])
            skip = (_NOT_COLLIDE.get(pb) == pa and (pa == "torso" or sa == sb)) or (
                _NOT_COLLIDE.get(pa) == pb and (pb == "torso" or sa == sb)
            )
            if skip:
                continue
            pairs.append((a, b))
            joints = frozen_by(names[a]) | frozen_by(names[b])
            freeze.append([e in joints for e in effectors])
            pair_names.append((names[a], names[b]))
    return BoxSet(
        bodies=np.array(boxes),
        half=np.array([model.bodies[k].size for k in boxes], float) / 2,
        pairs=np.array(pairs),
        freeze=np.array(freeze, bool),
        names=tuple(pair_names),
    )


SOURCE = Path(__file__).with_name("self_collision.c")
"""The test in C (:func:`colliding`'s arithmetic), compiled on first use like the world's step
(:mod:`robocup_gym.sim.compiled`); NumPy where it cannot be built or ``ROBOCUP_GYM_COMPILED=0``."""


def _configure(lib: ctypes.CDLL) -> None:
    p = ctypes.c_void_p
    lib.rg_self_collisions.argtypes = [ctypes.c_int, p, p, p, p, ctypes.c_double, p]
    lib.rg_self_collisions.restype = ctypes.c_int


@cache
def _compiled() -> ctypes.CDLL | None:
    from robocup_gym.sim import compiled

    if compiled.wanted() is False:
        return None
    try:
        return compiled.load_library(SOURCE, _configure)
    except compiled.CompiledStepUnavailableError:
        if compiled.wanted():
            raise
        return None


def colliding(
    positions: np.ndarray,
    rotations: np.ndarray,
    half: np.ndarray,
    pairs: np.ndarray,
    tolerance: float = TOLERANCE_M,
    *,
    compiled: bool | None = None,
) -> np.ndarray:
    """Which ``pairs`` of boxes collide by the server's separating-axis test.

    The 15 axes' projections are written with ``C = Aᵀ B`` (the axes of box B in the frame of
    box A), the usual way; they are the same numbers as the server's projections onto the
    unnormalised axes.

    Args:
        positions: box centres ``(n, 3)``, world, m.
        rotations: box rotations ``(n, 3, 3)`` (columns = box axes in world coordinates).
        half: half edge lengths ``(n, 3)``, m.
        pairs: ``(p, 2)`` box indices.
        tolerance: the overlap needed on every axis, m.
        compiled: ``None``: in C where it can be compiled (:data:`SOURCE`), else NumPy;
            ``False``: NumPy (the reference); ``True``: C or an error.

    Returns:
        ``(p,)`` bool.
    """
    lib = None if compiled is False else _compiled()
    if lib is None and compiled:
        from robocup_gym.sim.compiled import CompiledStepUnavailableError

        raise CompiledStepUnavailableError(f"{SOURCE.name} cannot be compiled here")
    if lib is not None:
        prs = np.ascontiguousarray(pairs, np.int32)
        out = np.zeros(len(prs), np.uint8)
        lib.rg_self_collisions(
            len(prs),
            np.ascontiguousarray(positions, float).ctypes.data,
            np.ascontiguousarray(rotations, float).ctypes.data,
            np.ascontiguousarray(half, float).ctypes.data,
            prs.ctypes.data,
            float(tolerance),
            out.ctypes.data,
        )
        return out.astype(bool)
    a, b = pairs[:, 0], pairs[:, 1]
    ra, rb = rotations[a], rotations[b]
    ha, hb = half[a], half[b]
    rel = positions[b] - positions[a]
    c = np.matmul(np.swapaxes(ra, 1, 2), rb)  # (p, 3, 3): C[i, j] = A_i · B_j
    abs_c = np.abs(c)
    t = np.einsum("pji,pj->pi", ra, rel)  # rel in A's frame
    # faces of A, faces of B
    sep = (np.abs(t) + tolerance > ha + np.einsum("pij,pj->pi", abs_c, hb)).any(axis=1)
    u = np.einsum("pji,pj->pi", rb, rel)
    sep |= (np.abs(u) + tolerance > hb + np.einsum("pij,pi->pj", abs_c, ha)).any(axis=1)
    # A_i × B_j: (i, i1, i2) and (j, j1, j2) cyclic
    i1, i2 = [1, 2, 0], [2, 0, 1]
    for i in range(3):
        k1, k2 = i1[i], i2[i]
        dist = np.abs(t[:, k2, None] * c[:, k1, :] - t[:, k1, None] * c[:, k2, :])  # (p, 3) over j
        ext = ha[:, k1, None] * abs_c[:, k2, :] + ha[:, k2, None] * abs_c[:, k1, :]
        ext = ext + (hb[:, i1] * abs_c[:, i, i2] + hb[:, i2] * abs_c[:, i, i1])
        sep |= (dist + tolerance > ext).any(axis=1)
    return ~sep


class SelfCollisions:
    """The rule's state for the robots of one world: when each joint was last frozen.

    :meth:`update` runs after every step; :meth:`frozen` is the mask the world's hinge effectors
    apply to the commands they take.
    """

    def __init__(self) -> None:
        self._since: dict[int, np.ndarray] = {}
        """Per robot index: the game time (float32) each joint was last frozen, NaN for never
        (or released by a pause)."""
        self._frozen: dict[int, np.ndarray] = {}
        self.collisions: list[tuple[int, str, str]] = []
        """The collisions of the last update: ``(robot index, body, body)``."""
        self.fouls: list[int] = []
        """The last update's fouls, as the server counts them: the robot index of each
        colliding pair that froze a joint anew."""
        self._clock: np.float32 | None = None

    def clear(self) -> None:
        """Every robot's joints released and free to be frozen (the game paused)."""
        self._since.clear()
        self._frozen.clear()
        self.collisions = []
        self.fouls = []
        self._clock = None

    def frozen(self, index: int) -> np.ndarray | None:
        """Robot ``index``'s frozen joints (canonical order), or ``None`` when none is."""
        return self._frozen.get(index)

    def update(self, world, robot_types: list[int], game_time: float) -> None:
        """After a step in a running game: test every robot's boxes (one test for the whole
        world), freeze the joints of the colliding pairs, release those frozen for
        :data:`FROZEN_S`."""
        self.collisions = []
        self.fouls = []
        t = np.float32(game_time)
        if self._clock is not None and t < self._clock:  # the clock was set back: start again
            self.clear()
        if not robot_types:  # nobody on the field (the last player left a server)
            self.clear()
            return
        self._clock = t
        plan = _plan(tuple(robot_types))
        positions, rotations = world.every_body_frame()
        hit = colliding(positions[plan.rows], rotations[plan.rows], plan.half, plan.pairs)
        hits_by_robot: dict[int, list[int]] = {}
        for p in np.flatnonzero(hit):
            hits_by_robot.setdefault(int(plan.robot[p]), []).append(int(plan.pair[p]))
        for index in sorted(set(hits_by_robot) | set(self._since)):
            boxes = box_set(robot_types[index])
            since = self._since.get(index)
            for p in hits_by_robot.get(index, ()):
                if since is None:
                    since = self._since[index] = np.full(boxes.freeze.shape[1], np.nan, np.float32)
                self.collisions.append((index, *boxes.names[p]))
                # a joint never frozen, or frozen more than FROZEN_S + THAW_S ago
                free = np.isnan(since) | ((t - since) > np.float32(FROZEN_S + THAW_S))
                anew = boxes.freeze[p] & free
                if anew.any():
                    self.fouls.append(index)
                since[anew] = t
            if since is None:
                continue
            age = t - since  # NaN where never frozen
            with np.errstate(invalid="ignore"):
                frozen = age < np.float32(FROZEN_S)
                since[age >= np.float32(FROZEN_S + THAW_S)] = np.nan
            if frozen.any():
                self._frozen[index] = frozen
            else:
                self._frozen.pop(index, None)
                if np.isnan(since).all():
                    del self._since[index]


@dataclass(frozen=True)
class _Plan:
    """The boxes of every robot of a world, as one test: rows into ``every_body_frame``."""

    rows: np.ndarray
    half: np.ndarray
    pairs: np.ndarray
    robot: np.ndarray
    """Each pair's robot index."""
    pair: np.ndarray
    """Each pair's index in its robot's :class:`BoxSet`."""


@cache
def _plan(robot_types: tuple[int, ...]) -> _Plan:
    rows, half, pairs, robot, pair = [], [], [], [], []
    body_offset = box_offset = 0
    for index, robot_type in enumerate(robot_types):
        boxes = box_set(robot_type)
        rows.append(boxes.bodies + body_offset)
        half.append(boxes.half)
        pairs.append(boxes.pairs + box_offset)
        robot.append(np.full(len(boxes.pairs), index))
        pair.append(np.arange(len(boxes.pairs)))
        body_offset += len(nao_model(robot_type).bodies)
        box_offset += len(boxes.bodies)
    return _Plan(
        rows=np.concatenate(rows),
        half=np.concatenate(half),
        pairs=np.concatenate(pairs).astype(np.int32),
        robot=np.concatenate(robot),
        pair=np.concatenate(pair),
    )

"""The monitor's scene graph (SparkMonitor format, wire reference §7.4–7.6).

A full scene (``RSG``) is a tree of :class:`SceneNode`: transforms ``TRF`` with a local 4×4
matrix ``SLT``, meshes ``SMN``/``StaticMesh`` and lights. A delta (``RDS``) has exactly the same
shape and carries only what changed; :meth:`SceneGraph.apply_delta` matches it by position.
:meth:`SceneGraph.world_transforms` gives every node's world matrix (product of the ancestors'
``SLT``). Lengths in m.

Writers produce the server's exact spacing: :func:`format_full_scene`, :class:`DeltaEncoder`
(remembers what each monitor was sent) and the single-node helpers :func:`format_slt`,
:func:`format_trf`, :func:`format_smn`, :func:`format_static_mesh`, :func:`format_light`.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np

from robocup_gym.protocol.errors import ProtocolError
from robocup_gym.protocol.sexpr import SExpr, dumps
from robocup_gym.protocol.values import fmt_g, is_atom, strict_float

__all__ = [
    "MESH_KINDS",
    "SLT_THRESHOLD",
    "DeltaEncoder",
    "DeltaNode",
    "SceneGraph",
    "SceneNode",
    "format_delta_scene",
    "format_full_scene",
    "format_light",
    "format_slt",
    "format_smn",
    "format_static_mesh",
    "format_trf",
    "parse_delta_nodes",
    "parse_scene_nodes",
    "slt_matrix",
]

MESH_KINDS = frozenset({"SMN", "StaticMesh"})
"""Node types that are meshes."""

SLT_THRESHOLD = 0.005
"""A delta repeats a transform only if an entry moved by more than this since last sent."""

_IDENTITY = np.eye(4)


def slt_matrix(values: Sequence[float]) -> np.ndarray:
    """The 4×4 matrix of 16 ``SLT`` numbers (column-major: m12–m14 = translation)."""
    if len(values) != 16:
        raise ProtocolError(f"SLT needs 16 numbers, got {len(values)}", predicate="SLT")
    return np.array(values, dtype=float).reshape(4, 4).T


@dataclass
class SceneNode:
    """One node of a full scene.

    ``props`` keeps every other sub-list verbatim, in order (``setVisible``, ``setTransparent``,
    ``load``, ``sSc``, ``sMat``, ``resetMaterials``, ``setDiffuse`` …) as name → atoms.
    """

    kind: str
    """``TRF``, ``SMN``, ``StaticMesh``, ``Light`` (or another type a server might send)."""
    slt: np.ndarray | None = None
    """Local transform relative to the parent (4×4), ``TRF`` only."""
    props: dict[str, tuple[SExpr, ...]] = field(default_factory=dict)
    children: list[SceneNode] = field(default_factory=list)

    @property
    def is_mesh(self) -> bool:
        return self.kind in MESH_KINDS

    @property
    def visible(self) -> bool:
        """``setVisible`` (meshes default to visible)."""
        return self.props.get("setVisible", ("1",))[:1] != ("0",)

    @property
    def model(self) -> str | None:
        """The ``load`` model name (``models/naobody0.obj``, ``StdUnitBox`` …)."""
        load = self.props.get("load")
        return load[0] if load and isinstance(load[0], str) else None

    @property
    def materials(self) -> tuple[str, ...]:
        """``resetMaterials`` names or the single ``sMat``."""
        mats = self.props.get("resetMaterials") or self.props.get("sMat") or ()
        return tuple(m for m in mats if isinstance(m, str))

    @property
    def scale(self) -> np.ndarray | None:
        """``sSc`` scale factors (``None`` if absent or not numeric)."""
        s = self.props.get("sSc")
        if s is None:
            return None
        try:
            return np.array([strict_float(x) for x in s if isinstance(x, str)])
        except ProtocolError:
            return None


@dataclass
class DeltaNode:
    """One node of a delta scene: only what changed."""

    kind: str | None = None
    """``SMN``/``StaticMesh`` for meshes; ``None`` for transforms and lights (``(nd …)``)."""
    slt: np.ndarray | None = None
    """New local transform, or ``None`` if unchanged."""
    props: dict[str, tuple[SExpr, ...]] = field(default_factory=dict)
    children: list[DeltaNode] = field(default_factory=list)


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


def _node_parts(
    expr: SExpr,
) -> tuple[str | None, np.ndarray | None, dict[str, tuple[SExpr, ...]], list[list[SExpr]]]:
    if not isinstance(expr, list) or not expr or expr[0] != "nd":
        raise ProtocolError(f"expected a scene node (nd …), got {_short(expr)}")
    rest = expr[1:]
    kind = None
    if rest and isinstance(rest[0], str):
        kind = rest[0]
        rest = rest[1:]
    slt = None
    props: dict[str, tuple[SExpr, ...]] = {}
    children: list[list[SExpr]] = []
    for item in rest:
        if not isinstance(item, list) or not item or not isinstance(item[0], str):
            raise ProtocolError(f"unexpected element {_short(item)} in a scene node")
        key = item[0]
        if key == "nd":
            children.append(item)
        elif key == "SLT":
            slt = slt_matrix([_num(x) for x in item[1:]])
        else:
            props[key] = tuple(item[1:])
    return kind, slt, props, children


def _num(x: SExpr) -> float:
    if not isinstance(x, str):
        raise ProtocolError("SLT entries must be numbers", predicate="SLT")
    return strict_float(x, predicate="SLT")


def _short(expr: SExpr) -> str:
    text = str(expr)
    return text if len(text) <= 40 else text[:40] + "…"


def parse_scene_nodes(exprs: Sequence[SExpr]) -> list[SceneNode]:
    """The nodes of a full scene (the third expression of an ``RSG`` frame).

    Raises:
        ProtocolError: for something that is not an ``(nd <type> …)`` node.
    """
    return [_scene_node(e) for e in exprs]


def _scene_node(expr: SExpr) -> SceneNode:
    kind, slt, props, children = _node_parts(expr)
    if kind is None:
        raise ProtocolError("a node of a full scene needs a type (TRF, SMN, StaticMesh, Light)")
    return SceneNode(kind, slt, props, [_scene_node(c) for c in children])


def parse_delta_nodes(exprs: Sequence[SExpr]) -> list[DeltaNode]:
    """The nodes of a delta scene (the third expression of an ``RDS`` frame).

    Raises:
        ProtocolError: for something that is not an ``(nd …)`` node.
    """
    return [_delta_node(e) for e in exprs]


def _delta_node(expr: SExpr) -> DeltaNode:
    kind, slt, props, children = _node_parts(expr)
    return DeltaNode(kind, slt, props, [_delta_node(c) for c in children])


# --------------------------------------------------------------------------------------------
# The tracked graph
# --------------------------------------------------------------------------------------------


class SceneGraph:
    """A monitor's copy of the scene: replace it with each full scene, patch it with deltas."""

    def __init__(self, nodes: list[SceneNode] | None = None) -> None:
        self.nodes: list[SceneNode] = nodes or []

    def apply_delta(self, delta: Sequence[DeltaNode]) -> None:
        """Apply a delta scene (matched by position, wire reference §7.4).

        Raises:
            ProtocolError: if the delta's shape differs from the scene (a full frame was
                missed); the graph may then be partly updated.
        """
        _apply(self.nodes, delta, "root")

    def walk(self) -> Iterator[tuple[tuple[int, ...], SceneNode, np.ndarray]]:
        """Every node depth-first as ``(path, node, world matrix)``.

        ``path`` holds child indices from the root; a node's world matrix is the product of
        its ancestors' and its own ``SLT`` (meshes and lights share their parent's).
        """
        stack: list[tuple[tuple[int, ...], SceneNode, np.ndarray]] = []
        for i in range(len(self.nodes) - 1, -1, -1):
            stack.append(((i,), self.nodes[i], _IDENTITY))
        while stack:
            path, node, parent = stack.pop()
            world = parent if node.slt is None else parent @ node.slt
            yield path, node, world
            for i in range(len(node.children) - 1, -1, -1):
                stack.append(((*path, i), node.children[i], world))

    def world_transforms(self) -> dict[tuple[int, ...], np.ndarray]:
        """World matrix of every node by path."""
        return {path: world for path, _, world in self.walk()}

    def node(self, path: Sequence[int]) -> SceneNode:
        """The node at ``path`` (child indices from the root)."""
        nodes = self.nodes
        node = None
        for i in path:
            node = nodes[i]
            nodes = node.children
        if node is None:
            raise KeyError("empty path")
        return node

    def find_meshes(self, model_suffix: str) -> list[tuple[tuple[int, ...], SceneNode, np.ndarray]]:
        """Meshes whose model name ends with ``model_suffix``, with path and world matrix."""
        return [
            (path, node, world)
            for path, node, world in self.walk()
            if node.is_mesh and (node.model or "").endswith(model_suffix)
        ]

    def ball_position(self) -> np.ndarray | None:
        """World position of the first ``…soccerball.obj`` mesh (as RoboViz finds it), m."""
        found = self.find_meshes("soccerball.obj")
        return None if not found else found[0][2][:3, 3].copy()

    def agents(self) -> dict[tuple[str, int], int]:
        """Top-level subtrees that are robots: ``(side, unum)`` → index in :attr:`nodes`.

        A robot is the top-level node holding a mesh whose materials include ``matNum<N>``
        and ``matLeft``/``matRight`` (wire reference §7.6); ``side`` is ``"left"`` or ``"right"``.
        """
        found: dict[tuple[str, int], int] = {}
        for path, node, _ in self.walk():
            if not node.is_mesh:
                continue
            mats = node.materials
            side = "left" if "matLeft" in mats else "right" if "matRight" in mats else None
            if side is None:
                continue
            for m in mats:
                if m.startswith("matNum") and m[6:].isdigit():
                    found.setdefault((side, int(m[6:])), path[0])
        return found


def _apply(nodes: list[SceneNode], delta: Sequence[DeltaNode], where: str) -> None:
    if len(delta) != len(nodes):
        raise ProtocolError(
            f"delta does not match the scene at {where}: {len(delta)} node(s) instead of "
            f"{len(nodes)} (missed a full frame?)"
        )
    for i, (node, d) in enumerate(zip(nodes, delta, strict=True)):
        if d.kind is not None and d.kind != node.kind:
            raise ProtocolError(
                f"delta does not match the scene at {where}/{i}: {d.kind} instead of {node.kind}"
            )
        if d.slt is not None:
            node.slt = d.slt
        if d.props:
            node.props.update(d.props)
        _apply(node.children, d.children, f"{where}/{i}")


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------


def format_slt(matrix: np.ndarray | Sequence[float]) -> str:
    """``(SLT m0 … m15)`` of a 4×4 matrix (or its 16 column-major numbers), ``%g`` notation."""
    m = np.asarray(matrix, dtype=float)
    flat = m.T.ravel() if m.shape == (4, 4) else m.ravel()
    if flat.shape != (16,):
        raise ValueError(f"SLT needs a 4x4 matrix or 16 numbers, got shape {m.shape}")
    return "(SLT " + " ".join(fmt_g(v) for v in flat.tolist()) + ")"


def format_trf(matrix: np.ndarray | Sequence[float], children: str = "") -> str:
    """``(nd TRF (SLT …)<children>)``: a transform with already formatted children."""
    return f"(nd TRF {format_slt(matrix)}{children})"


def _nums(values: Sequence[float]) -> str:
    return " ".join(fmt_g(float(v)) for v in values)


def format_smn(
    model: str,
    scale: Sequence[float],
    material: str,
    *,
    load_params: Sequence[float | str] = (),
    visible: bool = True,
    transparent: bool = False,
) -> str:
    """A single-material mesh: ``(nd SMN (setVisible 1) (load <model> …) (sSc …) (sMat …))``."""
    params = "".join(f" {p if isinstance(p, str) else fmt_g(p)}" for p in load_params)
    return (
        f"(nd SMN (setVisible {int(visible)}){' (setTransparent)' if transparent else ''}"
        f" (load {_atom(model)}{params}) (sSc {_nums(scale)}) (sMat {_atom(material)}))"
    )


def format_static_mesh(
    model: str,
    scale: Sequence[float],
    materials: Sequence[str],
    *,
    visible: bool = True,
    transparent: bool = False,
) -> str:
    """An OBJ mesh: ``(nd StaticMesh (setVisible 1) (load …) (sSc …)(resetMaterials …))``."""
    mats = "".join(f" {_atom(m)}" for m in materials)
    return (
        f"(nd StaticMesh (setVisible {int(visible)}){' (setTransparent)' if transparent else ''}"
        f" (load {_atom(model)}) (sSc {_nums(scale)})(resetMaterials{mats}))"
    )


def format_light(
    diffuse: Sequence[float], ambient: Sequence[float], specular: Sequence[float]
) -> str:
    """``(nd Light (setDiffuse r g b a) (setAmbient …) (setSpecular …))``."""
    return (
        f"(nd Light (setDiffuse {_nums(diffuse)}) (setAmbient {_nums(ambient)})"
        f" (setSpecular {_nums(specular)}))"
    )


def _atom(text: str) -> str:
    if not is_atom(text):
        raise ValueError(f"{text!r} is not a single atom")
    return text


def _props_text(node: SceneNode | DeltaNode) -> str:
    # SparkMonitor writes every property with a leading space, except resetMaterials.
    out = []
    for key, values in node.props.items():
        body = "".join(f" {v}" if isinstance(v, str) else f" {dumps(v)}" for v in values)
        out.append(f"({key}{body})" if key == "resetMaterials" else f" ({key}{body})")
    return "".join(out)


def format_full_scene(nodes: Sequence[SceneNode]) -> str:
    """A full scene in the server's exact layout, e.g. ``((nd TRF (SLT …)(nd Light …))…)``."""
    return "(" + "".join(_full_node(n) for n in nodes) + ")"


def _full_node(node: SceneNode) -> str:
    parts = [f"(nd {node.kind}"]
    if node.slt is not None:
        parts.append(" " + format_slt(node.slt))
    parts.append(_props_text(node))
    parts.extend(_full_node(c) for c in node.children)
    parts.append(")")
    return "".join(parts)


def format_delta_scene(nodes: Sequence[DeltaNode]) -> str:
    """A delta scene in the server's exact layout, e.g. ``((nd(nd))(nd (SLT …)(nd SMN))…)``."""
    return "(" + "".join(_delta_text(n) for n in nodes) + ")"


def _delta_text(node: DeltaNode) -> str:
    parts = ["(nd" if node.kind is None else f"(nd {node.kind}"]
    if node.slt is not None:
        parts.append(" " + format_slt(node.slt))
    parts.append(_props_text(node))
    parts.extend(_delta_text(c) for c in node.children)
    parts.append(")")
    return "".join(parts)


class DeltaEncoder:
    """Writes full and delta scenes for one monitor stream, remembering what was sent.

    A delta repeats a node's ``SLT`` only when an entry moved by more than
    :data:`SLT_THRESHOLD` since it was last sent, and a mesh's ``setVisible`` only when it
    toggled (wire reference §7.4). Call :meth:`full` after any structural change, :meth:`delta`
    otherwise.
    """

    def __init__(self, threshold: float = SLT_THRESHOLD) -> None:
        self.threshold = threshold
        self._sent_slt: dict[tuple[int, ...], np.ndarray] = {}
        self._sent_visible: dict[tuple[int, ...], bool] = {}
        self._shape: list[object] | None = None

    def full(self, nodes: Sequence[SceneNode]) -> str:
        """The full scene text; resets the remembered state."""
        self._sent_slt.clear()
        self._sent_visible.clear()
        for path, node, _ in SceneGraph(list(nodes)).walk():
            if node.slt is not None:
                self._sent_slt[path] = node.slt.copy()
            if node.is_mesh:
                self._sent_visible[path] = node.visible
        self._shape = _shape(nodes)
        return format_full_scene(nodes)

    def delta(self, nodes: Sequence[SceneNode]) -> str:
        """The delta scene text relative to what was sent so far.

        Raises:
            ValueError: if the structure changed since the last :meth:`full` (send a full
                scene instead) or no full scene was sent yet.
        """
        if self._shape is None or _shape(nodes) != self._shape:
            raise ValueError("scene structure changed since the last full scene; send full()")
        return "(" + "".join(self._delta(n, (i,)) for i, n in enumerate(nodes)) + ")"

    def _delta(self, node: SceneNode, path: tuple[int, ...]) -> str:
        if node.is_mesh:
            text = f"(nd {node.kind}"
            visible = node.visible
            if self._sent_visible.get(path) != visible:
                self._sent_visible[path] = visible
                text += f" (setVisible {int(visible)})"
        else:
            text = "(nd"
            if node.slt is not None:
                sent = self._sent_slt.get(path)
                if sent is None or np.max(np.abs(node.slt - sent)) > self.threshold:
                    self._sent_slt[path] = node.slt.copy()
                    text += " " + format_slt(node.slt)
        children = "".join(self._delta(c, (*path, i)) for i, c in enumerate(node.children))
        return text + children + ")"


def _shape(nodes: Sequence[SceneNode]) -> list[object]:
    return [(n.kind, _shape(n.children)) for n in nodes]

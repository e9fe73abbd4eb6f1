"""MJCF generation for the Nao (any type) from the tables in :mod:`robocup_gym.robot.nao`.

Nothing here is hand-copied XML: every body, inertia, joint and geom comes from
:func:`robocup_gym.robot.nao.nao_model`. The world (field, ball, several robots) is assembled by
:mod:`robocup_gym.sim.engines.mujoco.scene`, which calls :func:`robot_xml` once per robot.

How SimSpark's joint motor is modelled
--------------------------------------
A SimSpark hinge is driven by an ODE *velocity motor*: a constraint row that makes the joint rate
equal to the commanded velocity using at most 10 N·m. Each hinge here has ``frictionloss = 10``:
MuJoCo's friction-loss row is exactly such a force-bounded velocity row, with target velocity 0.
The world (:mod:`robocup_gym.sim.engines.mujoco.world`) shifts the row's reference acceleration
every step so
that its target is the commanded velocity, which gives the ODE motor semantics: the joint moves at
the commanded velocity whenever ≤ 10 N·m suffices and otherwise accelerates with exactly 10 N·m.
"""

from __future__ import annotations

import numpy as np

from robocup_gym.robot.nao import Body, NaoModel, nao_model


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in np.atleast_1d(v))


def _geom(body: Body, prefix: str, rgba: str) -> str:
    name = f'name="{prefix}{body.name}"'
    if body.shape == "box":
        half = np.array(body.size) / 2
        return f'<geom {name} type="box" size="{_fmt(half)}" class="robot" rgba="{rgba}"/>'
    if body.shape == "sphere":
        return f'<geom {name} type="sphere" size="{body.size[0]:.9g}" class="robot" rgba="{rgba}"/>'
    if body.shape == "capsule":
        r, length = body.size[0], body.size[1]
        return (
            f'<geom {name} type="capsule" size="{r:.9g} {length / 2:.9g}" class="robot" '
            f'rgba="{rgba}"/>'
        )
    raise ValueError(body.shape)


def robot_xml(
    prefix: str,
    type_index: int = 0,
    *,
    rgba: str = "0.85 0.85 0.9 1",
    accent: str = "0.2 0.4 0.9 1",
) -> str:
    """MJCF of one Nao whose names all start with ``prefix``: its body tree (torso with a free
    joint at the origin in the zero pose; the world moves it). Robot geoms use default class
    ``robot``, joints class ``robot_joint`` (limits and motor rows, set by the scene); the
    non-colliding mass-only spheres get a visual-only sphere (group 3).
    """
    model = nao_model(type_index)
    children: dict[str | None, list[Body]] = {}
    for b in model.bodies:
        children.setdefault(b.parent, []).append(b)
    joint_of_child = {j.child: j for j in model.joints}

    def emit(body: Body, parent: Body | None, depth: int) -> str:
        ind = "  " * depth
        pos = np.array(body.pos) - (np.array(parent.pos) if parent else 0.0)
        lines = [f'{ind}<body name="{prefix}{body.name}" pos="{_fmt(pos)}">']
        if parent is None:
            lines.append(f'{ind}  <freejoint name="{prefix}root"/>')
        else:
            j = joint_of_child[body.name]
            anchor = np.array(j.anchor) - np.array(body.pos)
            lines.append(
                f'{ind}  <joint name="{prefix}{j.effector}" type="hinge" pos="{_fmt(anchor)}" '
                f'axis="{_fmt(j.axis)}" range="{_fmt(np.radians([j.min_deg, j.max_deg]))}" '
                f'class="robot_joint"/>'
            )
        lines.append(
            f'{ind}  <inertial pos="0 0 0" mass="{body.mass:.9g}" '
            f'diaginertia="{_fmt(body.inertia)}"/>'
        )
        if body.collides:
            colour = accent if body.name in ("torso", "head") else rgba
            lines.append(ind + "  " + _geom(body, prefix, colour))
        else:
            lines.append(
                f'{ind}  <geom type="sphere" size="{body.size[0]:.9g}" class="visual" '
                f'rgba="{rgba}"/>'
            )
        if body.name == "head":
            lines.append(f'{ind}  <site name="{prefix}camera" pos="0 0 0" size="0.005"/>')
        if body.name == "torso":
            lines.append(f'{ind}  <site name="{prefix}imu" pos="0 0 0" size="0.005"/>')
        for c in children.get(body.name, []):
            lines.append(emit(c, body, depth + 1))
        lines.append(f"{ind}</body>")
        return "\n".join(lines)

    return emit(children[None][0], None, 2)


def self_collision_excludes(prefix: str, model: NaoModel) -> str:
    """``<exclude>`` pairs that switch off contacts between parts of the same robot.

    SimSpark puts each robot in one ODE space with inner collision disabled (reference §1.1).
    """
    names = [b.name for b in model.bodies if b.collides]
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            out.append(f'    <exclude body1="{prefix}{a}" body2="{prefix}{b}"/>')
    return "\n".join(out)

"""The league's current robots (RCSSServerMJ, since 2026): Booster T1, K1 and whatever else the
installed ``rcsssmj`` ships, as data read from ``rcsssmj``'s own model files.

Nothing here is a copy: every number comes from the MJCF files of the installed ``rcsssmj``
package, through its own model loader (``rcsssmj.resources.spec_provider``). ``rcsssmj`` is an
optional dependency (``pip install robocup-gym[mj]``); without it :func:`league_robot` says so.

Units as the league's protocol uses them: joint commands are ``(<name> q dq kp kd tau)`` in
degrees, degrees per second, N·m per rad and N·m·s per rad, and N·m; :class:`LeagueRobot` keeps
the model's SI ranges (rad, N·m) and gives degrees where the wire uses them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "LeagueRobot",
    "RcsssmjUnavailableError",
    "clearance",
    "league_robot",
    "league_robot_names",
]


class RcsssmjUnavailableError(ImportError):
    """The ``rcsssmj`` package (the league's server) is not installed."""


def _rcsssmj_resources() -> Path:
    try:
        import rcsssmj.resources as res
    except ImportError as exc:
        raise RcsssmjUnavailableError(
            "the league's robots come from the rcsssmj package, which is not installed "
            f"({exc}); install it with: pip install 'robocup-gym[mj]' (or pip install rcsssmj)"
        ) from exc
    return Path(res.__file__).parent


def league_robot_names() -> list[str]:
    """The robots the installed ``rcsssmj`` ships (e.g. ``["K1", "T1", "ant"]``), sorted.

    Raises:
        RcsssmjUnavailableError: ``rcsssmj`` is not installed.
    """
    robots = _rcsssmj_resources() / "robots"
    return sorted(p.name for p in robots.iterdir() if (p / "robot.xml").is_file())


@dataclass(frozen=True)
class LeagueJoint:
    """One actuated joint of a league robot."""

    name: str
    """The joint's name in the model (``Left_Knee_Pitch``)."""
    effector: str
    """The name joint commands use (``lle4``): its actuators are ``<effector>_pos``, ``_vel``
    and ``_tau``."""
    range_rad: tuple[float, float]
    """Limits, rad."""
    force_range: tuple[float, float]
    """The actuator's torque limits, N·m: the PD torque is clamped to these."""
    perceptor: str = ""
    """The joint's name in the ``HJ`` perceptor (``q_llj4``), from its joint-position sensor."""

    @property
    def range_deg(self) -> tuple[float, float]:
        """Limits in degrees (the wire's unit)."""
        return (math.degrees(self.range_rad[0]), math.degrees(self.range_rad[1]))


@dataclass(frozen=True)
class LeagueRobot:
    """A robot of RCSSServerMJ, read from ``rcsssmj``'s model of it."""

    name: str
    """Model name, as ``(init <name> <team> <number>)`` requests it (``T1``, ``K1``)."""
    model_file: Path
    """The MJCF file in the installed ``rcsssmj``."""
    joints: tuple[LeagueJoint, ...]
    """Actuated joints, in the model's order (the order of the ``HJ`` perceptors)."""
    sensors: tuple[str, ...]
    """Names of the model's sensors (without the per-player prefix)."""
    standing_torso_height: float = 0.0
    """Torso centre height (m) with every joint at 0 and the lowest point on the ground."""
    foot_bodies: tuple[str, str] = ("", "")
    """The model's (left, right) foot bodies (the bodies named ``left_foot…``/``right_foot…``)."""
    right_foot_offset: tuple[float, float] = (0.0, 0.0)
    """Right foot body's (forward, left) offset from the torso, m, all joints at 0."""
    ball_radius: float = 0.11
    """Radius of the league's ball, m (from ``rcsssmj``'s soccer world model)."""
    total_mass: float = 0.0
    """Sum of the model's body masses, kg."""
    joint_index: dict[str, int] = field(default_factory=dict, compare=False)
    """Joint index (model order) by effector (``lle4``), perceptor (``q_llj4``) or model
    (``Left_Knee_Pitch``) name."""

    def __post_init__(self) -> None:
        for i, j in enumerate(self.joints):
            for n in (j.effector, j.perceptor, j.name):
                if n:
                    self.joint_index.setdefault(n, i)

    max_joint_speed_rad_s: float = 20.0
    """The range joint velocities are normalised over in observations, rad/s (the models set
    no speed limits; this is a scale, not a limit)."""

    @functools.cached_property
    def max_speeds(self) -> np.ndarray:
        """Per joint :attr:`max_joint_speed_rad_s` (the observation's velocity scale)."""
        return np.full(len(self.joints), self.max_joint_speed_rad_s)

    @property
    def label(self) -> str:
        """How messages name the robot (``"T1"``)."""
        return self.name

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def effector_names(self) -> tuple[str, ...]:
        """The joint command names (``he1``, …), model order."""
        return tuple(j.effector for j in self.joints)

    @property
    def perceptor_names(self) -> tuple[str, ...]:
        """The ``HJ`` perceptor names (``q_hj1``, …), model order."""
        return tuple(j.perceptor for j in self.joints)

    @functools.cached_property
    def ranges_deg(self) -> np.ndarray:
        """Joint limits, degrees, shape ``(n, 2)``, model order."""
        return np.array([j.range_deg for j in self.joints])

    def check_commands(self, commands) -> None:
        """Refuse PD commands (effector name → :class:`~robocup_gym.types.PDCommand`) that name
        an unknown joint, aim outside the joint's range, use a negative gain or ask for more
        feed-forward torque than the actuator has (the server would take them; a library user
        gets told). NaN and inf are refused by ``PDCommand`` itself.

        Raises:
            ValueError: naming the joint, the value and the valid range.
        """
        index = self.joint_index
        for name, c in commands.items():
            i = index.get(name)
            if i is None:
                raise ValueError(
                    f"unknown joint {name!r}; the {self.name}'s joints: "
                    f"{', '.join(self.effector_names)}"
                )
            j = self.joints[i]
            lo, hi = j.range_deg
            if not lo - 1e-6 <= c.q_deg <= hi + 1e-6:
                raise ValueError(
                    f"target of {name} ({j.name}) is {c.q_deg:g}°, outside its range "
                    f"[{lo:g}, {hi:g}]°"
                )
            if c.kp < 0 or c.kd < 0:
                raise ValueError(f"gains of {name} must be >= 0, got kp={c.kp:g}, kd={c.kd:g}")
            tlo, thi = j.force_range
            if not tlo - 1e-9 <= c.tau <= thi + 1e-9:
                raise ValueError(
                    f"feed-forward torque of {name} is {c.tau:g} N·m, outside its actuator's "
                    f"range [{tlo:g}, {thi:g}] N·m"
                )

    @functools.cached_property
    def torque_limits(self) -> np.ndarray:
        """The actuators' torque limits, N·m, shape ``(n, 2)``, model order."""
        return np.array([j.force_range for j in self.joints])

    def joint(self, name: str) -> LeagueJoint:
        """The joint called ``name``.

        Raises:
            KeyError: naming the robot's joints.
        """
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(
            f"{self.name} has no joint {name!r}; its joints: {', '.join(self.joint_names)}"
        )


@functools.cache
def league_robot(name: str) -> LeagueRobot:
    """The league robot ``name`` (``"T1"``, ``"K1"``, …) from the installed ``rcsssmj`` (read
    once per process: the data is immutable).

    Raises:
        RcsssmjUnavailableError: ``rcsssmj`` is not installed.
        ValueError: no such robot (naming those there are).
    """
    names = league_robot_names()
    if name not in names:
        raise ValueError(f"unknown league robot {name!r}; rcsssmj ships: {', '.join(names)}")
    import mujoco
    from rcsssmj.resources.spec_provider import ModelSpecProvider

    spec = ModelSpecProvider().load_robot_spec(name)
    model = spec.compile()
    effector = {}  # joint id -> command name, from the joint's torque actuator
    for k in range(model.nu):
        actuator = model.actuator(k).name
        if actuator.endswith("_tau"):
            effector[int(model.actuator_trnid[k][0])] = actuator[: -len("_tau")]
    perceptor = {  # joint id -> HJ name, from the joint's position sensor
        int(model.sensor_objid[k]): model.sensor(k).name
        for k in range(model.nsensor)
        if int(model.sensor_type[k]) == int(mujoco.mjtSensor.mjSENS_JOINTPOS)
    }
    joints = []
    for j in range(model.njnt):
        if int(model.jnt_type[j]) not in (
            int(mujoco.mjtJoint.mjJNT_HINGE),
            int(mujoco.mjtJoint.mjJNT_SLIDE),
        ):
            continue
        lo, hi = (float(v) for v in model.jnt_range[j])
        flo, fhi = (float(v) for v in model.jnt_actfrcrange[j])
        joint = model.joint(j).name
        joints.append(
            LeagueJoint(joint, effector.get(j, joint), (lo, hi), (flo, fhi), perceptor.get(j, ""))
        )
    sensors = tuple(model.sensor(k).name for k in range(model.nsensor))
    height, feet, right = _standing_geometry(ModelSpecProvider().load_robot_spec(name))
    return LeagueRobot(
        name=name,
        model_file=_rcsssmj_resources() / "robots" / name / "robot.xml",
        joints=tuple(joints),
        sensors=sensors,
        standing_torso_height=height,
        foot_bodies=feet,
        right_foot_offset=right,
        ball_radius=_ball_radius(),
        total_mass=float(model.body_mass.sum()),
    )


def clearance(model, data, geoms, planes) -> float:
    """How far (m) the lowest of the collision geometries ``geoms`` is above the plane
    geometries ``planes`` (negative: below), by MuJoCo's own geometry distance
    (``mj_geomDistance``; geometries that collide with nothing are left out)."""
    import mujoco

    planes = list(planes)
    fromto = np.zeros(6)
    best = math.inf
    for g in geoms:
        if model.geom_contype[g] or model.geom_conaffinity[g]:
            for p in planes:
                best = min(best, mujoco.mj_geomDistance(model, data, g, p, 10.0, fromto))
    return best


def _standing_geometry(spec) -> tuple[float, tuple[str, str], tuple[float, float]]:
    """The robot standing with every joint at 0: torso height (m) with its lowest point on a
    ground plane (MuJoCo's geometry distance), its foot bodies and the right foot's offset."""
    import mujoco

    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1], name="_ground")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    plane = model.geom("_ground").id
    lowest = clearance(model, data, (g for g in range(model.ngeom) if g != plane), [plane])
    torso = 1  # the root body, child of the world
    names = [model.body(b).name for b in range(model.nbody)]
    left = next((n for n in names if n.lower().startswith("left_foot")), "")
    right = next((n for n in names if n.lower().startswith("right_foot")), "")
    offset = (0.0, 0.0)
    if right:
        d = data.body(right).xpos - data.xpos[torso]
        offset = (float(d[0]), float(d[1]))
    return float(data.xpos[torso][2] - lowest), (left, right), offset


@functools.cache
def _ball_radius() -> float:
    """The league ball's radius, m, from ``rcsssmj``'s soccer world model (geometry ``ball``)."""
    from rcsssmj.resources.spec_provider import ModelSpecProvider

    spec = ModelSpecProvider().load_environment_spec("soccer", "world")
    model = spec.compile()
    return float(model.geom("ball").size[0])

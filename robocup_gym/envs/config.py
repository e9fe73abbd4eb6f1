"""Configuration of the RoboCup Gym environments: one typed, documented dataclass.

Every option of :class:`EnvConfig` has a default, so ``EnvConfig()`` (and therefore every
environment constructed without arguments) works. Environments also take any field as a keyword
argument, e.g. ``gymnasium.make("RobocupGym/VelocityKick-v0", wait_steps=50, robot_type=4)``.

Units follow SimSpark: joint angles in degrees, joint speeds in rad/s, positions in m (world frame:
origin at the field centre, x towards the right team's goal, z up).
"""

from __future__ import annotations

import dataclasses
import enum
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robocup_gym.protocol.constants import PLAY_MODES
from robocup_gym.robot.nao import NaoModel, nao_model
from robocup_gym.robot.types import is_type_number
from robocup_gym.sim.field import FIELD_LENGTH, FIELD_WIDTH
from robocup_gym.sim.physics import BALL_REST_Z
from robocup_gym.types import check_field_kinds, is_names, is_number

__all__ = [
    "BALL_REST_Z",
    "DEFAULT_OBSERVATIONS",
    "PAPER_STANDING_POSE_DEG",
    "ActionMode",
    "EnvConfig",
    "EnvConfigError",
    "Normalisation",
    "resolve_joints",
]


DEFAULT_OBSERVATIONS: tuple[str, ...] = (
    "joint_pos",
    "joint_vel",
    "ball_rel",
    "foot_force",
    "accel",
    "gyro",
    "time",
)
"""The RobocupGym paper's observation: joints and their velocities, the ball relative to the robot,
foot pressure, accelerometer, gyroscope and the episode step."""

PAPER_STANDING_POSE_DEG: dict[str, float] = {
    "HeadYaw": -18.6,
    "HeadPitch": -45.0,
    "LShoulderPitch": -81.51,
    "LShoulderRoll": 14.86,
    "LElbowYaw": -70.0,
    "LElbowRoll": -15.0,
    "LHipYawPitch": 0.0,
    "LHipRoll": -0.26,
    "LHipPitch": 25.57,
    "LKneePitch": -59.42,
    "LAnklePitch": 33.84,
    "LAnkleRoll": 0.25,
    "RHipYawPitch": 0.0,
    "RHipRoll": -0.26,
    "RHipPitch": 25.58,
    "RKneePitch": -59.42,
    "RAnklePitch": 33.84,
    "RAnkleRoll": 0.25,
    "RShoulderPitch": -81.51,
    "RShoulderRoll": -15.14,
    "RElbowYaw": 70.0,
    "RElbowRoll": 15.0,
}
"""The crouched standing pose the RobocupGym paper drives the joints to before every episode
(``STANDING_JOINT_ANGLES``), by Nao joint name, degrees. Use it as
``EnvConfig(joint_start_deg=PAPER_STANDING_POSE_DEG)``."""


ON_FIELD_MARGIN_M = 1.0
"""How far outside the field's lines a start position may be, m."""
ON_FIELD_X_M = FIELD_LENGTH / 2 + ON_FIELD_MARGIN_M
ON_FIELD_Y_M = FIELD_WIDTH / 2 + ON_FIELD_MARGIN_M


def _finite(v: Any) -> bool:
    try:
        return math.isfinite(float(v)) and not isinstance(v, bool)
    except (TypeError, ValueError):
        return False


def _pair(v: Any) -> bool:
    try:
        return len(v) == 2 and all(_finite(x) for x in v)
    except TypeError:
        return False


class EnvConfigError(ValueError):
    """An invalid environment configuration (unknown name, impossible value, …)."""


class ActionMode(str, enum.Enum):
    """How an action in [-1, 1] per controlled joint becomes a joint velocity command."""

    VELOCITY = "velocity"
    """One number per joint: the target joint velocity, scaled to ±the joint's max speed (rad/s).
    (Paper: ``ActionMode.VELOCITIES``.)"""
    TARGET_ANGLE = "target_angle"
    """One number per joint: a target angle, scaled to the joint's range [min, max] (deg). On the
    Nao the velocity sent is ``clip(target_gain · (target − current), ±max speed)``; on a league
    robot it is the PD command's target, with the joint's default gains (see
    ``pd_saturation_deg``).
    (Paper: ``ActionMode.DESIRED_ANGLES``, with gain 1/s.)"""
    TARGET_ANGLE_GAINS = "target_angle_gains"
    """League robots (PD joints) only. Three numbers per joint, interleaved ``[angle_0, kp_0,
    kd_0, …]``: the target angle (scaled to the joint's range) and the PD gains, each scaled to
    [0, 2 ×] the joint's default gain (see ``pd_saturation_deg`` and ``pd_damping_s``)."""
    TORQUE = "torque"
    """League robots (PD joints) only. One number per joint: the torque, scaled to ±the
    actuator's limit (N·m), sent as the feed-forward torque with zero gains."""
    TARGET_ANGLE_MAX_SPEED = "target_angle_max_speed"
    """Two numbers per joint, interleaved ``[angle_0, speed_0, angle_1, speed_1, …]``: the target
    angle (scaled to the joint's range) and a speed limit (scaled to [0, max speed]); the velocity
    sent is ``clip(target_gain · (target − current), ±speed limit)``.
    (Paper: ``ActionMode.DESIRED_ANGLES_MAX_SPEED``.)"""

    def __str__(self) -> str:
        return self.value


class Normalisation(str, enum.Enum):
    """How raw observation values (SI/SimSpark units) are scaled before clipping."""

    MIN_MAX = "min_max"
    """Analytic min–max: each value's documented range [lo, hi] maps linearly onto [-1, 1]."""
    MIN_MAX_01 = "min_max_01"
    """Analytic min–max onto [0, 1], as the paper's ``MIN_MAX_ANALYTIC``."""
    NONE = "none"
    """Raw values in their units (set ``obs_clip=None`` to keep them unclipped)."""

    def __str__(self) -> str:
        return self.value


_CHECKED_IN_VALIDATE = frozenset({"int"})
"""Annotations whose fields :meth:`EnvConfig.validate` checks with messages of their own
(``robot_type must be one of the integers 0, 1, 2, 3, 4``)."""


def _enum_value(enum_cls: type[enum.Enum], value: Any, what: str) -> Any:
    if isinstance(value, enum_cls):
        return value
    aliases = {
        "VELOCITIES": "velocity",
        "DESIRED_ANGLES": "target_angle",
        "DESIRED_ANGLES_MAX_SPEED": "target_angle_max_speed",
        "MIN_MAX_ANALYTIC": "min_max_01",
        "NONE": "none",
    }
    key = str(getattr(value, "value", value))
    key = aliases.get(key, key).lower()
    try:
        return enum_cls(key)
    except ValueError:
        valid = ", ".join(repr(m.value) for m in enum_cls)
        raise EnvConfigError(f"unknown {what} {value!r}; valid: {valid}") from None


def robot_model(config: EnvConfig) -> Any:
    """The robot a config describes: a :class:`~robocup_gym.robot.nao.NaoModel` of
    ``robot_type``, or the :class:`~robocup_gym.robot.league.LeagueRobot` named ``robot``.

    Raises:
        EnvConfigError: an unknown robot name (listing the valid ones).
        robocup_gym.robot.league.RcsssmjUnavailableError: a league robot without ``rcsssmj``.
    """
    if config.robot == "nao":
        return nao_model(int(config.robot_type))
    return league_robot_of(config.robot)


def nao_type(config: EnvConfig) -> int | None:
    """The Nao type a config runs (``robot_type``), or ``None`` where its robot is a league
    robot (whose ``robot_type`` means nothing)."""
    return int(config.robot_type) if config.robot == "nao" else None


def league_robot_of(name: Any) -> Any:
    """The :class:`~robocup_gym.robot.league.LeagueRobot` called ``name``.

    Raises:
        EnvConfigError: an unknown robot name (listing the valid ones).
        robocup_gym.robot.league.RcsssmjUnavailableError: ``rcsssmj`` is not installed.
    """
    if not isinstance(name, str):
        raise EnvConfigError(f"robot must be a name, got {name!r}")
    from robocup_gym.robot.league import league_robot, league_robot_names

    names = league_robot_names()
    if name not in names:
        raise EnvConfigError(
            f"unknown robot {name!r}; valid: 'nao' (rcssserver3d) or, from the installed "
            f"rcsssmj: {', '.join(map(repr, names))}"
        )
    return league_robot(name)


@dataclass
class EnvConfig:
    """Everything that defines a RoboCup Gym environment except its reward.

    Tasks subclass this to add their reward coefficients (see
    :class:`robocup_gym.envs.tasks.VelocityKickConfig`). All fields are plain values so a config
    can be copied, compared, pickled and logged (:meth:`to_dict`).
    """

    policy_options = frozenset(
        {
            "robot", "observed_joints", "normalise", "obs_clip", "frame_stack",
            "controlled_joints", "action_mode", "pd_saturation_deg", "pd_damping_s",
            "target_gain", "target_stop_margin_deg", "target_around_start_deg",
            "mirror_actions", "joint_start_deg",
        }
    )  # fmt: skip
    """The options that shape how a policy acts (the robot and the joints it drives, how its
    actions become joint commands, the stance it starts from, how its observations are
    scaled): a policy that starts a run of another task (``--init-from``) takes them along;
    the others (observations, reward, starts, episode ends, commands) are the task's own."""

    # ---------------------------------------------------------------- observation
    observations: tuple[str, ...] = DEFAULT_OBSERVATIONS
    """Observation components, concatenated in this order (see
    :data:`robocup_gym.envs.observations.COMPONENTS` and ``docs/environments.md``)."""
    observed_joints: tuple[str, ...] | None = None
    """Joints in ``joint_pos``/``joint_vel`` (effector, perceptor or Nao names); ``None`` = the
    controlled joints."""
    normalise: Normalisation | str = Normalisation.MIN_MAX
    """``"min_max"`` (→ [-1, 1]), ``"min_max_01"`` (→ [0, 1], the paper's) or ``"none"``."""
    obs_clip: float | None = 1.0
    """Clip every (normalised) observation value to ±obs_clip; ``None`` = no clipping (paper: 1)."""
    frame_stack: int = 1
    """Number of consecutive frames in one observation (oldest first); the first frame of an
    episode fills the stack."""
    observation_noise_std: float = 0.0
    """σ of Gaussian noise added to every observation value after normalisation (in normalised
    units; raw units with ``normalise="none"``)."""
    kick_target: tuple[float, float] = (20.0, 0.0)
    """``kick_target`` component: desired kick distance (m) and direction (deg, 0 = robot's
    forward, CCW positive)."""
    randomise_kick_target: bool = False
    """Draw a new kick target every episode: distance uniform in ``kick_target_distance_range``,
    angle uniform in ``kick_target_angle_range``."""
    kick_target_distance_range: tuple[float, float] = (3.0, 10.0)
    """m (paper: 3–10)."""
    kick_target_angle_range: tuple[float, float] = (-45.0, 45.0)
    """deg (paper: ±45)."""

    # ---------------------------------------------------------------- action
    controlled_joints: tuple[str, ...] | None = None
    """Joints the policy drives (effector, perceptor or Nao names), in action order; ``None`` =
    every joint except the head (``he1``, ``he2``). Other joints get a 0 rad/s command."""
    action_mode: ActionMode | str = ActionMode.VELOCITY
    """``"velocity"``, ``"target_angle"`` or ``"target_angle_max_speed"`` on the Nao;
    ``"target_angle"`` (the default there), ``"target_angle_gains"`` or ``"torque"`` on a league
    robot (see :class:`ActionMode`)."""
    pd_saturation_deg: float = 20.0
    """League robots: the default proportional gain of each joint makes its actuator's whole
    torque at this angle error, ``kp = τ_max / θ_sat`` (N·m/rad)."""
    pd_damping_s: float = 0.05
    """League robots: the default derivative gain, ``kd = kp × pd_damping_s`` (N·m·s/rad)."""
    target_gain: float = 12.5
    """Proportional gain of the target-angle modes, 1/s: velocity = gain × angle error. 12.5 is
    critically damped with SimSpark's one-cycle dead time (the error halves every cycle);
    the paper used 1.0."""
    target_stop_margin_deg: float = 0.5
    """Target-angle modes on the Nao: target angles stay this far inside each joint's stops,
    deg. rcssserver3d takes a joint's velocity only while the joint is strictly inside its
    stops (reference §8.3), so a joint driven exactly onto a stop obeys or ignores the next command
    on differences of rounding, and the same policy then moves differently in-process and on a
    real server; kept off the stops, it moves the same. 0: targets may reach the stops."""
    target_around_start_deg: float | None = None
    """Target-angle modes: ``None``, an action of ±1 spans each joint's whole range (0 is its
    middle); a number of degrees, the action spans the start pose (``joint_start_deg``) ± that
    many degrees, clipped to the range, so action 0 holds the start pose (the default-pose offset
    of legged_gym's and MuJoCo Playground's locomotion policies, their ``action_scale``). Modes
    without target angles (``velocity``, ``torque``) ignore it."""
    mirror_actions: bool = False
    """One action value per left/right pair of controlled joints (the Nao's default joints: 10
    values instead of 20): the right joint does the mirror image of the left one across the
    sagittal plane, the sign taken from the joints' axes, so the robot moves symmetrically. For
    symmetric skills (getting up) it halves what the policy has to explore. ``velocity`` and
    ``target_angle`` modes, the Nao only."""
    action_noise_std: float = 0.0
    """σ of Gaussian noise added to the action (in [-1, 1] units, before scaling; the noisy
    action is clipped to [-1, 1])."""

    # ---------------------------------------------------------------- episode
    robot_type: int = 0
    """Heterogeneous Nao type 0–4 (4 has toes: joints ``lle7``/``rle7``)."""
    robot: str = "nao"
    """``"nao"`` (rcssserver3d's robot, of ``robot_type``) or a robot of the league's current
    simulator, RCSSServerMJ: ``"T1"``, ``"K1"`` (whatever the installed ``rcsssmj`` ships; needs
    ``pip install robocup-gym[mj]``). A league robot runs on the ``"rcsssmj"`` backend, and the
    task's options left at their Nao defaults take the robot's (:meth:`BaseEnv.default_config`)."""
    robot_start_pos: tuple[float, float] = (-1.0, 0.0)
    """Torso centre (x, y) at the start of an episode, m; the robot stands on the ground."""
    robot_start_heading_deg: float = 0.0
    """Direction the robot faces at the start, deg (0 = +x, towards the opponent goal)."""
    joint_start_deg: Mapping[str, float] | None = None
    """Start pose: joint angles in degrees by effector, perceptor or Nao name (others 0);
    ``None`` = all joints at 0 (upright). :data:`PAPER_STANDING_POSE_DEG` is the paper's pose."""
    joint_start_noise_deg: float | Mapping[str, float] = 0.0
    """σ of Gaussian noise (deg) added to each start angle every episode (one number for all
    joints or by name); the result is clipped to the joint's range."""
    ball_start_pos: tuple[float, float, float] = (-0.8, -0.055, BALL_REST_Z)
    """Ball centre at the start (x, y, z), m; default 0.2 m ahead of the robot and 0.055 m to
    its right (in front of the right foot), resting on the ground. ``(x, y)`` is accepted and
    completed with the resting height :data:`BALL_REST_Z`."""
    ball_start_vel: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Ball velocity at the start, m/s."""
    ball_spawn_noise: float = 0.0
    """Radius (m) of the ball's spawn noise: every episode the ball starts at a uniformly random
    point on the circle of this radius around ``ball_start_pos`` (as the paper)."""
    max_episode_steps: int = 40
    """Steps (20 ms agent cycles) after which an episode is truncated (paper's kick runs: 40).
    ``gymnasium.make(id, max_episode_steps=N)`` does not set it (Gymnasium keeps that argument
    for its own ``TimeLimit`` wrapper): pass ``config=<Task>Config(max_episode_steps=N)``, a task
    class's keyword, or ``robocup_gym.train.tasks.make_env``'s ``env_kwargs`` (and so ``--env``
    on the CLI), which sets both."""
    wait_steps: int = 0
    """After the episode ends (terminated or truncated) the world runs on for this many cycles
    with zero joint velocities before the final reward is computed, so the ball can roll."""
    terminate_on_fall: bool = True
    """End the episode (terminated) when the robot has fallen."""
    fall_up_z: float = 0.5
    """Fallen when the world z component of the torso's up axis drops below this (0.5 = tilted
    by more than 60°)…"""
    fall_height: float = 0.25
    """…or when the torso centre is lower than this, m (standing: ≈0.38)."""
    play_mode: str = "PlayOn"
    """Play mode during the episode (wire name)."""
    self_collisions: bool = False
    """Run rcssserver3d's self-collision rule in the in-process world
    (:mod:`robocup_gym.sim.self_collision`: while the game runs, a robot whose own boxes
    collide has those parts' joints frozen for 1 s), as a real server always does and as
    ``robocup-gym serve`` does. Off in the environments' current versions, whose behaviour it
    would change."""

    # ---------------------------------------------------------------- backend
    backend_options: Mapping[str, Any] = field(default_factory=dict)
    """Extra keyword arguments for the backend (e.g. ``{"physics": PhysicsConfig(...)}`` or
    ``{"vision_config": VisionConfig(noise=False)}`` for ``"mujoco"``)."""

    def __post_init__(self) -> None:
        if not isinstance(self.self_collisions, bool):
            raise EnvConfigError(
                f"self_collisions must be true or false, got {self.self_collisions!r}"
            )
        if not is_names(self.observations):
            raise EnvConfigError(
                f"observations must be a list of component names, got {self.observations!r}"
            )
        self.observations = tuple(self.observations)
        try:
            pos = tuple(float(v) for v in self.ball_start_pos)
            vel = tuple(float(v) for v in self.ball_start_vel)
            robot = tuple(float(v) for v in self.robot_start_pos)
        except (TypeError, ValueError) as e:
            raise EnvConfigError(
                "ball_start_pos, ball_start_vel and robot_start_pos must be sequences of numbers "
                f"(m, m/s): {e}"
            ) from None
        self.ball_start_pos = (*pos, BALL_REST_Z) if len(pos) == 2 else pos
        self.ball_start_vel, self.robot_start_pos = vel, robot
        for name in ("observed_joints", "controlled_joints"):
            v = getattr(self, name)
            if v is not None:
                if isinstance(v, str):
                    raise EnvConfigError(f"{name} must be a sequence of joint names, not a string")
                setattr(self, name, tuple(v))
        self.normalise = _enum_value(Normalisation, self.normalise, "normalisation")
        self.action_mode = _enum_value(ActionMode, self.action_mode, "action mode")
        check_field_kinds(self, EnvConfigError, skip=_CHECKED_IN_VALIDATE)
        self.validate()

    # ---------------------------------------------------------------- helpers
    def validate(self) -> None:
        """Check the values that do not depend on the robot model.

        Raises:
            EnvConfigError: naming the field and the problem.
        """

        def need(cond: bool, msg: str) -> None:
            if not cond:
                raise EnvConfigError(msg)

        need(len(self.observations) > 0, "observations must name at least one component")
        need(
            len(set(self.observations)) == len(self.observations),
            f"observations lists a component twice: {list(self.observations)}",
        )
        need(
            isinstance(self.frame_stack, int | np.integer) and self.frame_stack >= 1,
            f"frame_stack must be an integer >= 1, got {self.frame_stack!r}",
        )
        need(
            isinstance(self.max_episode_steps, int | np.integer) and self.max_episode_steps >= 1,
            f"max_episode_steps must be an integer >= 1, got {self.max_episode_steps!r}",
        )
        need(
            isinstance(self.wait_steps, int | np.integer) and self.wait_steps >= 0,
            f"wait_steps must be an integer >= 0, got {self.wait_steps!r}",
        )
        need(
            self.obs_clip is None
            or (math.isfinite(self.obs_clip) and self.obs_clip > 0)
            or self.obs_clip == math.inf,
            f"obs_clip must be > 0 or None, got {self.obs_clip!r}",
        )
        for name in ("observation_noise_std", "action_noise_std", "ball_spawn_noise"):
            v = getattr(self, name)
            need(math.isfinite(v) and v >= 0, f"{name} must be a finite number >= 0, got {v!r}")
        need(
            math.isfinite(self.target_gain) and self.target_gain > 0,
            f"target_gain must be > 0 (1/s), got {self.target_gain!r}",
        )
        need(
            _finite(self.target_stop_margin_deg) and 0.0 <= self.target_stop_margin_deg <= 5.0,
            "target_stop_margin_deg must be a number of degrees in [0, 5], got "
            f"{self.target_stop_margin_deg!r}",
        )
        need(
            len(self.ball_start_pos) == 3 and all(map(math.isfinite, self.ball_start_pos)),
            f"ball_start_pos must be (x, y) or (x, y, z) in m, got {self.ball_start_pos!r}",
        )
        need(
            len(self.ball_start_vel) == 3 and all(map(math.isfinite, self.ball_start_vel)),
            f"ball_start_vel must be 3 finite numbers (m/s), got {self.ball_start_vel!r}",
        )
        need(
            len(self.robot_start_pos) == 2 and all(map(math.isfinite, self.robot_start_pos)),
            f"robot_start_pos must be (x, y) in m, got {self.robot_start_pos!r}",
        )
        need(
            is_type_number(self.robot_type),
            f"robot_type must be one of the integers 0, 1, 2, 3, 4, got {self.robot_type!r}",
        )
        for name, pos in (
            ("robot_start_pos", self.robot_start_pos),
            ("ball_start_pos", self.ball_start_pos),
        ):
            need(
                abs(pos[0]) <= ON_FIELD_X_M and abs(pos[1]) <= ON_FIELD_Y_M,
                f"{name} ({pos[0]:g}, {pos[1]:g}) is off the field: x must be within "
                f"±{ON_FIELD_X_M:g} m and y within ±{ON_FIELD_Y_M:g} m (the field's lines and "
                f"{ON_FIELD_MARGIN_M:g} m around them)",
            )
        need(
            0.0 <= self.ball_start_pos[2] <= 5.0,
            f"ball_start_pos z must be between 0 and 5 m, got {self.ball_start_pos[2]!r}",
        )
        need(
            _finite(self.robot_start_heading_deg),
            f"robot_start_heading_deg must be a finite number (deg), got "
            f"{self.robot_start_heading_deg!r}",
        )
        need(
            _pair(self.kick_target),
            f"kick_target must be 2 finite numbers (m, deg), got {self.kick_target!r}",
        )
        for name in ("kick_target_distance_range", "kick_target_angle_range"):
            v = getattr(self, name)
            need(
                _pair(v) and float(v[0]) <= float(v[1]),
                f"{name} must be 2 finite numbers (low, high) with low <= high, got {v!r}",
            )
        need(
            _finite(self.fall_height) and 0.0 <= self.fall_height <= 1.0,
            f"fall_height must be a torso height between 0 and 1 m (standing: ~0.38), got "
            f"{self.fall_height!r}",
        )
        need(
            _finite(self.fall_up_z) and -1.0 <= self.fall_up_z <= 1.0,
            f"fall_up_z must be between -1 and 1 (the world z of the torso's up axis; 0.5 = "
            f"tilted 60°), got {self.fall_up_z!r}",
        )
        need(
            self.play_mode in PLAY_MODES,
            f"unknown play_mode {self.play_mode!r}; valid: {', '.join(PLAY_MODES)}",
        )
        need(
            _finite(self.pd_saturation_deg) and 0.0 < self.pd_saturation_deg <= 180.0,
            f"pd_saturation_deg must be in (0, 180] deg, got {self.pd_saturation_deg!r}",
        )
        need(
            _finite(self.pd_damping_s) and self.pd_damping_s >= 0.0,
            f"pd_damping_s must be a number >= 0 (s), got {self.pd_damping_s!r}",
        )
        model = robot_model(self)
        league = self.robot != "nao"
        pd_modes = (ActionMode.TARGET_ANGLE, ActionMode.TARGET_ANGLE_GAINS, ActionMode.TORQUE)
        if league and self.action_mode not in pd_modes:
            raise EnvConfigError(
                f"action_mode {self.action_mode.value!r} is for the Nao; the {self.robot} takes "
                f"PD joint commands: {', '.join(repr(m.value) for m in pd_modes)}"
            )
        if not league and self.action_mode in pd_modes[1:]:
            raise EnvConfigError(
                f"action_mode {self.action_mode.value!r} is for the league's robots (PD joints); "
                "the Nao's: 'velocity', 'target_angle', 'target_angle_max_speed'"
            )
        if self.target_around_start_deg is not None:
            need(
                _finite(self.target_around_start_deg) and 0.0 < self.target_around_start_deg <= 360,
                "target_around_start_deg must be None or a number of degrees in (0, 360], got "
                f"{self.target_around_start_deg!r}",
            )
        if self.mirror_actions and (
            league or self.action_mode is ActionMode.TARGET_ANGLE_MAX_SPEED
        ):
            raise EnvConfigError(
                "mirror_actions works on the Nao with action_mode 'velocity' or 'target_angle', "
                f"not on robot {self.robot!r} with {self.action_mode.value!r}"
            )
        if self.joint_start_deg is not None:
            angles = resolve_angles(model, self.joint_start_deg, "joint_start_deg")
            check_joint_ranges(model, angles, "joint_start_deg")
        if self.normalise is Normalisation.NONE and self.obs_clip not in (None, math.inf):
            warnings.warn(
                f"normalise='none' with obs_clip={self.obs_clip} clips raw observations "
                "(degrees, N, m/s², …); pass obs_clip=None to keep them unclipped",
                stacklevel=3,
            )

    @property
    def ball_start(self) -> np.ndarray:
        """``ball_start_pos`` as an array (x, y, z), m."""
        return np.array(self.ball_start_pos, dtype=float)

    def replace(self, **changes: Any) -> EnvConfig:
        """A copy with ``changes`` applied (and validated).

        Raises:
            EnvConfigError: for a name that is not a field of this config.
        """
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise EnvConfigError(
                f"unknown option(s) {', '.join(map(repr, unknown))} for {type(self).__name__}; "
                f"valid options: {', '.join(sorted(names))}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict of all options (enums as strings)."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, enum.Enum):
                v = v.value
            elif isinstance(v, Mapping | tuple):
                v = _jsonable(v)
            out[f.name] = v
        return out


def _jsonable(value: Any) -> Any:
    """``value`` with tuples as lists and mappings' keys as strings, all the way down; an object
    JSON cannot hold (a backend's options, say) as its ``repr``."""
    if value is None or isinstance(value, int | float | str | bool):
        return value
    if isinstance(value, Mapping):
        return {str(k): _jsonable(x) for k, x in value.items()}
    if isinstance(value, tuple | list):
        return [_jsonable(x) for x in value]
    return repr(value)


def resolve_joints(model: NaoModel, names: Sequence[str], what: str) -> np.ndarray:
    """Canonical indices of joints given by effector (``rle3``), perceptor (``rlj3``) or Nao
    (``RHipPitch``) name.

    Raises:
        EnvConfigError: unknown or repeated name (lists the valid names for this robot type).
    """
    idx = model.joint_index
    out = []
    for n in names:
        if n not in idx:
            raise EnvConfigError(
                f"unknown joint {n!r} in {what} for {model.label}; valid "
                f"effector names: {', '.join(model.effector_names)} (perceptor names like "
                f"'rlj3' and Nao names like 'RHipPitch' work too)"
            )
        out.append(idx[n])
    if len(set(out)) != len(out):
        raise EnvConfigError(f"{what} names a joint twice: {list(names)}")
    return np.array(out, dtype=int)


def check_joint_ranges(model: NaoModel, angles_deg: np.ndarray, what: str) -> None:
    """Refuse joint angles outside the robot's limits (the physics would tear the joint apart).

    Raises:
        EnvConfigError: naming the first such joint, its value and its range in degrees.
    """
    lo, hi = model.ranges_deg[:, 0], model.ranges_deg[:, 1]
    bad = np.flatnonzero((angles_deg < lo - 1e-9) | (angles_deg > hi + 1e-9))
    if len(bad):
        i = int(bad[0])
        raise EnvConfigError(
            f"{what}: {model.effector_names[i]} ({model.perceptor_names[i]}) = "
            f"{angles_deg[i]:g}° is outside its range [{lo[i]:g}, {hi[i]:g}]° for "
            f"{model.label}"
        )


def resolve_angles(
    model: NaoModel, angles: Mapping[str, float] | None, what: str, default: float = 0.0
) -> np.ndarray:
    """Per-joint values by name → canonical-order array (missing joints get ``default``).

    Names of joints this robot type lacks (the toes) are ignored only for the paper's pose
    tables; any other unknown name raises :class:`EnvConfigError`.
    """
    out = np.full(len(model.joints), float(default))
    if angles is None:
        return out
    if not isinstance(angles, Mapping):
        raise EnvConfigError(f"{what} must map joint names to degrees, got {type(angles).__name__}")
    idx = model.joint_index
    for n, v in angles.items():
        if n not in idx:
            raise EnvConfigError(
                f"unknown joint {n!r} in {what} for {model.label}; valid "
                f"effector names: {', '.join(model.effector_names)}"
            )
        if not is_number(v):
            raise EnvConfigError(f"{what}[{n!r}] must be a number of degrees, got {v!r}")
        v = float(v)
        if not math.isfinite(v):
            raise EnvConfigError(f"{what}[{n!r}] must be finite, got {v}")
        out[idx[n]] = v
    return out

"""Compatibility with the RobocupGym paper's code (Beukman et al., 2024).

Thin aliases so the paper's listings run unchanged on top of the real API
(:class:`robocup_gym.envs.BaseEnv`):

* ``from robocup_gym.rl.envs.base_env import BaseEnv`` → :class:`PaperBaseEnv`: the paper's
  constructor signature (``env_config, vectorise_index, wait_steps, agent_type, …``; process and
  port arguments are accepted and ignored) and the attributes its tasks read:
  ``self.python_agent_conn.player.real_ball_pos``, ``.ball_velocity``, ``.is_fallen``, …,
  ``self.env_config.ball_start_pos``, ``self.latest_ball_pos``, ``self.has_completed``,
  ``self.step_counter``, ``self.div_reward_by``.
* ``from robocup_gym.envs.tasks.env_simple_kick import EnvSimpleKick`` →
  :class:`~robocup_gym.envs.tasks.env_simple_kick.EnvSimpleKick` (= :class:`SimpleKick`).
* ``robocup_gym.rl.envs.tasks.benchmark.velocity_kick.KickVelocityReward`` (= :class:`VelocityKick`
  with the paper's ``coefficients`` / ``square_y`` / ``penalise_y_vel_too`` arguments).

Differences from the paper's classes (all deliberate): the simulator is the embedded world (or
any backend), resets are instant (no PID loop), ``player.real_ball_pos`` is the exact ball
position every cycle (the paper's came from vision every 3rd cycle), and ``div_reward_by`` divides
the reward once.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from robocup_gym.envs.base_env import BaseEnv
from robocup_gym.envs.config import EnvConfig, EnvConfigError
from robocup_gym.envs.observations import heading_frame

__all__ = ["PaperBaseEnv", "PaperConnection", "PaperEnvMixin", "PaperPlayer"]

# the paper's Player attribute -> perceptor name
_PLAYER_JOINTS = {
    "neckYaw": "hj1",
    "neckPitch": "hj2",
    "leftShoulderPitch": "laj1",
    "leftShoulderYaw": "laj2",
    "leftArmRoll": "laj3",
    "leftArmYaw": "laj4",
    "leftHipYawPitch": "llj1",
    "leftHipRoll": "llj2",
    "leftHipPitch": "llj3",
    "leftKneePitch": "llj4",
    "leftFootPitch": "llj5",
    "leftFootRoll": "llj6",
    "rightHipYawPitch": "rlj1",
    "rightHipRoll": "rlj2",
    "rightHipPitch": "rlj3",
    "rightKneePitch": "rlj4",
    "rightFootPitch": "rlj5",
    "rightFootRoll": "rlj6",
    "rightShoulderPitch": "raj1",
    "rightShoulderYaw": "raj2",
    "rightArmRoll": "raj3",
    "rightArmYaw": "raj4",
    "leftToePitch": "llj7",
    "rightToePitch": "rlj7",
}


class PaperPlayer:
    """The paper's ``Player``: the robot's latest state, read from the environment's current
    perception. Units as in the paper: joint angles in degrees, gyro in **rad/s**, accelerometer in
    m/s², positions in m (world frame = the left team's frame)."""

    def __init__(self, env: BaseEnv) -> None:
        self._env = env

    def __getattr__(self, name: str) -> Any:
        perceptor = _PLAYER_JOINTS.get(name)
        if perceptor is not None:
            p = self._env.perception
            if p is None or perceptor not in p.joint_names:
                return 0.0
            return p.joint(perceptor)
        raise AttributeError(
            f"the compatibility Player has no attribute {name!r}; see robocup_gym.envs.compat"
        )

    @property
    def real_ball_pos(self) -> np.ndarray:
        """Ball centre (x, y, z), m (exact)."""
        return np.array(self._env.ball_pos)

    @property
    def ball_velocity(self) -> np.ndarray:
        """Ball velocity (x, y, z), m/s (exact)."""
        return np.array(self._env.ball_vel)

    @property
    def ball_speed(self) -> float:
        return float(np.linalg.norm(self._env.ball_vel))

    @property
    def ball_acceleration(self) -> np.ndarray:
        """Not tracked by the compatibility layer: always zeros."""
        return np.zeros(3)

    @property
    def player_pos(self) -> np.ndarray:
        """Torso centre (x, y, z), m (the paper used the head position from ``mypos``)."""
        return np.array(self._env.torso_pos)

    @property
    def my_orientation(self) -> float:
        """Heading of the robot, radians (0 = facing +x)."""
        c, s = heading_frame(self._env.ground_truth.torso_quat)
        return math.atan2(s, c)

    @property
    def is_fallen(self) -> bool:
        return bool(self._env.fallen)

    @property
    def acc(self) -> np.ndarray:
        return np.array(self._env.perception.accel)

    @property
    def gyro(self) -> np.ndarray:
        """rad/s (the paper converted GYR's deg/s)."""
        return np.radians(self._env.perception.gyro)

    def _frp(self, name: str) -> np.ndarray:
        fr = self._env.perception.force_sensors.get(name)
        if fr is None:
            return np.zeros((2, 3))
        return np.stack([fr.point, fr.force])

    @property
    def lf(self) -> np.ndarray:
        """Left foot ``[[cx, cy, cz], [fx, fy, fz]]``."""
        return self._frp("lf")

    @property
    def rf(self) -> np.ndarray:
        return self._frp("rf")

    @property
    def lf1(self) -> np.ndarray:
        return self._frp("lf1")

    @property
    def rf1(self) -> np.ndarray:
        return self._frp("rf1")

    @property
    def time(self) -> float:
        return float(self._env.perception.time)

    @property
    def steps(self) -> int:
        return int(self._env.episode_step)

    @property
    def joint_vector(self) -> np.ndarray:
        """All joint angles, degrees, canonical order."""
        return np.array(self._env.joint_angles_deg)


class PaperConnection:
    """The paper's ``DirectServerConnection`` as far as tasks use it: ``.player``."""

    def __init__(self, env: BaseEnv) -> None:
        self.player = PaperPlayer(env)
        self.env_config = env.config


class PaperEnvMixin:
    """Gives an environment class the paper's constructor and attributes (see module docs).

    Args (the paper's ``BaseEnv`` signature):
        env_config: An :class:`EnvConfig` (``None`` = the class default).
        vectorise_index: Ignored (the paper used it to pick server ports).
        wait_steps: Cycles to run after the episode before the final reward (``None`` = the
            class default: 0 for ``BaseEnv``, 200 for ``EnvSimpleKick``, 20 for
            ``KickVelocityReward``).
        sleep_time_after_proc_starts, wait_steps_after_pid, make_joints_zero_after_start, date:
            Ignored (no processes; resets are instant).
        agent_type: Robot type 0–4.
        init_target_distance: Kick target distance (m) for the ``kick_target`` observation.
        logger: Object with ``.log(dict)``; gets ball position/velocity at every episode end.
        make_action_scale_1: Must be True (actions are always in [-1, 1]).
        div_reward_by: Rewards are divided by this.
        **kwargs: Passed on (``backend=``, ``render_mode=``, or any config field).
    """

    def __init__(
        self,
        env_config: EnvConfig | None = None,
        vectorise_index: int = 0,
        wait_steps: int | None = None,
        sleep_time_after_proc_starts: float = 0,
        agent_type: int | None = None,
        init_target_distance: float | None = None,
        logger: Any = None,
        make_action_scale_1: bool = True,
        make_joints_zero_after_start: bool = True,
        wait_steps_after_pid: int = 0,
        div_reward_by: float = 1.0,
        date: str | None = None,
        **kwargs: Any,
    ) -> None:
        if not make_action_scale_1:
            raise EnvConfigError(
                "make_action_scale_1=False is not supported: actions are always in [-1, 1] and "
                "scaled to each joint's range"
            )
        if wait_steps is not None:
            kwargs["wait_steps"] = int(wait_steps)
        if agent_type is not None:
            kwargs["robot_type"] = int(agent_type)
        if init_target_distance is not None:
            kwargs["kick_target"] = (float(init_target_distance), 0.0)
        super().__init__(env_config, **kwargs)  # type: ignore[call-arg]
        self.vectorise_index = vectorise_index
        self.logger = logger
        self.div_reward_by = float(div_reward_by)
        self.reset_count = 0
        self.python_agent_conn = PaperConnection(self)  # type: ignore[arg-type]

    # ---- the paper's attribute names
    @property
    def env_config(self) -> EnvConfig:
        """The paper's name for :attr:`BaseEnv.config`."""
        return self.config  # type: ignore[attr-defined]

    @property
    def latest_ball_pos(self) -> tuple[float, float, float]:
        """Where the ball was spawned this episode (after spawn noise), m."""
        return tuple(float(v) for v in self.ball_spawn_pos)  # type: ignore[attr-defined]

    @property
    def step_counter(self) -> int:
        return self.episode_step  # type: ignore[attr-defined]

    @property
    def wait_steps_after_done(self) -> int:
        return int(self.config.wait_steps)  # type: ignore[attr-defined]

    @property
    def target(self) -> dict[str, float]:
        d, a = self.kick_target  # type: ignore[attr-defined]
        return {"desired_distance": float(d), "desired_angle": float(a)}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        out = super().reset(seed=seed, options=options)  # type: ignore[misc]
        self.reset_count += 1
        return out

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = super().step(action)  # type: ignore[misc]
        if self.div_reward_by != 1.0:
            reward = reward / self.div_reward_by
        if (terminated or truncated) and self.logger is not None and self.vectorise_index <= 1:
            self.logger.log(
                {
                    "ballpos": dict(zip("xyz", map(float, info.get("ball_pos", ())), strict=False)),
                    "ballvel": dict(zip("xyz", map(float, info.get("ball_vel", ())), strict=False)),
                }
            )
        return obs, reward, terminated, truncated, info


class PaperBaseEnv(PaperEnvMixin, BaseEnv):
    """The paper's ``BaseEnv`` (``robocup_gym.rl.envs.base_env.BaseEnv``): subclass it and
    override ``_get_reward(self, action)``; the default reward is 0.

    Example (the paper's listing, unchanged)::

        from robocup_gym.rl.envs.base_env import BaseEnv
        import numpy as np

        class EnvSimpleKick(BaseEnv):
            def _get_reward(self, action: np.ndarray) -> float:
                if self.has_completed:
                    cur = np.array(self.python_agent_conn.player.real_ball_pos)
                    return np.linalg.norm(cur - np.array(self.env_config.ball_start_pos))
                return 0
    """

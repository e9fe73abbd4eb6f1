"""A helping hand for learning to stand: an upward push on the torso that fades out.

A robot lying on the ground has to find a long, coordinated motion (legs under the body, weight
forward, rise) before standing pays anything, and PPO tends to settle for the nearest comfortable
pose instead (a GetUp policy learnt to sit up and stay sitting). HoST (Huang et al., *Learning
Humanoid Standing-up Control across Diverse Postures*, 2025) lifts the robot by its base early in
training with a vertical force that a curriculum lowers to zero: the policy meets standing states
early, learns their value, and then has to produce the lift itself. :class:`TorsoAssist` does this
on the in-process engines, on any task, with a linear schedule.

The push is a training aid only: SimSpark has no such force. Evaluations
(``robocup-gym eval``, the training run's periodic evaluations, the benchmarks) never wrap their
environment, so what they measure is the robot alone. ``robocup-gym train --assist-force 0.8
--assist-steps 2000000`` turns it on for a run (``TrainConfig.assist_force``/``assist_steps``).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym

from robocup_gym.envs.observations import up_z
from robocup_gym.sim.physics import GRAVITY

__all__ = ["SCHEDULES", "TorsoAssist", "assist_share"]

SCHEDULES = ("linear", "success")
"""How the push fades: ``linear`` over a number of steps; ``success`` by the robot's own
successes (the task's ``info["success"]``)."""
SUCCESS_STEP_DOWN = 0.02
"""``success`` schedule: each successful episode lowers the push by this share of its start
(50 successes in a row take it to 0)."""
FAILURE_STEP_UP = 0.005
"""…and each failed one raises it by this share, up to its start (four failures undo one
success)."""


def assist_share(share: float, decay_steps: int, step: int) -> float:
    """The push at environment step ``step``, as a share of the robot's weight: ``share`` at
    step 0, falling linearly to 0 at ``decay_steps``."""
    if decay_steps <= 0:
        return 0.0
    return share * max(0.0, 1.0 - step / decay_steps)


class TorsoAssist(gym.Wrapper):
    """Push the robot's torso upward with a force that fades out as training goes on.

    With the ``linear`` schedule, before every step the torso gets ``share × (1 − t /
    decay_steps) × m g`` newtons straight up
    (world z, at its centre of mass), where ``t`` counts this environment's steps over all its
    episodes and ``m g`` is the robot's weight (45.2 N for every Nao type; a league robot's from
    its model). From ``decay_steps`` on the push is 0 and the environment is the task itself.
    ``info["assist_force_n"]`` has the push of each step.

    Args:
        env: A RobocupGym environment on an in-process engine (``ode``, ``mujoco``, or
            ``rcsssmj`` for a league robot).
        share: The push at step 0 as a share of the robot's weight, 0–2 (from 1 on the robot
            hangs from its torso and floats up; 0.5 leaves a stiff lying robot on the ground).
        decay_steps: Steps of *this* environment over which the push fades (a training run
            with ``n_envs`` environments gives each ``assist_steps / n_envs``).
        start_step: Steps already taken (a resumed run continues the ``linear`` schedule).
        max_tilt_deg: Push only while the torso's up axis is within this angle of the vertical
            (180: always). With 60, say, the robot has to sit or kneel up by itself before the
            hand helps, as in HoST, and cannot learn to be lifted off its back.
        schedule: ``"linear"``: the push falls from ``share`` to 0 over ``decay_steps``.
            ``"success"`` (``decay_steps`` unused): it falls by 2 % of ``share`` with each
            successful episode (the task's ``info["success"]``, e.g. GetUp's) and rises by 0.5 %
            with each failed one, up to ``share``: the robot gets as much help as it still
            needs (HoST lowers its force when the robot reaches the target height).

    Raises:
        ValueError: ``share`` is outside 0–2 or not finite, ``decay_steps``/``start_step`` is
            negative, or ``max_tilt_deg`` is outside (0, 180].
        BackendNotAvailableError: the environment's backend cannot push (a real server).
    """

    def __init__(
        self,
        env: gym.Env,
        share: float,
        decay_steps: int,
        start_step: int = 0,
        max_tilt_deg: float = 180.0,
        schedule: str = "linear",
    ) -> None:
        super().__init__(env)
        if schedule not in SCHEDULES:
            raise ValueError(
                f"assist schedule must be one of {', '.join(SCHEDULES)}, got {schedule!r}"
            )
        if not (0.0 <= share <= 2.0):  # also refuses NaN
            raise ValueError(f"assist share must be within 0 and 2 (of the weight), got {share!r}")
        if not (0.0 < max_tilt_deg <= 180.0):
            raise ValueError(f"max_tilt_deg must be within 0 and 180, got {max_tilt_deg!r}")
        if decay_steps < 0 or start_step < 0:
            raise ValueError(
                f"decay_steps and start_step must be >= 0, got {decay_steps} and {start_step}"
            )
        self.share = float(share)
        self.decay_steps = int(decay_steps)
        self.steps = int(start_step)
        self.max_tilt_deg = float(max_tilt_deg)
        self.schedule = schedule
        self.level = self.share
        """The push as a share of the weight now (the ``success`` schedule's state)."""
        self._min_up_z = math.cos(math.radians(max_tilt_deg))
        base = env.unwrapped
        self._base = base
        self._backend = base.backend
        self._backend.set_torso_force((0.0, 0.0, 0.0))  # refuses a backend that cannot push
        self.weight_n = float(base.robot_model.total_mass) * GRAVITY
        """The robot's weight, N."""
        self._pushing = False

    def force_n(self) -> float:
        """The push of the next step, N (0 while the torso is tilted beyond ``max_tilt_deg``)."""
        if self.schedule == "success":
            f = self.level * self.weight_n
        else:
            f = assist_share(self.share, self.decay_steps, self.steps) * self.weight_n
        if f > 0.0 and self.max_tilt_deg < 180.0:
            gt = self._base.ground_truth
            if gt is not None and up_z(gt.torso_quat) < self._min_up_z:
                return 0.0
        return f

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        f = self.force_n()
        if f > 0.0 or self._pushing:
            self._backend.set_torso_force((0.0, 0.0, f))
            self._pushing = f > 0.0
        self.steps += 1
        obs, reward, terminated, truncated, info = self.env.step(action)
        info["assist_force_n"] = f
        if self.schedule == "success" and (terminated or truncated):
            if info.get("success"):
                self.level = max(0.0, self.level - SUCCESS_STEP_DOWN * self.share)
            else:
                self.level = min(self.share, self.level + FAILURE_STEP_UP * self.share)
        info["assist_share"] = self.level if self.schedule == "success" else f / self.weight_n
        return obs, reward, terminated, truncated, info

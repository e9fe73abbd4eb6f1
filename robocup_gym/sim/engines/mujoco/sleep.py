"""ODE's auto-disable as SimSpark keeps it, on MuJoCo: a robot placed at rest sleeps (is held
where it is, not integrated) until a non-zero motor target or a contact with a moving body
wakes it (reference §7.1, §8.3).

:class:`AutoDisable` is a part of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

from __future__ import annotations

from robocup_gym.sim.engines.mujoco.motors import _any

AUTO_DISABLE_SPEED = 0.01
"""ODE's default auto-disable thresholds (linear m/s, angular rad/s) that SimSpark keeps: a body
slower than both is resting (reference §7.1)."""


class AutoDisable:
    """The sleeping robots of :class:`~robocup_gym.sim.engines.mujoco.world.World`."""

    def _update_sleepers(self) -> None:
        self._sleepers = [r for r in self.robots if r.asleep]

    def _wake_touched(self) -> None:
        """Wake every sleeping robot one of whose parts touches a moving body (the ball or
        another robot) in this step's contacts: in ODE the contact joint joins it to that body's
        island, which is enabled as a whole."""
        d = self._data  # inside step(): the contacts are this step's
        if d.ncon == 0:
            return
        pairs = d.contact.geom[: d.ncon].tolist()
        static = self._static_geoms
        woke = False
        for r in self._sleepers:
            own = r.robot_geoms
            for g1, g2 in pairs:
                if (g1 in own and g2 not in own and g2 not in static) or (
                    g2 in own and g1 not in own and g1 not in static
                ):
                    r.asleep = False
                    woke = True
                    break
        if woke:
            self._update_sleepers()

    def _hold_sleepers(self) -> None:
        """Put every sleeping robot back into its held pose with zero velocity (a disabled ODE
        body is not integrated)."""
        d = self._data  # inside step(): only the state is written
        for r in self._sleepers:
            a = r.qpos_root
            d.qpos[a : a + 7] = r.sleep_qpos[:7]
            d.qpos[r.qpos_joints] = r.sleep_qpos[7:]
            d.qvel[r.qvel_root : r.qvel_root + 6] = 0.0
            d.qvel[r.qvel_joints] = 0.0

    def _wake_commanded(self) -> None:
        """A non-zero motor target wakes a sleeping robot for this very step (reference §8.3)."""
        for r in self._sleepers:
            if _any(r.targets != 0.0):
                r.asleep = False
        self._update_sleepers()

"""The Nao's geometry read off the shared kinematics worlds (``robocup_gym.sim.kinematics``)."""

from __future__ import annotations

import threading

import numpy as np

from robocup_gym.robot.nao import nao_model
from robocup_gym.sim.kinematics import resting_height_and_feet


def test_threads_that_place_the_same_robot_type_read_their_own_pose():
    """Two teams of a match play in threads of one process and read every player's feet off
    the same world per Nao type: each call gets the geometry of its own joint angles."""
    rng = np.random.default_rng(0)
    n = len(nao_model(0).joints)
    poses = [rng.normal(0.0, 25.0, n) for _ in range(4)]
    want = [resting_height_and_feet(0, q) for q in poses]
    wrong: list[int] = []

    def reader(k: int) -> None:
        for _ in range(400):
            height, feet = resting_height_and_feet(0, poses[k])
            if height != want[k][0] or not np.array_equal(feet, want[k][1]):
                wrong.append(k)

    threads = [threading.Thread(target=reader, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not wrong, f"{len(wrong)} of 1600 reads met another thread's pose"

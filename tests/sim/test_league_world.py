"""The league's current simulator (RCSSServerMJ, ``rcsssmj``): its robots as data, the in-process
world, and the proof that it is the real server's: the same commands give the same perception
bytes as a real ``rcssservermj`` process, every cycle. Skipped (with the reason) where the
optional ``rcsssmj`` is not installed (``pip install robocup-gym[mj]``; CI installs it)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

rcsssmj = pytest.importorskip("rcsssmj", reason="the optional rcsssmj package is not installed")

from robocup_gym.backends.rcssservermj import RcssServerMJProcess  # noqa: E402
from robocup_gym.robot.league import league_robot, league_robot_names  # noqa: E402
from robocup_gym.sim.engines.rcsssmj import LeagueWorld, PDCommand  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import rcssservermj_match  # noqa: E402


def test_the_league_robots_come_from_rcsssmjs_model_files():
    assert {"T1", "K1"} <= set(league_robot_names())
    t1, k1 = league_robot("T1"), league_robot("K1")
    assert len(t1.joints) == 23 and len(k1.joints) == 22  # as rcsssmj's models say
    assert t1.model_file.is_file() and t1.model_file.parent.name == "T1"
    knee = t1.joint("Left_Knee_Pitch")
    assert knee.range_deg[0] == pytest.approx(0.0) and 100 < knee.range_deg[1] < 180
    assert all(j.force_range[0] < 0 < j.force_range[1] for j in t1.joints)
    # what the environments read: HJ names from the joints' position sensors, the joint index
    # by every name, the standing geometry from MuJoCo's own distance to a ground plane
    assert t1.perceptor_names[:2] == ("q_hj1", "q_hj2") and len(set(t1.perceptor_names)) == 23
    assert t1.joint_index["lle4"] == t1.joint_index["q_llj4"] == t1.joint_index["Left_Knee_Pitch"]
    assert t1.ranges_deg.shape == (23, 2) and t1.torque_limits.shape == (23, 2)
    assert 0.6 < t1.standing_torso_height < 0.75 and 0.45 < k1.standing_torso_height < 0.6
    assert t1.foot_bodies == ("left_foot_link", "right_foot_link")
    assert t1.right_foot_offset[1] < -0.05 < 0.05 < -k1.right_foot_offset[1] + 0.1
    assert t1.ball_radius == pytest.approx(0.11)
    with pytest.raises(ValueError, match=r"unknown league robot 'Nao'.*T1"):
        league_robot("Nao")
    with pytest.raises(KeyError, match="no joint 'elbow'"):
        t1.joint("elbow")


def test_without_rcsssmj_the_error_says_how_to_install_it(monkeypatch):
    from robocup_gym.robot.league import RcsssmjUnavailableError

    monkeypatch.setitem(sys.modules, "rcsssmj.resources", None)
    with pytest.raises(RcsssmjUnavailableError, match=r"pip install 'robocup-gym\[mj\]'"):
        league_robot_names()


_JOIN_PROBE = """
import hashlib, sys
import numpy as np
from robocup_gym.sim.engines.rcsssmj import LeagueWorld
junk = [bytearray(np.random.default_rng().bytes(4096 + 997 * k)) for k in range(200)]
del junk[::2]  # freed garbage of many sizes for the next allocations
w = LeagueWorld([("K1", "A", 1), ("T1", "B", 1)], idle_cycles=3)
ctrl = w.sim.mj_data.ctrl
assert np.isfinite(ctrl).all() and np.abs(ctrl).max() < 1e3, ctrl
p = w.cycle()
print(hashlib.sha256(ctrl.tobytes() + b"".join(p)).hexdigest())
"""


@pytest.mark.skipif(
    not __import__("robocup_gym.sim.engines.rcsssmj.join", fromlist=["x"]).zero_fill_available(),
    reason="zero-filled joins need glibc's mallopt (Linux)",
)
def test_a_join_is_the_same_whatever_the_heap_held():
    """MuJoCo's recompile reads a joining robot's first controls partly from uninitialised
    memory; with the join's allocations zero-filled, processes whose heaps hold different garbage
    (glibc's perturbation bytes 1 and 170 everywhere else, a long environment) start the same."""
    import os
    import subprocess

    digests = set()
    for extra in ({"MALLOC_PERTURB_": "1"}, {"MALLOC_PERTURB_": "170"}, {"PAD": "x" * 5000}):
        env = {**os.environ, **extra}
        out = subprocess.run(
            [sys.executable, "-c", _JOIN_PROBE], env=env, capture_output=True, text=True
        )
        assert out.returncode == 0, out.stderr[-2000:]
        digests.add(out.stdout.split()[-1])
    assert len(digests) == 1, digests


@pytest.mark.parametrize(("robot", "cycles"), [("T1", 500), ("K1", 200)])
def test_the_in_process_world_is_the_real_server(robot, cycles):
    """500 cycles of random PD targets on every joint of a T1 (200 for a K1): every perception
    the real rcssservermj sends is byte for byte the in-process world's."""
    r = rcssservermj_match.run(cycles=cycles, robot=robot, seed=1)
    assert r["identical_perceptions"] == cycles, r
    assert r["max_joint_deg_diff"] == 0.0 and r["max_torso_m_diff"] == 0.0, r
    assert r["max_ball_m_diff"] == 0.0 and r["ball_seen_in"] > 0, r


def test_commands_act_and_bad_ones_are_named():
    w = LeagueWorld([("T1", "A", 1)])
    names = w.effector_names(0)
    assert names[:2] == ("he1", "he2") and len(names) == 23
    w.cycle()
    q0 = w.joint_angles(0)[0]
    for _ in range(30):  # (sent every cycle, as agents do)
        w.command(0, {"he1": PDCommand(30.0, 0.0, 20.0, 1.0)})
        w.cycle()
    assert math.degrees(w.joint_angles(0)[0] - q0) > 20.0  # the head turned towards 30°
    pos, quat = w.torso_pose(0)
    assert np.isfinite(pos).all() and abs(np.linalg.norm(quat) - 1.0) < 1e-9
    assert np.isfinite(w.ball_position()).all() and w.time > 0.5
    with pytest.raises(KeyError, match=r"unknown joint 'knee'.*he1"):
        w.command(0, {"knee": PDCommand(0.0)})
    with pytest.raises(ValueError, match="q_deg must be finite"):
        PDCommand(math.nan)
    with pytest.raises(ValueError, match="idle_cycles must be >= 1"):
        LeagueWorld([("T1", "A", 1)], idle_cycles=0)
    with pytest.raises(ValueError, match="refused"):
        LeagueWorld([("T1", "A", 1), ("T1", "A", 1)])  # the same number twice


def test_the_server_process_is_ended_and_its_folder_removed(process_ends):
    server = RcssServerMJProcess()
    pid, folder = server.pid, server.folder
    assert server.running and Path(folder).is_dir()
    server.close()
    if not process_ends(pid):
        pytest.fail("the rcssservermj process is still running")
    assert not Path(folder).exists()

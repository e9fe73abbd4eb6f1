"""The compiled per-cycle work (robocup_gym/sim/engines/mujoco/cstep.c) against the NumPy path it
replaces.

Both must give bit-equal physics on every rule of the world's step: commands (full and partial,
several due at once, dead time 0 and 1), creep compensation, joints at and pulled away from their
stops, the ball's bounce switch, drag, sleeping robots, several robots of every type, substeps.
Only the accelerometer may differ in its last bits (NumPy's dot sums in another order).
The build and its fallback are tested with a fresh cache and a compiler that does not exist.
"""

import numpy as np
import pytest

from robocup_gym.sim import compiled
from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError, World
from robocup_gym.sim.fidelity import load_data, scripted_kick
from robocup_gym.sim.physics import PhysicsConfig

needs_compiler = pytest.mark.skipif(
    not compiled.available(), reason="no C compiler here (apt-get install gcc, or set CC)"
)


def _trajectory(make_world, drive, cycles):
    """Per cycle: (state the physics depends on, accelerometers) of a run that calls
    ``drive(world, cycle)`` every cycle."""
    w = make_world()
    states, accels = [], []
    for c in range(cycles):
        drive(w, c)
        states.append(
            np.concatenate(
                [
                    w.data.qpos,
                    w.data.qvel,
                    w._targets,
                    w._q_ref,
                    w._motor_lost,
                    w.model.dof_frictionloss,
                    w.data.qfrc_applied,
                    w.model.pair_solref.ravel(),
                    [w._motors_relaxed, w._ball_bouncy],
                ]
            )
        )
        accels.append(w._accel.copy())
    return w, np.array(states), np.array(accels)


def _assert_same(make_world, make_drive, cycles=300):
    """Run ``make_drive()``'s driver on the NumPy and the compiled world (``make_world(flag)``)
    and assert bit-equal physics; returns the compiled world and its states."""
    wn, sn, an = _trajectory(lambda: make_world(False), make_drive(), cycles)
    wc, sc, ac = _trajectory(lambda: make_world(True), make_drive(), cycles)
    assert (wn.stepper, wc.stepper) == ("numpy", "compiled")
    differ = np.argwhere(sn != sc)
    assert len(differ) == 0, f"first difference at cycle {differ[0][0]}, entry {differ[0][1]}"
    np.testing.assert_allclose(ac, an, rtol=0, atol=1e-12)
    return wc, sc


def _flail(seed, partial_every=7, replace_every=60):
    rng = np.random.default_rng(seed)

    def drive(w, c):
        cmds = {}
        for i, r in enumerate(w.robots):
            vmax = r.max_speeds
            cmds[i] = rng.uniform(-1.5, 1.5, len(vmax)) * vmax  # over-speed: clipped
        if c % partial_every == 3:
            cmds[0] = {"rle3": 3.0, "lae1": -9.0, "he1": 0.0}
        w.step(cmds)
        if c % replace_every == replace_every - 1:
            w.place_robot(0, -1.0, 0.0, joint_angles_deg=np.zeros(len(w.robots[0].model.joints)))

    return drive


def _place_all(w):
    for i, r in enumerate(w.robots):
        w.place_robot(i, -1.0 - 0.7 * i, 0.5 * i, joint_angles_deg=np.zeros(len(r.model.joints)))
    w.place_ball((-0.8, -0.055, 0.5), vel=(0.3, 0.0, -2.0))  # falls and bounces


@needs_compiler
@pytest.mark.parametrize("types", [(0,), (4, 1, 2, 3)])
def test_random_flailing_is_bit_equal(types):
    """Random over-speed commands on every joint (joints hit their stops and are pulled away
    again, motors saturate), partial commands, re-placements, a bouncing ball, several robots
    of every type (type 4's toes make dof order differ from effector order)."""

    def make(flag):
        w = World(list(types), compiled=flag, seed=1)
        _place_all(w)
        return w

    w, states = _assert_same(make, lambda: _flail(3), cycles=400)
    # the run exercised what it claims to: stops pulled away from (motor rows removed) and the
    # bouncy ball contact
    assert w.model.dof_frictionloss.min() >= 0.0
    relaxed = states[:, -2]
    assert relaxed.any() and not relaxed.all()


@needs_compiler
def test_kick_d_is_bit_equal_and_moves_the_ball():
    """The scripted kick of the fixtures (dead time, partial commands, ball contact)."""
    kick = load_data("kick_D.json")
    numpy_kick, compiled_kick = (
        scripted_kick(kick, world=World([0], compiled=flag)) for flag in (False, True)
    )
    assert np.array_equal(numpy_kick.ball_final, compiled_kick.ball_final)
    assert numpy_kick.first_move_cycle == compiled_kick.first_move_cycle
    assert compiled_kick.ball_displacement_m > 1.5


@needs_compiler
@pytest.mark.parametrize("dead_time", [0, 2])
def test_dead_time_and_queued_commands_are_bit_equal(dead_time):
    """Several commands due in one cycle (two queued per step): the later wins where it has a
    value, as when the NumPy path realises them one after the other."""

    def make(flag):
        w = World([0], compiled=flag, dead_time_cycles=dead_time)
        _place_all(w)
        return w

    def make_drive():
        rng = np.random.default_rng(5)

        def drive(w, c):
            vmax = w.robots[0].max_speeds
            w.command(0, rng.uniform(-1, 1, len(vmax)) * vmax)
            w.command(0, {"lle4": float(rng.uniform(-3, 3)), "rae2": float(rng.uniform(-3, 3))})
            w.step()

        return drive

    _assert_same(make, make_drive, cycles=200)


@needs_compiler
def test_substeps_and_sleeping_robots_are_bit_equal():
    """Two MuJoCo steps per cycle; a robot placed asleep that the ball wakes, one that a
    command wakes."""

    def make(flag):
        w = World([0, 0], compiled=flag, physics=PhysicsConfig(timestep=0.01))
        w.place_robot(0, -1.0, 0.0, asleep=True)
        w.place_robot(1, 1.0, 0.0, asleep=True)
        w.place_ball((-0.6, 0.0), vel=(-2.0, 0.0, 0.0))  # rolls into robot 0
        return w

    def drive(w, c):
        if c == 30:
            w.step({1: {"lae1": 2.0}})
        else:
            w.step()

    w, _ = _assert_same(make, lambda: drive, cycles=120)
    assert not w.robots[0].asleep and not w.robots[1].asleep


@needs_compiler
def test_divergence_is_reported_and_recoverable():
    """A NaN state is reported by the compiled step too, and the world works after reset."""
    w = World([0], compiled=True)
    w.step()
    w.data.qvel[0] = np.nan
    with pytest.raises(SimulationDivergedError, match="diverged"):
        w.step()
    w.reset()
    w.step()
    assert np.isfinite(w.data.qpos).all()


def test_numpy_path_on_request(monkeypatch):
    """``compiled=False`` and ``ROBOCUP_GYM_COMPILED=0`` give the NumPy path."""
    assert World([0], compiled=False).stepper == "numpy"
    monkeypatch.setenv("ROBOCUP_GYM_COMPILED", "0")
    assert World([0]).stepper == "numpy"
    monkeypatch.setenv("ROBOCUP_GYM_COMPILED", "maybe")
    with pytest.raises(ValueError, match="ROBOCUP_GYM_COMPILED"):
        World([0])


@pytest.fixture
def no_compiler(monkeypatch, tmp_path):
    """A fresh cache and a compiler that does not exist (the loaded library is forgotten)."""
    monkeypatch.setenv("ROBOCUP_GYM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    monkeypatch.delenv("ROBOCUP_GYM_COMPILED", raising=False)
    compiled.forget()
    yield tmp_path
    compiled.forget()


def test_without_a_compiler_the_world_falls_back(no_compiler):
    """No compiler: the world says why and runs the NumPy path; ``compiled=True`` (or
    ``ROBOCUP_GYM_COMPILED=1``) is a clear error naming the compiler."""
    w = World([0])
    assert w.stepper == "numpy"
    assert "no-such-cc" in w.compiled_unavailable and "gcc" in w.compiled_unavailable
    w.step({0: np.ones(22)})
    with pytest.raises(compiled.CompiledStepUnavailableError, match="no-such-cc"):
        World([0], compiled=True)
    assert not list((no_compiler / "cache").glob("*.so"))  # no half-written library left


def test_an_unwritable_cache_falls_back(no_compiler, monkeypatch):
    """A cache folder that cannot be made: the world runs the NumPy path and says why."""
    blocker = no_compiler / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("ROBOCUP_GYM_CACHE", str(blocker / "cache"))
    w = World([0])
    assert w.stepper == "numpy" and "ROBOCUP_GYM_CACHE" in w.compiled_unavailable


def test_a_failure_is_remembered(no_compiler, monkeypatch):
    """A process that could not build the step does not try again for every world (a machine
    without a compiler would otherwise pay for the attempt at each one); ``forget`` retries."""
    calls = []
    real_build = compiled.build

    def counting_build(*args, **kwargs):
        calls.append(1)
        return real_build(*args, **kwargs)

    monkeypatch.setattr(compiled, "build", counting_build)
    assert [World([0]).stepper for _ in range(3)] == ["numpy"] * 3
    assert len(calls) == 1
    compiled.forget()
    assert not compiled.available() and len(calls) == 2


def test_a_failed_compilation_says_why(no_compiler, monkeypatch):
    """A compiler that fails: the error carries its output."""
    fake = no_compiler / "failing-cc"
    fake.write_text("#!/bin/sh\necho 'cstep.c:1: error: something broke' >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("CC", str(fake))
    with pytest.raises(compiled.CompiledStepUnavailableError, match="something broke"):
        compiled.load()


@needs_compiler
def test_build_is_cached_per_mujoco_version(monkeypatch, tmp_path):
    """The library is built once into the cache and reused; its name carries the MuJoCo
    version, so an upgrade builds a new one."""
    monkeypatch.setenv("ROBOCUP_GYM_CACHE", str(tmp_path))
    path = compiled.build()
    assert path.parent == tmp_path and path.exists()
    import mujoco

    assert f"mujoco{mujoco.__version__}" in path.name
    stamp = path.stat().st_mtime_ns
    assert compiled.build() == path and path.stat().st_mtime_ns == stamp

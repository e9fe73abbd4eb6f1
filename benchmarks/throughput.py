"""Throughput of the embedded world and of the Gymnasium environments.

Usage::

    python benchmarks/throughput.py           # ~30 s
    python benchmarks/throughput.py --quick   # a few seconds, for smoke tests

Prints one line per measurement and, as its LAST line, one JSON object:

* ``world_cycles_per_s``: :meth:`World.step` (one robot + ball, random joint velocities on all
  joints, robot re-placed upright every 60 cycles), one core, in-process, with the per-cycle
  work compiled (``stepper``: ``"compiled"``; ``"numpy"`` where no C compiler is found);
* ``world_numpy_cycles_per_s``: the same with the NumPy path (``World(compiled=False)``, the
  reference implementation; bit-equal physics), and ``compiled_speedup``, the ratio;
* ``raw_cycles_per_s``: MuJoCo alone on the same model, timed on exactly the states the world
  stepped through (recorded, then replayed): ``mj_step1``, the motor rows' reference shift (one
  in-place add: the only Python the motor model needs) and ``mj_step2`` per MuJoCo step, nothing
  else — the same workload, so ``world_vs_raw`` is the cost of the world's Python work;
* ``bare_mj_step_cycles_per_s``: plain ``mujoco.mj_step`` from the same states (without the
  shift the motors hold their joints, so the solve differs slightly; for reference);
* ``env_steps_per_s``: ``VelocityKick`` with random actions, counting every simulated cycle (the
  wait steps after each episode included) over the whole time, resets included;
* ``reset_ms``: mean wall time of ``env.reset()`` (no simulated warm-up cycles);
* ``env_steps_per_s_2_workers``: the same with ``gymnasium.vector.AsyncVectorEnv`` and 2 worker
  processes (cycles of both workers per second); ``scaling_2_workers`` is its ratio to
  ``env_steps_per_s``;
* ratios ``world_vs_raw`` and ``env_vs_world``.

The same for SimSpark's physics on ODE (the default engine), where libode is installed:

* ``ode_world_cycles_per_s``: ``OdeWorld.step`` on the workload of ``world_cycles_per_s``;
* ``ode_raw_cycles_per_s``: ODE's own work alone (contact generation and ``dWorldStep``) on the
  same steps, so ``ode_world_vs_raw`` is what the world adds to the engine;
* ``ode_env_steps_per_s`` (and ``ode_env_agent_steps_per_s``): ``VelocityKick(engine="ode")``,
  counted like ``env_steps_per_s``; ``ode_env_vs_world`` its ratio to the world;
* ``ode_vs_mujoco_world``: the ODE world's cycle rate over the MuJoCo world's;
* ``ode_22_robots_cycles_per_s``: 22 robots of mixed types flailing on the full field with the
  ball (a game's physics; 50 cycles/s is real time), one core.

The league's current simulator (RCSSServerMJ), where the optional ``rcsssmj`` is installed, the
real server and the in-process world on the same command sequence in the same run
(``benchmarks/rcssservermj_match.py``):

* ``rcssservermj_cycles_per_s``: a real ``rcssservermj`` in sync mode with one T1 agent sending
  PD commands on all 23 joints each cycle;
* ``t1_world_cycles_per_s``: the in-process world on the same commands, without making the
  perceptions (what a learner that reads the state needs); ``t1_world_perceiving_cycles_per_s``
  making every perception message too;
* ``t1_world_vs_rcssservermj``: the ratio;
* ``t1_mujoco_step_cycles_per_s``: MuJoCo's ``mj_step`` alone on the world's model (four 5 ms
  steps per cycle), the bound of any in-process world on this model;
* ``t1_env_steps_per_s``: ``VelocityKick(robot="T1")`` with random actions, every cycle counted.

The MuJoCo keys above measure ``engine="mujoco"`` explicitly. Timings depend on the machine and
its load; ``loadavg`` is recorded with them.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import platform
import sys
import time
import warnings
from collections.abc import Callable

import mujoco
import numpy as np

from robocup_gym.sim.engines.mujoco.world import SimulationDivergedError, World
from robocup_gym.sim.engines.ode import available as ode_available

EPISODE_CYCLES = 60
"""Cycles between re-placements in the world/raw measurements (≈ one VelocityKick episode:
40 steps + 20 wait cycles)."""

# ----------------------------------------------------------------------------------------------
# Further measurements: every entry is ``name -> function(quick: bool) -> float`` and its result
# is added to the JSON under ``name``.
EXTRA_MEASUREMENTS: dict[str, Callable[[bool], float]] = {}


def _serve_sync_cycles_per_s(engine: str) -> Callable[[bool], float]:
    def measure(quick: bool) -> float:
        """``robocup-gym serve --engine <engine>`` in sync mode, one agent sending all 22 joints
        + (syn) each cycle and parsing every percept (the real server does 1,361 cycles/s here
        with such a client)."""
        from robocup_gym.server.bench import measure_sync_cycles_per_s

        return measure_sync_cycles_per_s(0.5 if quick else 3.0, engine=engine)

    return measure


# the MuJoCo engine's key keeps its name from the time serve ran on MuJoCo only
EXTRA_MEASUREMENTS["serve_sync_cycles_per_s"] = _serve_sync_cycles_per_s("mujoco")
if ode_available():
    EXTRA_MEASUREMENTS["serve_ode_sync_cycles_per_s"] = _serve_sync_cycles_per_s("ode")
# ----------------------------------------------------------------------------------------------


def league_speeds(quick: bool) -> dict:
    """The RCSSServerMJ keys of the module docstring (``{}`` without ``rcsssmj``)."""
    try:
        import rcsssmj  # noqa: F401
    except ImportError:
        return {"league_unavailable": "rcsssmj is not installed (pip install robocup-gym[mj])"}
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import rcssservermj_match

    from robocup_gym.envs import VelocityKick
    from robocup_gym.sim.engines.rcsssmj import LeagueWorld

    cycles = 100 if quick else 1000
    r = rcssservermj_match.run(cycles=cycles, robot="T1", seed=0)
    world = LeagueWorld([("T1", "A", 1)])
    model, data = world.sim.mj_model, world.sim.mj_data
    t0 = time.perf_counter()
    for _ in range(cycles):
        mujoco.mj_step(model, data, 4)
    bound = cycles / (time.perf_counter() - t0)
    env = VelocityKick(robot="T1")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    n, t0 = 0, time.perf_counter()
    while n < cycles:
        _, _, term, trunc, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        n += info["cycles"]
        if term or trunc:
            env.reset()
    env_rate = n / (time.perf_counter() - t0)
    env.close()
    out = {
        "rcssservermj_cycles_per_s": r["server_cycles_per_s"],
        "t1_world_cycles_per_s": r["inprocess_no_perception_cycles_per_s"],
        "t1_world_perceiving_cycles_per_s": r["inprocess_cycles_per_s"],
        "t1_world_vs_rcssservermj": r["speedup_no_perception"],
        "t1_mujoco_step_cycles_per_s": round(bound, 1),
        "t1_env_steps_per_s": round(env_rate, 1),
    }
    print(
        f"T1     {out['t1_world_cycles_per_s']:9.0f} cycles/s in-process, "
        f"{out['rcssservermj_cycles_per_s']:.0f} rcssservermj "
        f"({out['t1_world_vs_rcssservermj']:.2f}×; MuJoCo alone {bound:.0f})",
        file=sys.stderr,
    )
    return out


def _place(world) -> None:
    world.place_robot(0, -1.0, 0.0, joint_angles_deg=np.zeros(len(world.robots[0].model.joints)))
    world.place_ball((-0.8, -0.055))
    world.set_game(play_mode="PlayOn", game_time=0.0)


class WorldRunner:
    """World.step with random joint velocities on all joints; the robot is re-placed upright
    every ``EPISODE_CYCLES`` cycles (not timed)."""

    def __init__(self, seed: int = 0, compiled: bool | None = None) -> None:
        self.world = World([0], seed=seed, compiled=compiled)
        rng = np.random.default_rng(seed)
        vmax = self.world.robots[0].model.max_speeds
        self.commands = rng.uniform(-1.0, 1.0, (4096, len(vmax))) * vmax
        self.k = 0
        self.cycles = self.busy = 0.0
        self.diverged = 0
        _place(self.world)
        self.run(20)  # warm up
        self.cycles = self.busy = 0.0

    def _next(self) -> np.ndarray:
        self.k = (self.k + 1) % len(self.commands)
        return self.commands[self.k]

    def run(self, cycles: int) -> None:
        world = self.world
        done = 0
        while done < cycles:
            n = min(EPISODE_CYCLES, cycles - done)
            batch = [self._next() for _ in range(n)]
            ran = 0
            t0 = time.perf_counter()
            try:
                for c in batch:
                    world.step({0: c})
                    ran += 1
            except SimulationDivergedError:
                self.diverged += 1  # the cycles that ran count; the recovery is not timed
                self.busy += time.perf_counter() - t0
                world.reset()
            else:
                self.busy += time.perf_counter() - t0
            done += max(ran, 1)
            _place(world)
        self.cycles += done


class OdeWorldRunner:
    """The ODE engine's world (SimSpark's step) on the same workload as :class:`WorldRunner`:
    one robot and the ball, random joint velocities on every joint, re-placed upright every
    ``EPISODE_CYCLES`` cycles (not timed). It also measures ODE's own share of each step
    (contact generation and ``dWorldStep``: ``OdeWorld.engine_seconds``) on the same states."""

    def __init__(self, seed: int = 0) -> None:
        from robocup_gym.sim.engines.ode import OdeWorld

        self.world = OdeWorld([0], seed=seed)
        rng = np.random.default_rng(seed)
        vmax = self.world.robots[0].model.max_speeds
        self.commands = rng.uniform(-1.0, 1.0, (4096, len(vmax))) * vmax
        self.k = 0
        self.cycles = self.busy = 0.0
        _place(self.world)
        self.run(20)  # warm up
        self.cycles = self.busy = 0.0
        self.world.engine_seconds = 0.0

    def run(self, cycles: int) -> None:
        world = self.world
        done = 0
        while done < cycles:
            n = min(EPISODE_CYCLES, cycles - done)
            batch = []
            for _ in range(n):
                self.k = (self.k + 1) % len(self.commands)
                batch.append({0: self.commands[self.k]})
            t0 = time.perf_counter()
            for c in batch:
                world.step(c)
            self.busy += time.perf_counter() - t0
            done += n
            _place(world)
        self.cycles += done


def ode_22_robots(seed: int = 0):
    """``(world, commands)``: 22 robots of mixed types (0–4 in turn) in two teams' halves of the
    full field with the ball, on the ODE engine, and 50 cycles of random joint velocities for all
    of them (a game's worth of physics; also ``benchmarks/ode_threads.py``'s workload)."""
    from robocup_gym.sim.engines.ode import OdeWorld

    w = OdeWorld([i % 5 for i in range(22)], seed=seed)
    for i in range(22):
        side, k = (-1, i) if i < 11 else (1, i - 11)
        x, y = side * (1.0 + 1.2 * (k % 4)), -6.0 + 1.5 * k
        w.place_robot(i, x, y, heading_deg=0.0 if side < 0 else 180.0)
    w.place_ball((0.0, 0.0))
    rng = np.random.default_rng(seed)
    commands = [
        {
            i: rng.uniform(-1, 1, len(r.model.max_speeds)) * r.model.max_speeds
            for i, r in enumerate(w.robots)
        }
        for _ in range(50)
    ]
    return w, commands


def ode_22_robots_cycles_per_s(cycles: int, seed: int = 0) -> float:
    """:func:`ode_22_robots` flailing, one core: cycles per second."""
    w, commands = ode_22_robots(seed)
    for c in range(10):  # warm up
        w.step(commands[c])
    t0 = time.perf_counter()
    for c in range(cycles):
        w.step(commands[c % len(commands)])
    elapsed = time.perf_counter() - t0
    w.close()
    return cycles / elapsed


class _RecordingMujoco:
    """Stands in for the ``mujoco`` module inside :mod:`robocup_gym.sim.engines.mujoco.world` while
    recording:
    captures the complete input of every physics step the world makes (untimed): the state, the
    model fields the world retunes per cycle, and the motor rows' reference shift."""

    SPEC = mujoco.mjtState.mjSTATE_INTEGRATION

    def __init__(self, states: list) -> None:
        self._states = states
        self._pending: tuple | None = None

    def __getattr__(self, name: str):
        return getattr(mujoco, name)

    def mj_step1(self, m, d):
        buf = np.empty(mujoco.mj_stateSize(m, self.SPEC))
        mujoco.mj_getState(m, d, buf, self.SPEC)
        self._pending = (buf, m.dof_frictionloss.copy(), m.pair_solref.copy())
        mujoco.mj_step1(m, d)
        self._aref = d.efc_aref.copy()

    def mj_step2(self, m, d):
        shift = d.efc_aref - self._aref
        n = int(np.flatnonzero(shift)[-1]) + 1 if shift.any() else 0
        self._states.append((*self._pending, shift[:n].copy()))
        mujoco.mj_step2(m, d)


def replay_cycles_per_s(runner: WorldRunner, cycles: int) -> tuple[float, float]:
    """MuJoCo alone, timed on exactly the states (and model settings) the world stepped through,
    i.e. the world's own workload without its Python work around each step. Returns
    ``(raw, bare)``: ``raw`` = ``mj_step1`` + the motor rows' reference shift (one in-place
    add, the only thing the motor model needs between the two halves) + ``mj_step2``; ``bare``
    = plain ``mj_step`` from the same states (the motors then hold their joints instead of
    following the commands, so the solve differs a little)."""
    from robocup_gym.sim.engines.mujoco import world as world_module

    states: list = []
    saved = world_module.mujoco
    world_module.mujoco = _RecordingMujoco(states)
    try:
        k, cycles_before, busy_before = runner.k, runner.cycles, runner.busy
        runner.run(cycles)
        runner.k, runner.cycles, runner.busy = k, cycles_before, busy_before
    finally:
        world_module.mujoco = saved
    m = copy.deepcopy(runner.world.model)
    d = mujoco.MjData(m)
    sub = runner.world.substeps
    raw = bare = 0.0
    for buf, frictionloss, solref, shift in states:
        m.dof_frictionloss[:] = frictionloss
        m.pair_solref[:] = solref
        mujoco.mj_setState(m, d, buf, _RecordingMujoco.SPEC)
        n = len(shift)
        t0 = time.perf_counter()
        mujoco.mj_step1(m, d)
        d.efc_aref[:n] += shift
        mujoco.mj_step2(m, d)
        t1 = time.perf_counter()
        mujoco.mj_setState(m, d, buf, _RecordingMujoco.SPEC)
        t2 = time.perf_counter()
        mujoco.mj_step(m, d)
        t3 = time.perf_counter()
        raw += t1 - t0
        bare += t3 - t2
    n_cycles = len(states) / sub
    return n_cycles / raw, n_cycles / bare


class EnvRunner:
    """VelocityKick with random actions; counts every simulated cycle (wait steps included) over
    the whole time, resets included."""

    def __init__(self, seed: int = 0, engine: str = "mujoco") -> None:
        from robocup_gym.envs import VelocityKick

        self.env = env = VelocityKick(engine=engine)
        env.reset(seed=seed)
        env.action_space.seed(seed)
        self.actions = [env.action_space.sample() for _ in range(1000)]
        self.k = 0
        self.cycles = self.steps = self.episodes = 0
        self.busy = 0.0
        self.run(20)  # warm up
        self.cycles = self.steps = self.episodes = 0
        self.busy = 0.0

    def run(self, steps: int) -> None:
        env, actions = self.env, self.actions
        cycles = episodes = 0
        t0 = time.perf_counter()
        for _ in range(steps):
            self.k = (self.k + 1) % len(actions)
            _, _, te, tr, info = env.step(actions[self.k])
            cycles += info["cycles"]
            if te or tr:
                episodes += 1
                env.reset()
        self.busy += time.perf_counter() - t0
        self.cycles += cycles
        self.steps += steps
        self.episodes += episodes

    def reset_ms(self, resets: int) -> float:
        t0 = time.perf_counter()
        for _ in range(resets):
            self.env.reset()
        return (time.perf_counter() - t0) / resets * 1e3


def _make_velocity_kick():
    from robocup_gym.envs import VelocityKick

    return VelocityKick(engine="mujoco")


def measure_vector_env(steps_per_worker: int, workers: int = 2, seed: int = 0) -> float:
    """Cycles per second of all workers together in an AsyncVectorEnv (resets included)."""
    import gymnasium as gym

    vec = gym.vector.AsyncVectorEnv(
        [_make_velocity_kick] * workers, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP
    )
    try:
        wait = int(vec.call("config")[0].wait_steps)
        vec.reset(seed=seed)
        vec.action_space.seed(seed)
        for _ in range(10):
            vec.step(vec.action_space.sample())
        actions = [vec.action_space.sample() for _ in range(200)]
        cycles = 0
        t0 = time.perf_counter()
        for i in range(steps_per_worker):
            _, _, te, tr, _ = vec.step(actions[i % len(actions)])
            cycles += workers + wait * int(np.count_nonzero(te | tr))
        elapsed = time.perf_counter() - t0
    finally:
        vec.close()
    return cycles / elapsed


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="few cycles (smoke test)")
    args = parser.parse_args(argv)
    quick = args.quick
    warnings.simplefilter("ignore", RuntimeWarning)

    results: dict = {
        "quick": quick,
        "cpu_count": os.cpu_count(),
        "loadavg_1min": os.getloadavg()[0],
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
    }
    # world, raw and env are measured in interleaved rounds so that changes of the machine's load
    # hit all three alike
    world, env = WorldRunner(), EnvRunner()
    world_numpy = WorldRunner(compiled=False)
    ode = OdeWorldRunner() if ode_available() else None
    ode_env = EnvRunner(engine="ode") if ode is not None else None
    results["stepper"] = world.world.stepper
    if world.world.compiled_unavailable:
        results["compiled_unavailable"] = world.world.compiled_unavailable
    rounds, chunk = (2, 150) if quick else (10, 600)
    raw, bare = [], []
    for _ in range(rounds):
        world.run(chunk)
        world_numpy.run(chunk)
        r, b = replay_cycles_per_s(world, chunk)
        raw.append(r)
        bare.append(b)
        env.run(chunk)
        if ode is not None:
            ode.run(chunk // 2)
            ode_env.run(chunk // 2)
    results["world_cycles_per_s"] = world.cycles / world.busy
    results["world_numpy_cycles_per_s"] = world_numpy.cycles / world_numpy.busy
    results["raw_cycles_per_s"] = float(np.median(raw))
    results["bare_mj_step_cycles_per_s"] = float(np.median(bare))
    results["env_steps_per_s"] = env.cycles / env.busy
    results["env_agent_steps_per_s"] = env.steps / env.busy
    results["reset_ms"] = env.reset_ms(20 if quick else 500)
    if ode is not None:
        results["ode_world_cycles_per_s"] = ode.cycles / ode.busy
        results["ode_raw_cycles_per_s"] = ode.cycles / ode.world.engine_seconds
        results["ode_world_vs_raw"] = (
            results["ode_world_cycles_per_s"] / results["ode_raw_cycles_per_s"]
        )
        results["ode_stepper"] = ode.world.stepper
        results["ode_env_steps_per_s"] = ode_env.cycles / ode_env.busy
        results["ode_env_agent_steps_per_s"] = ode_env.steps / ode_env.busy
        results["ode_env_vs_world"] = (
            results["ode_env_steps_per_s"] / results["ode_world_cycles_per_s"]
        )
        results["ode_vs_mujoco_world"] = (
            results["ode_world_cycles_per_s"] / results["world_cycles_per_s"]
        )
        ode_env.env.close()
        results["ode_22_robots_cycles_per_s"] = ode_22_robots_cycles_per_s(20 if quick else 300)
        print(
            f"ode22  {results['ode_22_robots_cycles_per_s']:9.0f} cycles/s (22 robots)",
            file=sys.stderr,
        )
        print(
            f"ode    {results['ode_world_cycles_per_s']:9.0f} cycles/s "
            f"(ODE's own work alone: {results['ode_raw_cycles_per_s']:.0f})",
            file=sys.stderr,
        )
        print(f"odeenv {results['ode_env_steps_per_s']:9.0f} cycles/s", file=sys.stderr)
    else:
        results["ode_unavailable"] = "no double-precision libode here (apt-get install libode8)"
    results["world_divergences"] = world.diverged
    results["env_episodes"] = env.episodes
    results["env_diverged_episodes"] = env.env.diverged_episodes
    env.env.close()
    print(
        f"world  {results['world_cycles_per_s']:9.0f} cycles/s ({results['stepper']})",
        file=sys.stderr,
    )
    print(f"numpy  {results['world_numpy_cycles_per_s']:9.0f} cycles/s", file=sys.stderr)
    print(f"raw    {results['raw_cycles_per_s']:9.0f} cycles/s", file=sys.stderr)
    print(f"bare   {results['bare_mj_step_cycles_per_s']:9.0f} cycles/s", file=sys.stderr)
    print(f"env    {results['env_steps_per_s']:9.0f} cycles/s", file=sys.stderr)
    print(f"reset  {results['reset_ms']:9.3f} ms", file=sys.stderr)
    results["env_steps_per_s_2_workers"] = measure_vector_env(100 if quick else 3000, 2)
    print(f"env×2  {results['env_steps_per_s_2_workers']:9.0f} cycles/s", file=sys.stderr)
    for name, fn in EXTRA_MEASUREMENTS.items():
        results[name] = fn(quick)
    results.update(league_speeds(quick))
    results["world_vs_raw"] = results["world_cycles_per_s"] / results["raw_cycles_per_s"]
    results["compiled_speedup"] = (
        results["world_cycles_per_s"] / results["world_numpy_cycles_per_s"]
    )
    results["env_vs_world"] = results["env_steps_per_s"] / results["world_cycles_per_s"]
    results["scaling_2_workers"] = results["env_steps_per_s_2_workers"] / results["env_steps_per_s"]
    results["loadavg_1min_end"] = os.getloadavg()[0]
    print(json.dumps(results))
    return results


if __name__ == "__main__":
    main()

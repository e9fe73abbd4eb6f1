"""The world's per-cycle work compiled to C: same results, a fraction of the Python cost.

One :meth:`World.step <robocup_gym.sim.engines.mujoco.world.World.step>` is one MuJoCo step plus
~40 small
NumPy operations (motor targets, creep compensation, ODE's stop rules, the surface layer, drag,
accelerometer): about as much time again as MuJoCo itself. ``cstep.c`` does the same arithmetic
in the same order (the states are bit-equal, ``tests/sim/test_compiled.py``) in three calls per
cycle. It is compiled on first use with the system C compiler against the installed MuJoCo's
headers (it calls no MuJoCo function, it only reads and writes ``mjModel``/``mjData`` fields)
and cached; a MuJoCo upgrade compiles a new copy.

Where no compiler is found the world falls back to the NumPy path, which stays the reference.
Settings (environment variables):

* ``ROBOCUP_GYM_COMPILED``: ``0`` always use the NumPy path; ``1`` fail when the compiled path
  cannot be built; unset: use it when it can be built.
* ``CC``: the C compiler (default ``cc``).
* ``ROBOCUP_GYM_CACHE``: where the compiled library is kept (default
  ``$XDG_CACHE_HOME/robocup_gym`` or ``~/.cache/robocup_gym``).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shlex
import subprocess
import tempfile
from collections.abc import Callable
from functools import cache
from pathlib import Path

import mujoco
import numpy as np

SOURCE = Path(__file__).parent / "engines" / "mujoco" / "cstep.c"
"""The MuJoCo world's per-cycle work in C."""
CFLAGS = ("-O2", "-shared", "-fPIC", "-ffp-contract=off", "-fno-fast-math", "-std=c99")
"""No fused multiply-add and no fast-math: the C must round exactly as the NumPy path does."""
FLAGS = ("relaxed", "bouncy", "any_limited", "any_away", "nrows")
"""The shared int32 flags, in ``cstep.c``'s order."""

_p = ctypes.c_void_p
_i = ctypes.c_int32
_d = ctypes.c_double


class CompiledStepUnavailableError(RuntimeError):
    """The compiled step cannot be built or loaded here (no C compiler, a failed compilation,
    or a library that does not match the installed MuJoCo); the message says which."""


class WorldStruct(ctypes.Structure):
    """Mirror of ``rg_world`` in ``cstep.c``: pointers into the World's NumPy arrays (which
    the World keeps alive and never reallocates), sizes, indices and constants."""

    _fields_ = [
        ("n", _i),
        ("nrobots", _i),
        ("ndrag", _i),
        ("ball_qpos", _i),
        ("ball_qvel", _i),
        ("ball_pair", _i),
        ("qpos_j", _p),
        ("qvel_j", _p),
        ("lo", _p),
        ("hi", _p),
        ("vmax", _p),
        ("targets", _p),
        ("q_ref", _p),
        ("motor_lost", _p),
        ("cmd", _p),
        ("at_lo", _p),
        ("at_hi", _p),
        ("limited", _p),
        ("away", _p),
        ("q", _p),
        ("mt", _p),
        ("sort", _p),
        ("dofs", _p),
        ("motor_b", _p),
        ("shift", _p),
        ("rows", _p),
        ("qvel_root", _p),
        ("torso_body", _p),
        ("prev_vel", _p),
        ("accel", _p),
        ("drag_body", _p),
        ("ball_solref", _d * 4),
        ("flags", _p),
        ("cycle", _d),
        ("inv_cycle", _d),
        ("inv_timestep", _d),
        ("creep_window", _d),
        ("stop_erp", _d),
        ("stop_bounce", _d),
        ("fudge_torque", _d),
        ("max_torque", _d),
        ("saturated", _d),
        ("surface_layer", _d),
        ("gravity", _d),
        ("drag_lin", _d),
        ("drag_ang", _d),
        ("ball_radius", _d),
        ("ground_z", _d),
        ("bounce_min_speed", _d),
        ("diverged_qvel_sq", _d),
    ]


def cache_dir() -> Path:
    """Where compiled libraries are kept (``ROBOCUP_GYM_CACHE``, else the XDG cache)."""
    if os.environ.get("ROBOCUP_GYM_CACHE"):
        return Path(os.environ["ROBOCUP_GYM_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "robocup_gym"


def _compiler() -> list[str]:
    return shlex.split(os.environ.get("CC") or "cc")


def library_path(source: Path = SOURCE) -> Path:
    """The cached library's path for ``source``, the MuJoCo version, compiler and flags."""
    key = hashlib.sha256()
    key.update(source.read_bytes())
    key.update(" ".join([mujoco.__version__, *_compiler(), *CFLAGS]).encode())
    return cache_dir() / f"{source.stem}-mujoco{mujoco.__version__}-{key.hexdigest()[:16]}.so"


def build(path: Path | None = None, source: Path = SOURCE) -> Path:
    """Compile ``source`` (default ``cstep.c``) into ``path`` (default :func:`library_path`)
    unless it is there. Safe when several processes build at once (each writes a temporary file
    and renames it).

    Raises:
        CompiledStepUnavailableError: no compiler, or the compilation failed (with its output).
    """
    path = Path(path) if path is not None else library_path(source)
    if path.exists():
        return path
    include = Path(mujoco.__file__).with_name("include")
    if not (include / "mujoco" / "mjdata.h").exists():
        raise CompiledStepUnavailableError(f"the MuJoCo package has no C headers in {include}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(suffix=".so", dir=path.parent)
    except OSError as exc:
        raise CompiledStepUnavailableError(
            f"cannot write the compiled step's cache {path.parent} ({exc}); set ROBOCUP_GYM_CACHE "
            "to a writable folder"
        ) from exc
    os.close(fd)
    cmd = [*_compiler(), *CFLAGS, "-I", str(include), str(source), "-o", tmp, "-lm"]
    try:
        result = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as exc:
        os.unlink(tmp)
        raise CompiledStepUnavailableError(
            f"no working C compiler ({shlex.join(cmd[:1])}: {exc}); install one (Debian: "
            "apt-get install gcc) or name it in CC"
        ) from exc
    if result.returncode != 0:
        os.unlink(tmp)
        raise CompiledStepUnavailableError(
            f"compiling {source.name} failed ({shlex.join(cmd)}):\n{result.stderr[-2000:]}"
        )
    os.replace(tmp, path)
    return path


def load_library(source: Path, configure: Callable[[ctypes.CDLL], None]) -> ctypes.CDLL:
    """Build (if needed) and load the library of ``source``, then ``configure`` it (declare
    its signatures, check it; it raises :class:`CompiledStepUnavailableError` on a mismatch).
    Done once per process and source: the library, or the reason it is unavailable, is
    remembered (:func:`forget` starts over), so that a machine without a compiler does not try
    again for every world.

    Raises:
        CompiledStepUnavailableError: it cannot be built, loaded or configured.
    """
    result = _load_once(source, configure)
    if isinstance(result, CompiledStepUnavailableError):
        raise CompiledStepUnavailableError(str(result))
    return result


def forget() -> None:
    """Forget every loaded library and failure (the next load tries again)."""
    _load_once.cache_clear()


@cache
def _load_once(
    source: Path, configure: Callable[[ctypes.CDLL], None]
) -> ctypes.CDLL | CompiledStepUnavailableError:
    try:
        path = build(source=source)
        try:
            lib = ctypes.CDLL(str(path))
        except OSError as exc:
            raise CompiledStepUnavailableError(f"cannot load {path}: {exc}") from exc
        configure(lib)
    except CompiledStepUnavailableError as exc:
        return exc
    return lib


def load() -> ctypes.CDLL:
    """The world's compiled step (:func:`load_library` of ``cstep.c``), checked against the
    installed MuJoCo and the :class:`WorldStruct` layout.

    Raises:
        CompiledStepUnavailableError: it cannot be built or does not match.
    """
    return load_library(SOURCE, _configure_step)


def _configure_step(lib: ctypes.CDLL) -> None:
    lib.rg_header_version.restype = ctypes.c_int
    lib.rg_sizeof_world.restype = ctypes.c_int
    if lib.rg_header_version() != mujoco.mj_version():
        raise CompiledStepUnavailableError(
            f"{SOURCE.name} was compiled for MuJoCo {lib.rg_header_version()}, this is "
            f"{mujoco.mj_version()}; delete it from {cache_dir()} to rebuild"
        )
    if lib.rg_sizeof_world() != ctypes.sizeof(WorldStruct):
        raise CompiledStepUnavailableError(
            f"rg_world has {lib.rg_sizeof_world()} bytes, WorldStruct "
            f"{ctypes.sizeof(WorldStruct)}: cstep.c and compiled.py disagree"
        )
    for name in ("rg_pre", "rg_mid", "rg_post"):
        fn = getattr(lib, name)
        fn.argtypes = [_p, _p, _p] + ([ctypes.c_int] if name == "rg_mid" else [])
        fn.restype = ctypes.c_int if name == "rg_post" else None


def wanted() -> bool | None:
    """``ROBOCUP_GYM_COMPILED`` as a World's ``compiled`` default: ``False`` (``0``), ``True``
    (``1``) or ``None`` (unset: use it when it can be built)."""
    value = os.environ.get("ROBOCUP_GYM_COMPILED", "").strip().lower()
    if value in ("", "auto"):
        return None
    if value in ("0", "false", "no", "off"):
        return False
    if value in ("1", "true", "yes", "on"):
        return True
    raise ValueError(f"ROBOCUP_GYM_COMPILED must be 0, 1 or auto, got {value!r}")


def available() -> bool:
    """Whether the compiled step can be built and loaded here."""
    try:
        load()
    except CompiledStepUnavailableError:
        return False
    return True


def address(array: np.ndarray) -> int:
    """Address of a C-contiguous array's data (for a :class:`WorldStruct` pointer)."""
    if not array.flags.c_contiguous:
        raise ValueError("the compiled step needs C-contiguous arrays")
    return array.__array_interface__["data"][0]


class CompiledStep:
    """The three C calls of one cycle, bound to one world's model, data and arrays.

    ``pre()`` before the cycle's MuJoCo steps, ``mid(first)`` between ``mj_step1`` and
    ``mj_step2`` of each, ``post()`` after the last (returns whether the state diverged).
    ``keep`` holds every array the struct points into, so that none is freed or moved.
    """

    def __init__(
        self,
        struct: WorldStruct,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        keep: list[np.ndarray],
    ) -> None:
        lib = load()
        self.struct = struct
        self._keep = keep
        ptr = ctypes.addressof(struct)
        m, d = model._address, data._address
        self._pre_fn, self._mid_fn, self._post_fn = lib.rg_pre, lib.rg_mid, lib.rg_post
        self._args = (ptr, m, d)

    def pre(self) -> None:
        self._pre_fn(*self._args)

    def mid(self, first: bool) -> None:
        self._mid_fn(*self._args, first)

    def post(self) -> bool:
        return bool(self._post_fn(*self._args))

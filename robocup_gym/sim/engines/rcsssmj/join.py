"""A player's join made the same in every process: zero-filled heap memory while MuJoCo
recompiles.

When a player joins, ``rcsssmj`` attaches the robot to its MuJoCo spec and calls
``MjSpec.recompile(model, data)``. MuJoCo's ``mj_recompile`` (3.5.0, what ``rcsssmj`` 0.2.1
pins, and every release since, up to 3.12 at least) saves every actuator's control from the *old*
data before compiling, indexing the old ``ctrl`` array by the *new* model's actuator numbers: for
the actuators the old model did not have, it reads past the end of ``ctrl``, into the fields
behind it and the alignment padding between them, in a copy of the data that the Python bindings
have just allocated. The fields are the simulation's state, but the padding is uninitialised heap
memory: what the process allocated and freed before decides which controls a joining robot starts
with (so the start depended on the lengths of paths and environment variables), and a huge one
makes MuJoCo warn ``Nan, Inf or huge value in CTRL`` and clear every control.

glibc's malloc perturbation (``MALLOC_PERTURB_``, or ``mallopt(M_PERTURB, …)``) fills every new
allocation with the complement of its byte: with 255, new memory is zero. A server started with
:data:`SERVER_ENVIRONMENT` and an in-process world that joins inside
:func:`zero_filled_allocations` then read the same bytes (the state's fields, and zero for the
padding), so the robot starts with the same controls in both, wherever they run.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import platform
from collections.abc import Callable, Iterator

__all__ = ["SERVER_ENVIRONMENT", "zero_fill_available", "zero_filled_allocations"]

_PERTURB_BYTE = 255
"""glibc fills a new allocation with ``byte ^ 0xFF`` (so 255 gives zeros) and a freed one with
``byte``."""
_M_PERTURB = -6
"""glibc's ``mallopt`` parameter for the perturbation byte (``malloc.h``)."""

SERVER_ENVIRONMENT = {"MALLOC_PERTURB_": str(_PERTURB_BYTE)}
"""Environment variables a real ``rcssservermj`` is started with (see the module docstring)."""


def _glibc_mallopt() -> Callable[[int, int], int] | None:
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        return None
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return None
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return mallopt


_MALLOPT = _glibc_mallopt()


def zero_fill_available() -> bool:
    """Whether this process can zero-fill its allocations (Linux with glibc)."""
    return _MALLOPT is not None


@contextlib.contextmanager
def zero_filled_allocations() -> Iterator[bool]:
    """Inside: every heap allocation of this process starts zeroed, as in a server started with
    :data:`SERVER_ENVIRONMENT`; afterwards the perturbation this process started with is back.
    Yields whether it could (``False`` where glibc's ``mallopt`` is missing: nothing changes)."""
    if _MALLOPT is None:
        yield False
        return
    try:
        before = int(os.environ.get("MALLOC_PERTURB_", "0") or 0) & 0xFF
    except ValueError:
        before = 0
    if _MALLOPT(_M_PERTURB, _PERTURB_BYTE) != 1:
        yield False
        return
    try:
        yield True
    finally:
        _MALLOPT(_M_PERTURB, before)

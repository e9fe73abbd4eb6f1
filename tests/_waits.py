"""Waiting in tests for what has to happen (a condition, a process's end) instead of sleeping
for a fixed time that a loaded machine can outlast. Imported by the test packages by name
(``tests/`` is on ``sys.path`` in pytest's default import mode)."""

from __future__ import annotations

import time
from collections.abc import Callable


def pid_alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie counts as gone; reads ``/proc``: Linux)."""
    try:
        with open(f"/proc/{pid}/status") as f:
            return not any(line.startswith("State:") and "Z" in line for line in f)
    except FileNotFoundError:
        return False


def wait_until(pred: Callable[[], object], timeout: float = 10.0, what: str = "condition") -> None:
    """Poll ``pred`` every 20 ms until it is true.

    Raises:
        AssertionError: naming ``what``, when it is still false after ``timeout`` seconds.
    """
    deadline = time.monotonic() + timeout
    while not pred():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)

"""Fixtures of the backend tests: in-process protocol servers and a fake rcssserver3d, all on
OS-chosen ports and cleaned up after each test (also when it fails)."""

from __future__ import annotations

import json
import logging
import os
import signal
import stat
import sys
import threading
import time
from pathlib import Path

import pytest
from _waits import pid_alive

HERE = Path(__file__).resolve().parent
HOST = "127.0.0.1"


@pytest.fixture(autouse=True)
def _quiet_logs(caplog):
    caplog.set_level(logging.WARNING, logger="robocup_gym.server")
    yield


@pytest.fixture
def backends():
    """``backends.add(b)`` registers a backend to be closed after the test."""
    opened: list = []

    class Registry:
        @staticmethod
        def add(b):
            opened.append(b)
            return b

    yield Registry
    for b in opened:
        b.close()


class FakeServer:
    """Handle on the fake rcssserver3d executable and its event report."""

    def __init__(self, tmp_path: Path) -> None:
        self.report = tmp_path / "fake_report.jsonl"
        self.binary = tmp_path / "bin" / "rcssserver3d"
        self.binary.parent.mkdir()
        self.binary.write_text(
            f'#!/bin/sh\nexec "{sys.executable}" "{HERE / "fake_rcssserver3d.py"}" "$@"\n'
        )
        self.binary.chmod(self.binary.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
        self.pids: set[int] = set()

    def env(self, mode: str) -> dict[str, str]:
        return {"FAKE_RCSS_MODE": mode, "FAKE_RCSS_REPORT": str(self.report)}

    def events(self) -> list[dict]:
        if not self.report.exists():
            return []
        out = [json.loads(line) for line in self.report.read_text().splitlines() if line]
        self.pids.update(e["pid"] for e in out)
        return out

    def wait_event(self, name: str, timeout: float = 20.0) -> dict:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for e in self.events():
                if e["event"] == name:
                    return e
            time.sleep(0.02)
        raise AssertionError(f"fake server never reported {name!r}; events: {self.events()}")


@pytest.fixture
def fake_server(tmp_path, monkeypatch):
    """A fake rcssserver3d (see ``fake_rcssserver3d.py``) on ``RCSSSERVER3D``; ``fake.use(mode)``
    selects its behaviour. Any of its processes still running after the test is killed (by PID)."""
    fake = FakeServer(tmp_path)
    monkeypatch.setenv("RCSSSERVER3D", str(fake.binary))

    def use(mode: str) -> FakeServer:
        for k, v in fake.env(mode).items():
            monkeypatch.setenv(k, v)
        return fake

    fake.use = use  # type: ignore[attr-defined]
    use("idle")
    yield fake
    fake.events()
    for pid in fake.pids:
        if pid_alive(pid):
            os.kill(pid, signal.SIGKILL)


def no_leftover_threads() -> bool:
    return not [t for t in threading.enumerate() if t.name == "robocup-gym-serve"]

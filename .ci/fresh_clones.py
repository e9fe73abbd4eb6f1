#!/usr/bin/env python3
"""Run the test suite in several fresh clones at different paths, one after another.

A test that passes in one checkout and fails in another (because of where the clone and its
virtual environment live, what the environment holds, or what ran before) is a defect. This
clones the current commit (``HEAD``, not the working tree) into ``--paths`` new folders whose
paths differ in depth and length, runs ``.ci/run`` in each (a fresh virtual environment, then the
whole suite) and reports each run's pytest summary. The folders are removed afterwards
(``--keep`` keeps them).

    python3 .ci/fresh_clones.py [--paths 5] [--root /tmp] [--pytest-args "-x"] [--keep]

Prints a line per clone and, last, one JSON object: ``paths``, ``passed`` (clones whose suite
passed), and per clone its path, exit status, summary line and seconds. Exits non-zero if any
clone failed. Needs only Python's standard library and git.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
_SUMMARY = re.compile(r"^=*\s*(\d+ (passed|failed|error).*)$")


def clone_paths(root: Path, n: int) -> list[Path]:
    """``n`` distinct clone folders under ``root``, of growing depth and length."""
    paths = []
    for k in range(n):
        parts = [f"c{k}"] + [f"{'d' * (3 + 7 * j)}{j}" for j in range(k)]
        paths.append(root.joinpath(*parts, "robocup-gym"))
    return paths


def summary_line(output: str) -> str:
    """pytest's last summary line (``N passed, M skipped in S s``), or the output's last line."""
    lines = [ln.strip() for ln in output.splitlines() if ln.strip()]
    for line in reversed(lines):
        m = _SUMMARY.match(line)
        if m:
            return m.group(1).rstrip("= ")
    return lines[-1] if lines else ""


def run_clone(path: Path, pytest_args: str, log_dir: Path, name: str) -> dict:
    path.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(["git", "clone", "-q", str(REPO), str(path)], check=True)
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    env["CI"] = "true"
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".venv" not in p
    )
    command = ["bash", ".ci/run"]
    if pytest_args:
        env["PYTEST_ADDOPTS"] = pytest_args
    t0 = time.monotonic()
    done = subprocess.run(command, cwd=path, env=env, capture_output=True, text=True)
    seconds = time.monotonic() - t0
    output = done.stdout + done.stderr
    log = log_dir / f"{name}.log"
    log.write_text(output)
    return {
        "path": str(path),
        "returncode": done.returncode,
        "summary": summary_line(output),
        "seconds": round(seconds, 1),
        "log": str(log),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--paths", type=int, default=5, help="how many fresh clones")
    parser.add_argument("--root", default=tempfile.gettempdir(), help="where the clones go")
    parser.add_argument("--pytest-args", default="", help="extra pytest options (PYTEST_ADDOPTS)")
    parser.add_argument("--keep", action="store_true", help="keep the clones")
    args = parser.parse_args()
    root = Path(tempfile.mkdtemp(prefix="robocup_gym_clones_", dir=args.root))
    log_dir = root / "logs"
    log_dir.mkdir()
    results = []
    try:
        for path in clone_paths(root, args.paths):
            r = run_clone(path, args.pytest_args, log_dir, path.relative_to(root).parts[0])
            results.append(r)
            status = "ok  " if r["returncode"] == 0 else "FAIL"
            print(f"{status} {r['seconds']:7.1f} s  {r['path']}  {r['summary']}", flush=True)
            if not args.keep:
                shutil.rmtree(root / path.relative_to(root).parts[0], ignore_errors=True)
    finally:
        if not args.keep:
            for child in root.iterdir():
                if child != log_dir:
                    shutil.rmtree(child, ignore_errors=True)
    passed = sum(r["returncode"] == 0 for r in results)
    print(f"logs: {log_dir}")
    print(json.dumps({"paths": len(results), "passed": passed, "clones": results}))
    return 0 if passed == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())

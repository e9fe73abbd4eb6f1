"""The commands the README and docs/*.md show exist, with every option they use.

Every ``robocup-gym …``, ``python -m robocup_gym.server …`` and ``python benchmarks/….py …``
command in a code block, an indented block or an inline code span is checked against the real
command-line interface: the subcommand must exist and each ``--option`` must be one it accepts.
(The commands are not run: training a million steps is not a test.)
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from functools import cache
from pathlib import Path

import pytest

pytest.importorskip("typer")

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_START = re.compile(
    r"(robocup-gym(?=\s|$)|python3? -m robocup_gym\.server|python3? benchmarks/[\w./-]+\.py)"
)
_STOP = {"#", "&", "&&", "|", "||", ";", ">", ">>", "2>&1", "\\"}


def _code_fragments(text: str) -> list[str]:
    """Fenced and indented code lines, and inline code spans."""
    out, fenced = [], False
    for line in text.splitlines():
        if line.strip().startswith("```"):
            fenced = not fenced
            continue
        if fenced and "`" in line:  # prose inside a text block (a folder listing, …)
            out += re.findall(r"`([^`]+)`", line)
        elif fenced or (line.startswith("    ") and "`" not in line):
            out.append(line)
        else:
            out += re.findall(r"`([^`]+)`", line)
    return out


def documented_commands() -> list[tuple[str, list[str]]]:
    """``(where, argv)`` of every command shown in the docs."""
    found = []
    for doc in DOCS:
        for fragment in _code_fragments(doc.read_text()):
            for m in _START.finditer(fragment):
                rest = fragment[m.start() :]
                try:
                    tokens = shlex.split(rest, comments=True)
                except ValueError:
                    tokens = rest.split()
                argv = []
                for tok in tokens:
                    if tok in _STOP or tok.startswith((">", "2>")):
                        break
                    argv.append(tok)
                head = m.group(1).split()
                found.append((f"{doc.name}: {rest.strip()[:80]}", [*head, *argv[len(head) :]]))
    return found


@cache
def _click_app():
    import typer

    from robocup_gym.cli import app

    return typer.main.get_command(app)


def _click_options(command) -> set[str]:
    out = set()
    for p in command.params:
        out.update(o for o in (*p.opts, *p.secondary_opts) if o.startswith("-"))
    return out | {"--help"}


def _argparse_options(parser) -> set[str]:
    return {o for a in parser._actions for o in a.option_strings}


@cache
def _script_help(script: str) -> str:
    res = subprocess.run(
        [sys.executable, str(ROOT / script), "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert res.returncode == 0, f"{script} --help failed:\n{res.stderr[-2000:]}"
    return res.stdout


def _options_used(argv: list[str]) -> list[str]:
    """``--name`` of every option, also from usage forms like ``[--sync/--no-sync]``."""
    out = []
    for a in argv:
        for part in a.strip("[]").split("/"):
            if part.startswith("--"):
                out.append(part.split("=", 1)[0])
    return out


COMMANDS = documented_commands()


def test_the_docs_show_commands():
    assert len(COMMANDS) > 30
    kinds = {argv[0] for _, argv in COMMANDS}
    assert {"robocup-gym", "python"} <= kinds


@pytest.mark.parametrize("where, argv", COMMANDS, ids=[w for w, _ in COMMANDS])
def test_every_documented_command_exists_with_its_options(where, argv):
    from robocup_gym.server.__main__ import build_parser

    if argv[0] == "robocup-gym":
        if len(argv) == 1 or argv[1].startswith("-"):
            return  # `robocup-gym` / `robocup-gym --help`
        group = _click_app()
        name, rest = argv[1], argv[2:]
        assert name in group.commands, f"{where}: no command `robocup-gym {name}`"
        command = group.commands[name]
        if name == "serve":
            valid = _argparse_options(build_parser())
        elif hasattr(command, "commands"):  # experiments paper
            sub = next((a for a in rest if not a.startswith("-")), None)
            assert sub in command.commands, f"{where}: no `robocup-gym {name} {sub}`"
            valid = _click_options(command.commands[sub])
        else:
            valid = _click_options(command)
    elif "-m" in argv:
        rest, valid = argv[3:], _argparse_options(build_parser())
    else:
        script = argv[1]
        assert (ROOT / script).exists(), f"{where}: {script} does not exist"
        help_text = _script_help(script)
        rest = argv[2:]
        valid = set(re.findall(r"--[\w-]+", help_text)) | {"--help"}
    unknown = [o for o in _options_used(rest) if o not in valid]
    assert not unknown, f"{where}: option(s) {unknown} do not exist; valid: {sorted(valid)}"


def test_the_checker_catches_an_option_that_does_not_exist(monkeypatch):
    """The check is real: a made-up option fails it."""
    with pytest.raises(AssertionError, match="--no-such-option"):
        test_every_documented_command_exists_with_its_options(
            "made up", ["robocup-gym", "train", "velocity-kick", "--no-such-option"]
        )
    with pytest.raises(AssertionError, match="--sync-timeout"):
        test_every_documented_command_exists_with_its_options(
            "made up", ["robocup-gym", "eval", "RUN", "--sync-timeout", "3"]
        )

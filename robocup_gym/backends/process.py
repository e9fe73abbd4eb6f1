"""A private rcssserver3d process: find the binary, configure it, start it, always stop it.

:class:`ServerProcess` starts one ``rcssserver3d`` for one environment, in **agent sync mode with
real-time mode off**, on TCP ports the operating system reports free, with a configuration it
generates in a temporary folder. The user's ``~/.simspark`` is never read or written: the child
runs with ``HOME`` set to that folder, so SimSpark's per-user init-script directory is
``<tmp>/.simspark`` (the server copies its installed init scripts there on first start).

What is generated (see :func:`render_server_script` and ``docs/rcssserver3d.md``):

* ``<tmp>/.simspark/rcssserver3d.rb`` — the installed ``rcssserver3d.rb`` (found next to the
  binary, ``<prefix>/share/rcssserver3d/rcssserver3d.rb``) with ``$enableRealTimeMode``,
  ``$enableInternalMonitor`` and ``$recordLogfile`` set to ``false``, and a header that sets the
  ``spark.rb`` globals read by ``sparkSetupServer()`` (``$agentSyncMode = true``,
  ``$monitorStep = 0.02`` so the monitor stream carries every cycle, single-threaded server,
  the two ports). It is passed as ``--script-path``; ports also go on the command line
  (``--agent-port``/``--server-port``). Without an installed ``rcssserver3d.rb`` a built-in
  copy of 0.7.3's script (headless) is used.

Clean-up: the child is stopped with **SIGINT** (rcssserver3d ignores SIGTERM in some states),
escalating to SIGKILL after a grace period, by :meth:`ServerProcess.stop`, when the object is
garbage-collected (:func:`weakref.finalize`), at interpreter exit (``finalize``'s ``atexit``
hook), and — on Linux — when the Python process dies without running any of these
(``PR_SET_PDEATHSIG`` = SIGINT, set in the child before ``exec``). Only this child is signalled,
by its PID; nothing is ever killed by name.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import weakref
from collections.abc import Sequence
from pathlib import Path

from robocup_gym.backends.base import BackendError, BackendNotAvailableError
from robocup_gym.protocol.framing import connect

__all__ = [
    "RCSSSERVER3D_ENV",
    "RcssServerNotFoundError",
    "ServerProcess",
    "ServerStartError",
    "find_binary",
    "find_script_template",
    "free_ports",
    "render_server_script",
    "sweep_stale_folders",
    "wait_for_port",
]

log = logging.getLogger("robocup_gym.backends.rcssserver3d")

RCSSSERVER3D_ENV = "RCSSSERVER3D"
"""Environment variable naming the rcssserver3d executable (a path, or a name on ``PATH``)."""

INSTALL_HINT = (
    "Install rcssserver3d (SimSpark) — e.g. build it from https://gitlab.com/robocup-sim/SimSpark "
    "(spark, then rcssserver3d: cmake, make, sudo make install, sudo ldconfig) or use your "
    "distribution's package — and put it on PATH or set RCSSSERVER3D=/path/to/rcssserver3d; or "
    "connect to a running server with backend_options={'host': ..., 'agent_port': ..., "
    "'monitor_port': ...}; or use the in-process world, which needs no server: engine='ode' "
    "(the default, SimSpark's own physics) or engine='mujoco'."
)


class RcssServerNotFoundError(BackendNotAvailableError):
    """No rcssserver3d executable was found (the message says where it looked and what to do).

    A :class:`~robocup_gym.backends.BackendNotAvailableError`, like an unknown backend name.
    """

    def __init__(self, message: str) -> None:
        super().__init__(f"backend 'rcssserver3d' is not available: {message}")


class ServerStartError(BackendError):
    """The server process exited or did not become ready (the message has its log tail)."""


# ------------------------------------------------------------------------------------------
# finding things
# ------------------------------------------------------------------------------------------


def find_binary(explicit: str | os.PathLike[str] | None = None) -> str:
    """Absolute path of the rcssserver3d executable.

    Looks at ``explicit``, then the :data:`RCSSSERVER3D_ENV` environment variable, then
    ``rcssserver3d`` on ``PATH``. A path that is given but unusable is an error (no silent
    fallback to ``PATH``).

    Raises:
        RcssServerNotFoundError: nothing usable found; says where it looked and how to install
            rcssserver3d or use the embedded backend.
    """
    for source, value in (
        ("binary=", explicit),
        (RCSSSERVER3D_ENV, os.environ.get(RCSSSERVER3D_ENV)),
    ):
        if value is None or str(value) == "":
            continue
        value = str(value)
        if os.sep in value or (os.altsep and os.altsep in value):
            path = Path(value).expanduser()
            if not path.exists():
                raise RcssServerNotFoundError(
                    f"rcssserver3d not found: {source} points to {value!r}, which does not exist. "
                    + INSTALL_HINT
                )
            if path.is_dir() or not os.access(path, os.X_OK):
                raise RcssServerNotFoundError(
                    f"rcssserver3d not usable: {source} points to {value!r}, which is not an "
                    "executable file. " + INSTALL_HINT
                )
            return str(path.resolve())
        found = shutil.which(value)
        if found is None:
            raise RcssServerNotFoundError(
                f"rcssserver3d not found: {source} is {value!r}, which is not on PATH. "
                + INSTALL_HINT
            )
        return str(Path(found).resolve())
    found = shutil.which("rcssserver3d")
    if found is None:
        raise RcssServerNotFoundError(
            f"rcssserver3d not found: the {RCSSSERVER3D_ENV} environment variable is not set and "
            "there is no rcssserver3d on PATH. " + INSTALL_HINT
        )
    return str(Path(found).resolve())


def find_script_template(binary: str | os.PathLike[str]) -> Path | None:
    """The installed ``rcssserver3d.rb`` that belongs to ``binary``, or ``None``.

    Tries ``<prefix>/share/rcssserver3d/rcssserver3d.rb`` for the binary's prefix (symlinks
    resolved), then ``/usr/local/share/…`` and ``/usr/share/…``.
    """
    b = Path(binary).resolve()
    candidates = [b.parent.parent / "share" / "rcssserver3d" / "rcssserver3d.rb"]
    candidates += [
        Path(p) / "rcssserver3d" / "rcssserver3d.rb" for p in ("/usr/local/share", "/usr/share")
    ]
    for c in candidates:
        if c.is_file():
            return c
    return None


def free_ports(count: int = 2, host: str = "127.0.0.1") -> list[int]:
    """``count`` distinct TCP ports that the OS reports free on ``host`` right now.

    Binds ``count`` sockets to port 0 at the same time (so the ports differ), reads the ports
    back and closes them. Another process may still take a port before the server binds it;
    :class:`ServerProcess` retries with new ports when the server fails to start.
    """
    socks: list[socket.socket] = []
    try:
        for _ in range(count):
            s = socket.socket(
                socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM
            )
            socks.append(s)
            s.bind((host, 0))
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def server_library_dirs(binary: str | os.PathLike[str]) -> list[str]:
    """``<prefix>/lib/simspark`` and ``<prefix>/lib/rcssserver3d`` of the installation ``binary``
    belongs to, where they exist: a server built from source into a prefix needs them on
    ``LD_LIBRARY_PATH`` (its run path misses libraries it loads indirectly), so the launcher puts
    them there for the child."""
    prefix = Path(os.path.realpath(binary)).parent.parent
    dirs = [prefix / "lib" / "simspark", prefix / "lib" / "rcssserver3d"]
    return [str(d) for d in dirs if d.is_dir()]


# ------------------------------------------------------------------------------------------
# configuration
# ------------------------------------------------------------------------------------------

#: A minimal headless server script (the set-up calls rcssserver3d 0.7.3's ``rcssserver3d.rb``
#: makes, without its GUI and logging options), used when no installed script is found next to
#: the binary.
BUILTIN_SCRIPT = """\
#
# rcssserver3d.rb (generated by robocup_gym: minimal headless set-up)
#
$recordLogfile = false
$enableInternalMonitor = false
$enableRealTimeMode = false

sparkSetupServer()
sparkSetupInput()
if ($enableRealTimeMode)
  sparkSetupTimer()
end

run "scripts/bindings.rb"
run "scripts/materials.rb"

sparkResetLogging()
sparkLogErrorToCerr()

run "naosoccersim.rb"
"""

# Globals assigned at the top level of rcssserver3d.rb itself: their assignments are rewritten.
_SCRIPT_SETTINGS = {
    "enableRealTimeMode": "false",
    "enableInternalMonitor": "false",
    "recordLogfile": "false",
}


def render_server_script(
    template: str | None,
    agent_port: int,
    monitor_port: int,
    *,
    sync: bool = True,
    real_time: bool = False,
    monitor_step: float = 0.02,
) -> str:
    """The ``rcssserver3d.rb`` this package runs the server with.

    ``template`` is the installed script's text (``None`` = :data:`BUILTIN_SCRIPT`). Its own
    top-level assignments of ``$enableRealTimeMode``/``$enableInternalMonitor``/``$recordLogfile``
    are rewritten (real-time mode from ``real_time``; no internal monitor, no log file), and a
    header sets the ``spark.rb`` globals that ``sparkSetupServer()`` reads when the script calls
    it: ``$agentSyncMode``, ``$monitorStep`` (0.02 = a monitor frame every cycle), the ports and
    the single-threaded mode (the 0.7.3 server crashes multi-threaded with Ruby >= 3; protocol
    behaviour is the same).
    """
    text = BUILTIN_SCRIPT if template is None else template
    settings = dict(_SCRIPT_SETTINGS)
    settings["enableRealTimeMode"] = "true" if real_time else "false"
    missing = []
    for name, value in settings.items():
        pattern = re.compile(rf"^([ \t]*)\${name}[ \t]*=.*$", re.MULTILINE)
        text, n = pattern.subn(
            lambda m, name=name, value=value: f"{m.group(1)}${name} = {value}", text
        )
        if n == 0:
            missing.append(f"${name} = {value}")
    header = [
        "# ---- generated by robocup_gym (rcssserver3d backend); safe to delete ----",
        f"$agentSyncMode = {'true' if sync else 'false'}",
        f"$monitorStep = {float(monitor_step)!r}",
        f"$agentPort = {int(agent_port)}",
        f"$serverPort = {int(monitor_port)}",
        "$multiThreadedMode = false",
        "$serverMultiThreadedMode = false",
        "$threadedAgentControl = false",
        *missing,
        "# ---- end of generated settings; the server's own script follows ----",
        "",
    ]
    return "\n".join(header) + text


# ------------------------------------------------------------------------------------------
# the process
# ------------------------------------------------------------------------------------------

_PR_SET_PDEATHSIG = 1


def _death_signal_preexec(sig: int) -> object | None:
    """A ``preexec_fn`` that asks Linux to send ``sig`` to the child when its parent dies."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl  # resolved here, not after fork
    except (OSError, AttributeError):  # pragma: no cover - exotic libc
        return None
    prctl.restype = ctypes.c_int
    prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
    parent = os.getpid()

    def preexec() -> None:  # runs in the child between fork and exec
        prctl(_PR_SET_PDEATHSIG, sig, 0, 0, 0)
        if os.getppid() != parent:  # the parent died before prctl took effect
            os.kill(os.getpid(), sig)

    return preexec


_FOLDER_PREFIX = "robocup_gym_rcssserver3d_"
_OWNER_FILE = "robocup_gym_owner.txt"


def _pid_running(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - someone else's process
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return True


def sweep_stale_folders(parent: str | None = None) -> list[str]:
    """Delete configuration folders left behind by killed Python processes.

    A folder is removed only if it is ours (name prefix, owned by this user) and both the Python
    process that made it and its server are gone (their PIDs are in ``robocup_gym_owner.txt``).
    Only happens after a parent died without clean-up (the server itself was stopped by the
    parent-death signal). Returns the removed paths.
    """
    parent = parent or tempfile.gettempdir()
    removed = []
    try:
        entries = list(os.scandir(parent))
    except OSError:  # pragma: no cover
        return removed
    for entry in entries:
        if not entry.name.startswith(_FOLDER_PREFIX) or not entry.is_dir(follow_symlinks=False):
            continue
        try:
            if entry.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            with open(os.path.join(entry.path, _OWNER_FILE)) as f:
                pids = [int(x) for x in f.read().split()]
        except (OSError, ValueError):
            continue
        if pids and not any(_pid_running(pid) for pid in pids):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(entry.path)
    return removed


def _stop_child(proc: subprocess.Popen, folder: str | None, grace_s: float) -> None:
    """Stop ``proc`` (SIGINT, then SIGKILL after ``grace_s``) and delete ``folder``.

    Module-level (no reference to the owner) so that :func:`weakref.finalize` can call it.
    """
    try:
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                proc.send_signal(signal.SIGINT)
            try:
                proc.wait(grace_s)
            except subprocess.TimeoutExpired:
                log.warning(
                    "rcssserver3d (pid %d) ignored SIGINT for %.1f s; sending SIGKILL",
                    proc.pid,
                    grace_s,
                )
                with contextlib.suppress(ProcessLookupError):
                    proc.kill()
                with contextlib.suppress(subprocess.TimeoutExpired):
                    proc.wait(5.0)
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)


class ChildProcess:
    """What a server child process says of itself: its ``proc`` (``None`` before it started
    and after it was stopped), pid and whether it runs."""

    proc: subprocess.Popen | None = None

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid

    @property
    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None


class ServerProcess(ChildProcess):
    """One rcssserver3d child process with a private, generated configuration.

    Args:
        binary: Executable (``None`` = :func:`find_binary`).
        host: Address the client connects to (the server listens on all interfaces).
        agent_port, monitor_port: Ports (``None`` = chosen by the OS, see :func:`free_ports`).
        sync: Agent sync mode (on: each cycle waits for every agent's ``(syn)``).
        real_time: Real-time mode (off: cycles run back to back).
        monitor_step: Seconds between monitor frames (0.02 = every cycle).
        extra_args: More command-line arguments for the server.
        script_template: ``rcssserver3d.rb`` to start from (``None`` = the installed one, see
            :func:`find_script_template`, else :data:`BUILTIN_SCRIPT`).
        stop_grace_s: Seconds to wait after SIGINT before SIGKILL.

    Nothing is started until :meth:`start`.
    """

    def __init__(
        self,
        binary: str | os.PathLike[str] | None = None,
        *,
        host: str = "127.0.0.1",
        agent_port: int | None = None,
        monitor_port: int | None = None,
        sync: bool = True,
        real_time: bool = False,
        monitor_step: float = 0.02,
        extra_args: Sequence[str] = (),
        script_template: str | os.PathLike[str] | None = None,
        stop_grace_s: float = 5.0,
    ) -> None:
        self.binary = find_binary(binary)
        self.host = host
        self.requested_ports = (agent_port, monitor_port)
        self.sync = bool(sync)
        self.real_time = bool(real_time)
        self.monitor_step = float(monitor_step)
        self.extra_args = tuple(str(a) for a in extra_args)
        self.script_template = (
            Path(script_template)
            if script_template is not None
            else find_script_template(self.binary)
        )
        self.stop_grace_s = float(stop_grace_s)
        self.folder: str | None = None
        self.agent_port = 0
        self.monitor_port = 0
        self.proc: subprocess.Popen | None = None
        self._finalizer: weakref.finalize | None = None
        self._log_file = None

    # -------------------------------------------------------------- paths
    @property
    def home(self) -> Path:
        """The private ``HOME`` of the child (``<folder>``)."""
        assert self.folder is not None
        return Path(self.folder)

    @property
    def script_path(self) -> Path:
        """The generated ``rcssserver3d.rb``."""
        return self.home / ".simspark" / "rcssserver3d.rb"

    @property
    def log_path(self) -> Path:
        """The server's stdout and stderr."""
        return self.home / "rcssserver3d.log"

    # -------------------------------------------------------------- start / stop
    def start(self) -> tuple[int, int]:
        """Write the configuration and start the server; returns (agent port, monitor port).

        Returns as soon as the process runs; the caller polls the ports for readiness (see
        :meth:`check_alive`).
        """
        if self.proc is not None:
            raise RuntimeError("server already started")
        sweep_stale_folders()
        self.folder = tempfile.mkdtemp(prefix=_FOLDER_PREFIX)
        try:
            a, m = self.requested_ports
            if a is None or m is None:
                fa, fm = free_ports(2, self.host)
                a = fa if a is None else a
                m = fm if m is None else m
            self.agent_port, self.monitor_port = int(a), int(m)
            self._write_config()
            self._spawn()
        except BaseException:
            shutil.rmtree(self.folder, ignore_errors=True)
            self.folder = None
            raise
        return self.agent_port, self.monitor_port

    def _write_config(self) -> None:
        dot = self.home / ".simspark"
        dot.mkdir(parents=True, exist_ok=True)
        template = None
        if self.script_template is not None:
            template = Path(self.script_template).read_text(encoding="latin-1")
        else:
            log.info(
                "no installed rcssserver3d.rb found next to %s; using a minimal built-in script",
                self.binary,
            )
        text = render_server_script(
            template,
            self.agent_port,
            self.monitor_port,
            sync=self.sync,
            real_time=self.real_time,
            monitor_step=self.monitor_step,
        )
        self.script_path.write_text(text, encoding="latin-1")

    def command_line(self) -> list[str]:
        """The command the server is started with."""
        return [
            self.binary,
            "--agent-port",
            str(self.agent_port),
            "--server-port",
            str(self.monitor_port),
            "--script-path",
            str(self.script_path),
            *self.extra_args,
        ]

    def _spawn(self) -> None:
        env = dict(os.environ)
        env["HOME"] = str(self.home)
        libs = server_library_dirs(self.binary)
        if libs:
            env["LD_LIBRARY_PATH"] = os.pathsep.join(
                [*libs, *([env["LD_LIBRARY_PATH"]] if env.get("LD_LIBRARY_PATH") else [])]
            )
        self._log_file = open(self.log_path, "wb")  # noqa: SIM115 - closed in stop()
        try:
            self.proc = subprocess.Popen(
                self.command_line(),
                cwd=self.home,
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=self._log_file,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # a Ctrl-C in the terminal is for Python, not the server
                preexec_fn=_death_signal_preexec(signal.SIGINT),
                close_fds=True,
            )
        except OSError as exc:
            self._log_file.close()
            raise ServerStartError(f"could not start {self.binary}: {exc}") from exc
        with open(self.home / _OWNER_FILE, "w") as f:
            f.write(f"{os.getpid()} {self.proc.pid}\n")
        self._finalizer = weakref.finalize(
            self, _stop_child, self.proc, self.folder, self.stop_grace_s
        )
        log.info(
            "started rcssserver3d (pid %d): agents on port %d, monitors on port %d, config in %s",
            self.proc.pid,
            self.agent_port,
            self.monitor_port,
            self.folder,
        )

    def check_alive(self) -> None:
        """Raise :class:`ServerStartError` (with the log tail) if the server has exited."""
        if self.proc is None:
            raise ServerStartError("server not started")
        code = self.proc.poll()
        if code is not None:
            raise ServerStartError(
                f"rcssserver3d exited with code {code} (command: {' '.join(self.command_line())}). "
                f"Its output ends with:\n{self.log_tail()}"
            )

    def wait_exit(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for the process to exit; True if it has (used to pace
        readiness polling: the wait ends early if the server dies)."""
        if self.proc is None:
            return True
        try:
            self.proc.wait(timeout)
            return True
        except subprocess.TimeoutExpired:
            return False

    def log_tail(self, max_chars: int = 3000) -> str:
        """The end of the server's output (empty if there is none)."""
        if self.folder is None:
            return ""
        try:
            with open(self.log_path, "rb") as f:
                f.seek(0, os.SEEK_END)
                size = f.tell()
                f.seek(max(0, size - max_chars))
                return f.read().decode("latin-1")
        except OSError:
            return ""

    def stop(self) -> int | None:
        """Stop the server (SIGINT, then SIGKILL after the grace period), delete the folder.
        Idempotent. Returns the exit code (``None`` if it was never started)."""
        if self._finalizer is not None:
            self._finalizer()  # runs _stop_child once, then detaches
            self._finalizer = None
        elif self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)
        self.folder = None
        if self._log_file is not None:
            self._log_file.close()
            self._log_file = None
        return None if self.proc is None else self.proc.returncode

    def __enter__(self) -> ServerProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def describe(self) -> dict[str, object]:
        return {
            "binary": self.binary,
            "pid": self.pid,
            "agent_port": self.agent_port,
            "monitor_port": self.monitor_port,
            "config": None if self.folder is None else str(self.script_path),
        }


def wait_for_port(
    host: str,
    port: int,
    timeout_s: float,
    server: ServerProcess | None = None,
    poll_s: float = 0.02,
) -> socket.socket:
    """Connect to ``host:port``, retrying until it accepts or ``timeout_s`` passes.

    Readiness is polled: between attempts it waits on the server process (so a server that
    dies is reported at once, with its log tail) or, without one, for ``poll_s``.

    Raises:
        ServerStartError: the server exited, or the port did not accept within ``timeout_s``.
    """

    def between() -> None:
        if server is None:
            time.sleep(poll_s)
        elif server.wait_exit(poll_s):
            server.check_alive()  # it exited: raises with its output

    if server is not None:
        server.check_alive()
    try:
        return connect(
            host, port, timeout=max(0.1, min(2.0, timeout_s)), retry_s=timeout_s, between=between
        )
    except OSError as exc:  # refused while starting up (or a wrong port)
        tail = "" if server is None else f" Server output:\n{server.log_tail()}"
        raise ServerStartError(
            f"nothing accepted connections on {host}:{port} within {timeout_s:.1f} s ({exc}).{tail}"
        ) from None

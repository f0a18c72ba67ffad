"""YADE scripts run in YADE processes that are kept and reused: ``run(script, cwd, log, timeout)``.

A YADE start costs about 1.9 CPU-s (its Python and plugins load), more than a collision or a
read-back probe itself, and a comparison runs a few YADE scripts a scene (two read-back probes,
the run). A session is one ``yade -n -j1`` process that runs the scripts it is sent one after
another, each as ``yade -x`` would run it: in its own folder, as ``__main__`` with YADE's globals
afresh (the previous script's names gone), its output and errors into its own log, then
``O.reset()``. A script that raises, exits, or outlives its timeout ends its process (so that no
state of a failed run reaches the next script), and the next script starts a fresh one. Idle
sessions wait in a shared list, so that concurrent runs (the job pool's threads) each hold their
own; all end when the program does.

``run`` returns the script's exit code (0, or 1 for an uncaught Python error, as ``yade -x``
gives), or None when it timed out; a YADE that crashed gives its negative signal number.
"""
from __future__ import annotations

import atexit
import json
import os
import select
import signal
import subprocess
import threading
import time
from pathlib import Path

# The program YADE runs in a session: reads one request a line on stdin, answers on the file
# descriptor YADE_SESSION_FD. Kept to what `yade -x SCRIPT` gives a script.
_SERVER = r'''
def _serve():
    import __main__, json, os, sys, traceback
    answer = os.fdopen(int(os.environ["YADE_SESSION_FD"]), "w")
    names = {k: v for k, v in __main__.__dict__.items() if k != "_serve"}  # what -x gives a script
    answer.write("ready\n"); answer.flush()
    for line in sys.stdin:
        req = json.loads(line)
        sys.stdout.flush(); sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
        log = os.open(req["log"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(log, 1); os.dup2(log, 2); os.close(log)
        rc, g = 0, __main__.__dict__
        try:
            os.chdir(req["cwd"])
            g.clear(); g.update(names); g["__file__"] = req["script"]
            exec(compile(open(req["script"]).read(), req["script"], "exec"), g)
        except SystemExit as e:
            rc = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except BaseException:
            traceback.print_exc()
            rc = 1
        sys.stdout.flush(); sys.stderr.flush()
        os.dup2(saved[0], 1); os.dup2(saved[1], 2); os.close(saved[0]); os.close(saved[1])
        g.clear(); g.update(names)
        names["O"].reset()
        answer.write(json.dumps({"rc": rc}) + "\n"); answer.flush()


_serve()
'''

START_TIMEOUT = 120.0    # [s] for a session's YADE to start


class SessionError(RuntimeError):
    pass


class _Session:
    """One YADE process and the pipe it answers on."""

    def __init__(self):
        read_fd, write_fd = os.pipe()
        server = Path(os.environ.get("TMPDIR", "/tmp")) / f"yade_session_{os.getpid()}_{id(self)}.py"
        server.write_text(_SERVER)
        env = dict(os.environ, OMP_NUM_THREADS="1", YADE_SESSION_FD=str(write_fd))
        try:
            self.proc = subprocess.Popen(["yade", "-n", "-j1", "-x", str(server)], stdin=subprocess.PIPE,
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, text=True,
                                         pass_fds=(write_fd,), start_new_session=True, env=env)
        finally:
            os.close(write_fd)
        self._answers = os.fdopen(read_fd, "r")
        try:
            if self._answer(START_TIMEOUT) != "ready":
                raise SessionError("yade did not start the session")
        except (SessionError, OSError):
            self.close()
            raise
        finally:
            server.unlink(missing_ok=True)

    def _answer(self, timeout: float) -> str | None:
        """The next line the session writes, or None after timeout seconds; SessionError when the
        process has ended."""
        ready, _, _ = select.select([self._answers], [], [], timeout)
        if not ready:
            return None
        line = self._answers.readline()
        if not line:
            raise SessionError(f"yade ended (exit {self.proc.wait()})")
        return line.strip()

    def run(self, script: str, cwd: Path, log: Path, timeout: float) -> int | None:
        self.proc.stdin.write(json.dumps({"script": script, "cwd": str(cwd), "log": str(log)}) + "\n")
        self.proc.stdin.flush()
        line = self._answer(timeout)
        if line is None:
            self.close()
            return None
        return int(json.loads(line)["rc"])

    def close(self) -> None:
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        self.proc.wait()
        self._answers.close()
        if self.proc.stdin:
            self.proc.stdin.close()


_idle: list[_Session] = []
_lock = threading.Lock()


def run(script: str, cwd: Path, log: Path, timeout: float) -> int | None:
    """Runs ``script`` (a file name in ``cwd``) as `yade -n -j1 -x script` would, its output into
    ``log``; the exit code, None when it timed out (the module doc)."""
    with _lock:
        session = _idle.pop() if _idle else None
    t0 = time.monotonic()
    try:
        if session is None:
            session = _Session()
        rc = session.run(script, Path(cwd).resolve(), Path(log).resolve(), max(timeout - (time.monotonic() - t0), 1.0))
    except (SessionError, OSError, BrokenPipeError) as e:
        if session is not None:
            rc = session.proc.poll()
            session.close()
        else:
            rc = None
        with open(log, "a") as f:
            f.write(f"\nyade session: {e}\n")
        return rc if rc not in (None, 0) else 1
    if rc is None:
        return None
    if rc == 0:
        with _lock:
            _idle.append(session)
    else:
        session.close()      # a failed script leaves nothing behind for the next one
    return rc


@atexit.register
def close_all() -> None:
    """Ends every idle session (a running one ends with its caller)."""
    with _lock:
        while _idle:
            _idle.pop().close()

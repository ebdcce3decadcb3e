"""New Python processes without a new interpreter's imports, for tests that run many short ones.

Starting Python and importing numpy, scipy, numba and symsphere cost about a CPU-second per process, more
than many a test's own work in it (a short doc page, a CLI run signalled while it writes).  A server
process imports them once and forks a child per run: a new process (its own pid, signals, exit status and
file descriptors) that has imported nothing else and run no kernel, that runs ``python ARGV`` in *folder*
as the interpreter would (``-c CODE``, ``-m MODULE`` or a script, then the arguments), its output in files.
One server per pytest(-xdist) worker, started at first use, one child at a time.  Where ``os.fork`` does not
exist the children are ordinary subprocesses.
"""

from __future__ import annotations

import atexit
import functools
import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_SERVER = r"""
import json, os, runpy, sys, traceback, types
import numpy, scipy.stats, numba, symsphere, symsphere.stats  # before any fork: what the children share


def run(argv, folder, outputs):
    os.chdir(folder)
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    for fd, path in enumerate(outputs, start=1):
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
    sys.stdin = open(0, closefd=False)
    sys.stdout = open(1, "w", closefd=False)
    sys.stderr = open(2, "w", buffering=1, closefd=False)
    code = 0
    try:
        if argv[0] == "-c":  # python -c CODE ARGS: sys.path[0] is the working folder
            sys.argv = argv[:1] + argv[2:]
            sys.path[0] = ""
            main = sys.modules["__main__"] = types.ModuleType("__main__")
            exec(compile(argv[1], "<string>", "exec"), main.__dict__)
        elif argv[0] == "-m":  # python -m MODULE ARGS
            sys.argv = argv[1:]
            sys.path[0] = os.getcwd()
            runpy.run_module(argv[1], run_name="__main__", alter_sys=True)
        else:  # python SCRIPT ARGS: sys.path[0] is the script's folder
            sys.argv = list(argv)
            sys.path[0] = os.path.dirname(os.path.abspath(argv[0]))
            runpy.run_path(argv[0], run_name="__main__")
    except SystemExit as stop:  # as the interpreter exits: None 0, an int itself, anything else printed and 1
        if stop.code is None or isinstance(stop.code, int):
            code = stop.code or 0
        else:
            print(stop.code, file=sys.stderr)
            code = 1
    except BaseException:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


for line in sys.stdin:
    request = json.loads(line)
    pid = os.fork()
    if pid == 0:
        try:
            run(request["argv"], request["folder"], request["outputs"])
        finally:
            os._exit(1)
    print(pid, flush=True)
    _, status = os.waitpid(pid, 0)
    print(os.waitstatus_to_exitcode(status), flush=True)
"""


class _Server:
    def __init__(self):
        self.process = subprocess.Popen([sys.executable, "-c", _SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.buffer = b""
        self.current = None  # the child whose exit status the server will report next
        atexit.register(self.stop)

    def start(self, child, request):
        """Send *request* for *child*; a previous child still running (its test failed) is killed first."""
        if self.current is not None and self.current.returncode is None:
            self.current.kill()
            self.current.wait()
        self.current = child
        self.send(request)
        return int(self.line())

    def send(self, request):
        self.process.stdin.write((json.dumps(request) + "\n").encode())
        self.process.stdin.flush()

    def line(self, timeout=None):
        """The server's next line, or None if none came within *timeout* seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        fd = self.process.stdout.fileno()
        while b"\n" not in self.buffer:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not select.select([fd], [], [], left)[0]:
                return None
            chunk = os.read(fd, 4096)
            if not chunk:
                raise RuntimeError(f"the fork server ended (exit status {self.process.wait()})")
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line.decode()

    def stop(self):
        self.process.stdin.close()
        self.process.wait(timeout=60)


@functools.cache
def _server():
    return _Server()


class Child:
    """``python *argv`` in *folder*, started at once: like a ``subprocess.Popen`` with text stdout and stderr
    pipes (``pid``, ``poll``, ``send_signal``, ``wait``, ``communicate``, ``returncode``)."""

    def __init__(self, argv, folder):
        self.args = [sys.executable, *argv]
        self.returncode = None
        self._folder = tempfile.mkdtemp(prefix="fresh-process-")
        self._outputs = [os.path.join(self._folder, name) for name in ("stdout", "stderr")]
        if not hasattr(os, "fork"):  # pragma: no cover - e.g. Windows
            self._popen = subprocess.Popen(
                self.args, cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            )
            self.pid = self._popen.pid
            return
        self._popen = None
        self.pid = _server().start(self, {"argv": list(argv), "folder": str(folder), "outputs": self._outputs})

    def poll(self):
        return self.wait(timeout=0, polling=True)

    def wait(self, timeout=None, polling=False):
        if self.returncode is None:
            if self._popen is not None:  # pragma: no cover
                try:
                    self.returncode = self._popen.wait(timeout)
                except subprocess.TimeoutExpired:
                    if not polling:
                        raise
            else:
                line = _server().line(timeout)
                if line is None:
                    if polling:
                        return None
                    raise subprocess.TimeoutExpired(self.args, timeout)
                self.returncode = int(line)
        return self.returncode

    def send_signal(self, signum):
        if self.returncode is None:
            os.kill(self.pid, signum)

    def kill(self):
        self.send_signal(signal.SIGKILL)

    def communicate(self, timeout=None):
        if self._popen is not None:  # pragma: no cover
            out, err = self._popen.communicate(timeout=timeout)
            self.returncode = self._popen.returncode
            return out, err
        self.wait(timeout)
        out, err = (Path(path).read_text(encoding="utf-8", errors="replace") for path in self._outputs)
        for path in self._outputs:
            os.unlink(path)
        os.rmdir(self._folder)
        return out, err


def run(argv, folder, timeout=600):
    """``python *argv`` in *folder* to its end: a ``subprocess.CompletedProcess`` with text stdout and stderr;
    after *timeout* seconds the child is killed and ``subprocess.TimeoutExpired`` raised, as by
    ``subprocess.run``."""
    child = Child(argv, folder)
    try:
        out, err = child.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        child.kill()
        child.communicate()
        raise
    return subprocess.CompletedProcess(child.args, child.returncode, out, err)

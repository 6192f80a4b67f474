"""The ``flexshaft`` command's watchdog: Ctrl-C or SIGTERM ends it within seconds, whatever it does.

Python runs a signal handler only between two bytecodes, and the long native calls flexshaft
makes - LAPACK's dense eigen-solves, OCCT's booleans - hold the interpreter lock while they run:
the handler, and every other Python thread, waits until they return (a SIGTERM waited 150 s).
So the command runs its work in a child process, and the process the user started only watches it:

- a signal (SIGINT, SIGTERM) to the command is passed on to the work, which stops at its next
  bytecode as any Python program does: writes clean up, one line on stderr, exit 130 or 143;
- if the work has not ended :data:`GRACE_S` later it is inside a native call: the watchdog kills it
  and every process it started (a sweep's workers), removes the temporary files of the writes it
  had in flight (the work tells it of each, see :func:`flexshaft.system.atomic.in_flight`), prints the
  one line itself and exits 130 (SIGINT) or 143 (SIGTERM); a second signal skips the grace;
- the work dies with the watchdog (a ``kill -9`` of the command takes both), and a signal that
  reaches the work twice (Ctrl-C at a terminal reaches every process of the job) acts once; a
  sweep's worker processes leave the signal to the work, which stops them.

The exit code and the output are the work's own otherwise. Only the command does this
(:func:`flexshaft.cli.main` without arguments, as ``flexshaft`` and ``python -m flexshaft`` call
it); ``main(argv)`` from Python runs in the caller's process, and ``FLEXSHAFT_WATCHDOG=0`` turns
the watchdog off (for a debugger or a profiler).
"""

from __future__ import annotations

import contextlib
import os
import re
import select
import signal
import sys
import time

__all__ = ["GRACE_S", "Terminated", "supervise", "stopping", "received", "is_stop"]

#: Seconds the work has, after a signal, to stop by itself before the watchdog kills it.
GRACE_S = 2.0
#: The signals that stop the command, and the exit code and line of each.
_STOPS = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated")}
#: A temporary file of :func:`flexshaft.system.atomic.atomic_write_bytes`: ``.NAME.<pid>.<random>.tmp``.
_TEMP_NAME = re.compile(rb"\..+\.[0-9]+\.[^/]*\.tmp")


class Terminated(BaseException):
    """SIGTERM, raised where the program is so that writes clean up as for Ctrl-C."""


_owner: int | None = None  # the process whose handlers act (forked workers inherit them, and ignore them)
_received: list[int] = []  # the signal that stopped this process, once it came


def _stop(signum, frame):  # noqa: ARG001 - signal handler signature
    """SIGINT raises KeyboardInterrupt, SIGTERM :class:`Terminated`: the first one, in the owner only."""
    if os.getpid() != _owner or _received:
        return  # a worker process (its parent stops it), or a second signal while the first one acts
    _received.append(signum)
    raise KeyboardInterrupt if signum == signal.SIGINT else Terminated()


def received() -> int | None:
    """The signal (SIGINT or SIGTERM) that is stopping this process, or None."""
    return _received[0] if _received else None


def is_stop(err: BaseException) -> bool:
    """True when ``err`` is the exception a received SIGINT or SIGTERM raised (not one code raised)."""
    return received() is not None and isinstance(err, (KeyboardInterrupt, Terminated))


@contextlib.contextmanager
def stopping(*, ending: bool = False):
    """SIGTERM raises :class:`Terminated` and SIGINT KeyboardInterrupt, once, for the block.

    A signal the process was started with ignored (a background job's SIGINT) stays ignored. The
    previous handlers come back at the end - unless ``ending`` (the command's own process, which
    exits next) and a signal came: a late second one then stays ignored too.
    """
    global _owner
    _owner = os.getpid()
    del _received[:]
    previous = {}
    for sig in _STOPS:
        if signal.getsignal(sig) is not signal.SIG_IGN:
            previous[sig] = signal.signal(sig, _stop)
    try:
        yield
    finally:
        if not (ending and _received):
            for sig, handler in previous.items():
                signal.signal(sig, handler)


# --- the watchdog ------------------------------------------------------------------------------------


def supervise() -> int | None:
    """Run the command's work in a child process and watch it.

    Returns
    -------
    int or None
        In the watchdog: the exit code, once the work has ended. In the work (the child), or
        where there is no watchdog (``FLEXSHAFT_WATCHDOG=0``, no ``fork``): None - go on and do
        the work.
    """
    if os.environ.get("FLEXSHAFT_WATCHDOG", "1").strip() == "0" or not hasattr(os, "fork"):
        return None
    stops = [s for s in _STOPS if signal.getsignal(s) is not signal.SIG_IGN]
    watched = [*stops, signal.SIGCHLD]
    wake_r, wake_w = os.pipe()  # the signals, written by the interpreter's C handler (no GIL needed)
    temp_r, temp_w = os.pipe()  # the work's temporary files, as it creates and finishes them
    for fd in (wake_r, wake_w, temp_r):
        os.set_blocking(fd, False)
    sys.stdout.flush()
    sys.stderr.flush()
    # Held back over the fork: neither side acts on a signal before its handlers are in place.
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, watched)
    watchdog = os.getpid()
    pid = os.fork()
    if pid == 0:  # the work
        os.close(wake_r)
        os.close(wake_w)
        os.close(temp_r)
        _die_with(watchdog)
        from .atomic import report_temporaries

        report_temporaries(_reporter(temp_w))
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        return None
    os.close(temp_w)
    for sig in watched:
        signal.signal(sig, _wake)
    signal.set_wakeup_fd(wake_w, warn_on_full_buffer=False)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    return _watch(pid, wake_r, temp_r)


def _wake(signum, frame):  # noqa: ARG001 - signal handler signature
    """Nothing: the signal's number reaches the watchdog's loop through the wakeup pipe."""


def _die_with(watchdog: int) -> None:
    """Have the kernel kill this process when the watchdog dies (Linux; elsewhere nothing)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != watchdog:  # it died before the request: so does the work
        os._exit(128 + signal.SIGKILL)


def _reporter(fd: int):
    """The work's side of the temporary-file channel: ``+path`` or ``-path``, NUL-terminated."""

    def report(live: bool, path: str) -> None:
        try:
            os.write(fd, (b"+" if live else b"-") + os.fsencode(path) + b"\0")
        except OSError:
            pass  # no watchdog to tell any more (it is gone, and the work goes with it)

    return report


def _read_temps(fd: int, pending: bytes, temps: set[bytes]) -> bytes:
    """Read what the work has said about its temporary files; returns the incomplete tail."""
    while True:
        try:
            chunk = os.read(fd, 65536)
        except BlockingIOError:
            break
        if not chunk:
            break
        pending += chunk
    *records, pending = pending.split(b"\0")
    for r in records:
        (temps.add if r[:1] == b"+" else temps.discard)(r[1:])
    return pending


def _signals(fd: int) -> list[int]:
    try:
        return list(os.read(fd, 512))
    except BlockingIOError:
        return []


def _watch(pid: int, wake: int, temp: int) -> int:
    """The watchdog's loop: pass a signal on, wait for the work, kill it when it is stuck."""
    temps: set[bytes] = set()
    pending = b""
    stop = None  # the signal the command is stopping for
    deadline = None
    status = None
    while status is None:
        timeout = None if deadline is None else max(0.0, deadline - time.monotonic())
        ready, _, _ = select.select([wake, temp], [], [], timeout)
        if temp in ready:
            pending = _read_temps(temp, pending, temps)
        for sig in _signals(wake) if wake in ready else ():
            if sig not in _STOPS:
                continue  # SIGCHLD: the work may have ended (below)
            if stop is None:
                stop, deadline = sig, time.monotonic() + GRACE_S
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, sig)
            else:
                deadline = time.monotonic()  # a second signal: no more waiting
        status = _ended(pid)
        if status is None and deadline is not None and time.monotonic() >= deadline:
            _kill_tree(pid)
            status = os.waitpid(pid, 0)[1]
    _read_temps(temp, pending, temps)
    code = os.waitstatus_to_exitcode(status)
    if code >= 0:
        return code  # the work ended by itself (a signal's own clean-up included) and said why
    _remove(temps)
    if stop is not None:
        os.write(2, f"flexshaft: {_STOPS[stop][1]}\n".encode())
        return _STOPS[stop][0]
    # Killed by a signal not sent here (the out-of-memory killer, a crash): the command ends alike.
    with contextlib.suppress(OSError, ValueError):
        signal.signal(-code, signal.SIG_DFL)
    os.kill(os.getpid(), -code)
    return 128 - code


def _ended(pid: int):
    """The work's wait status once it has ended, else None."""
    done, status = os.waitpid(pid, os.WNOHANG)
    return status if done else None


def _kill_tree(pid: int) -> None:
    """SIGKILL the work and every process under it (found in /proc before the first is killed)."""
    everyone = [pid, *_descendants(pid)]
    for p in everyone:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(p, signal.SIGKILL)


def _descendants(pid: int) -> list[int]:
    """Every process under ``pid``, from /proc (empty where there is none)."""
    children: dict[int, list[int]] = {}
    try:
        entries = [e.name for e in os.scandir("/proc") if e.name.isdigit()]
    except OSError:
        return []
    for name in entries:
        try:
            with open(f"/proc/{name}/stat", "rb") as fh:
                fields = fh.read().rsplit(b")", 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(name))
        except (OSError, IndexError, ValueError):
            continue  # gone meanwhile
    out, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), ()):
            out.append(child)
            todo.append(child)
    return out


def _remove(temps: set[bytes]) -> None:
    """Remove the work's temporary files still there: regular files named as the writer names them."""
    import stat

    for path in temps:
        if not _TEMP_NAME.fullmatch(os.path.basename(path)):
            continue
        with contextlib.suppress(OSError):
            if stat.S_ISREG(os.lstat(path).st_mode):
                os.unlink(path)

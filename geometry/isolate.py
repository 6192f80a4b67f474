"""Running foreign native code (gmsh) in a forked child, so that its crash or hang cannot take the
caller down with it.

A mesher's C++ core can crash (SIGSEGV) or loop on a damaged shape, and neither can be caught in
the process it happens in. :func:`run_isolated` runs the work in a forked child that inherits the
imported libraries and the caller's data (a fork costs ~10 ms; nothing is imported again):

- a crash of the child, or its running beyond ``timeout`` seconds, is one ModelError (the caller
  says what was being done);
- the child's stdout and stderr go to /dev/null (a library's own diagnostics never reach the user);
- its address space is capped (``memory`` bytes above what it inherits), so native code that
  allocates without end gets a MemoryError, reported as a failure, instead of the machine's memory;
- the work reports its stages through ``send``: the parent passes them on to ``on_message`` as they
  come; its result (picklable: plain arrays and numbers) comes back over a pipe.

The pattern is :mod:`flexshaft.io.measured.isolate`'s (geometry cannot import flexshaft.io); where
there is no ``fork`` (Windows), and in a daemonic process (a ``multiprocessing.Pool`` worker, which
may start none), the work runs in the caller's process.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import time
from collections.abc import Callable

from flexshaft.errors import ModelError

__all__ = ["run_isolated"]

_POLL_S = 0.2  # how often the parent looks whether a silent child is still alive
_ERROR_FIELDS = ("message", "file", "component", "field", "value", "unit", "valid", "has_value")


def _cap_memory(memory: int | None) -> None:
    """Limit the child's address space (Linux) to what it has plus ``memory`` bytes."""
    if memory is None:
        return
    try:
        import resource

        with open("/proc/self/statm") as fh:
            have = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        want = have + int(memory)
        if hard == resource.RLIM_INFINITY or want < hard:
            if soft == resource.RLIM_INFINITY or want < soft:
                resource.setrlimit(resource.RLIMIT_AS, (want, hard))
    except (ImportError, OSError, ValueError):
        pass  # no /proc, no limits: the child runs uncapped, as the caller would


def _child(work, conn, memory) -> None:
    """In the child: run ``work(send)``, send its result (or its error) to the parent."""
    try:
        import faulthandler
        import gc

        gc.freeze()  # the inherited heap is never collected here: a failure's collection stays quick
        faulthandler.disable()  # a crash is the parent's to report, in one line
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        _cap_memory(memory)
        try:
            result = work(lambda *message: conn.send(("message", message)))
        except ModelError as err:
            fields = {k: getattr(err, k) for k in _ERROR_FIELDS}
            try:
                pickle.dumps(fields["value"])
            except Exception:  # noqa: BLE001 - a value that cannot travel is shown as text
                fields["value"] = repr(fields["value"])
            conn.send(("error", fields))
            return
        except BaseException as err:  # noqa: BLE001 - a native library's failure, reported by the parent
            conn.send(("failed", f"{type(err).__name__}: {err}".strip()))
            return
        conn.send(("result", result))
    finally:
        conn.close()


def _died(proc) -> str:
    proc.join(1.0)
    code = proc.exitcode
    import signal

    try:
        how = f"signal {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit code {code}"
    except ValueError:
        how = f"signal {-code}"
    return f"crashed ({how})"


def run_isolated(
    work: Callable[[Callable], object],
    *,
    timeout: float,
    error: Callable[[str], ModelError],
    on_message: Callable | None = None,
    memory: int | None = None,
):
    """``work(send)`` run in a forked child; its result, or one ModelError.

    Parameters
    ----------
    work : callable
        ``work(send) -> result``. ``send(*message)`` passes a message (picklable values) to
        ``on_message(*message)`` in the caller; ``result`` must be picklable. A ModelError it
        raises is raised again in the caller as it was.
    timeout : float
        Seconds the child may run before it is stopped (from its start).
    error : callable
        ``error(reason) -> ModelError`` for a child that crashed (``"crashed (signal SIGSEGV)"``),
        ran out of time (``"took more than 600 s"``) or raised something other than a ModelError
        (``"failed: RuntimeError: ..."``): the caller names what was being done and what is valid.
    on_message : callable, optional
        Receives the work's messages as they come.
    memory : int, optional
        Bytes of address space the child may add to what it inherits; None: uncapped.

    Raises
    ------
    ModelError
        The work's own, or ``error(reason)``.
    """
    import multiprocessing

    def deliver(*message) -> None:
        if on_message is not None:
            on_message(*message)

    if not hasattr(os, "fork") or multiprocessing.current_process().daemon:
        try:
            return work(deliver)
        except ModelError:
            raise
        except Exception as err:  # noqa: BLE001 - the same report as from a child
            raise error(f"failed: {type(err).__name__}: {err}".strip()) from None
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(work, send, memory), daemon=True)
    deadline = time.monotonic() + timeout
    try:
        proc.start()
        send.close()  # the child's end: EOF here when the child is gone
        while True:
            while not recv.poll(min(_POLL_S, max(0.0, deadline - time.monotonic()))):
                if not proc.is_alive() and not recv.poll(0):
                    raise error(_died(proc))
                if time.monotonic() > deadline:
                    raise error(f"took more than {timeout:.3g} s")
            if time.monotonic() > deadline:  # a child that keeps talking is stopped on time too
                raise error(f"took more than {timeout:.3g} s")
            try:
                kind, payload = recv.recv()
            except (EOFError, OSError):
                raise error(_died(proc)) from None
            if kind == "message":
                deliver(*payload)
            elif kind == "error":
                raise ModelError(**payload)
            elif kind == "failed":
                raise error(f"failed: {payload}")
            else:
                return payload
    finally:
        recv.close()
        with contextlib.suppress(Exception):
            send.close()
        if proc.is_alive():
            proc.kill()
        proc.join()
        proc.close()

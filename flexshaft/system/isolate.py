"""Foreign native code run in a forked child, so that its crash or hang cannot take the caller down
with it.

A foreign library's C or C++ core can crash (SIGSEGV) or loop forever on damaged input: HDF5's C
library on a corrupted attribute, asammdf's C extension on a corrupted MDF 4 block (random byte
flips in a small file found both within 200 tries), gmsh on a damaged shape. Neither can be caught
in the process it happens in. :func:`run_isolated` runs the work in a forked child that inherits
the imported libraries, open files and the caller's data (a fork costs ~10 ms; nothing is imported
again):

- a crash of the child, its running beyond ``timeout`` seconds, or an exception other than a
  ModelError, is one ModelError that the caller builds from a :class:`Failure` (it says what was
  being done and what is valid); a ModelError of the work is raised in the caller as it was;
- the child's stdout and stderr go to /dev/null (a library's own diagnostics never reach the user),
  its fault handler is off (a crash is the parent's to report, in one line) and it dumps no core (a
  crash under ``ulimit -c unlimited`` left a core file of the child's whole heap, ~400 MB with
  build123d loaded, in the user's working directory);
- its address space is capped (``memory`` bytes above what it inherits), so native code that
  allocates without end gets a MemoryError instead of the machine's memory;
- the work reports its stages through ``send``: the parent passes them on to ``on_message`` as they
  come;
- its result (anything picklable) comes back over a pipe, pickled with protocol 5: the bytes of its
  contiguous arrays travel apart from the pickle, read straight from the pipe into a numpy buffer of
  the parent's that the unpickled array then uses (no second copy; the child's memory is freed when
  it ends, so the peak is the child's result and the parent's copy together). A pipe moves some
  2 GB/s here; ``multiprocessing``'s own ``recv_bytes_into`` gathered a message in pieces first, at
  a sixth of that, and shared memory (a memfd) costs more than the pipe in page faults alone. Work
  with much to return does better to return where its data lie (:mod:`flexshaft.measurement.files` does).

Where there is no ``fork`` (Windows), and in a daemonic process (a ``multiprocessing.Pool`` worker,
which may start none), the work runs in the caller's process; an exception other than a ModelError
is then the same failure as from a child.

Here, in the base stage, so that both the measured-file readers (:mod:`flexshaft.measurement.files`) and
the CAD side (:mod:`geometry.meshing`, which may import only flexshaft's base) use the one pattern.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import ModelError

try:  # here, not in the child: an extension module loaded in each child cost 0.5 ms of every run
    import resource
except ImportError:  # Windows: no limits (and no fork)
    resource = None

__all__ = ["Failure", "run_isolated"]

_POLL_S = 0.2  # how often the parent looks whether a silent child is still alive
_PIECE = 1 << 20  # bytes written or read at a time: the parent checks its deadline between them
_ERROR_FIELDS = ("message", "file", "component", "field", "value", "unit", "valid", "has_value")


@dataclass(frozen=True)
class Failure:
    """How the work ended when it gave neither a result nor a ModelError: what ``error`` is given.

    Attributes
    ----------
    kind : str
        ``"crashed"`` (the child died: a signal, or an exit without a result), ``"timeout"`` (it ran
        beyond the time allowed) or ``"failed"`` (it raised something other than a ModelError).
    detail : str
        How: ``"signal SIGSEGV"`` or ``"exit code 1"`` for a crash, the exception's type and text for
        a failure (``"MemoryError: "`` is the memory cap), ``""`` for a timeout.
    limit : float
        The seconds the work was allowed, s.
    """

    kind: str
    detail: str
    limit: float

    @property
    def reason(self) -> str:
        """One phrase for a message: ``crashed (signal SIGSEGV)``, ``took more than 600 s``,
        ``failed: RuntimeError: ...``."""
        if self.kind == "timeout":
            return f"took more than {self.limit:.3g} s"
        if self.kind == "crashed":
            return f"crashed ({self.detail})"
        return f"failed: {self.detail}"


def _described(err: BaseException) -> str:
    return f"{type(err).__name__}: {err}".strip()


def _cap_memory(memory: int | None) -> None:
    """Limit the child's address space (Linux) to what it has plus ``memory`` bytes."""
    if memory is None or resource is None:
        return
    try:
        with open("/proc/self/statm") as fh:
            have = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        want = have + int(memory)
        if hard == resource.RLIM_INFINITY or want < hard:
            if soft == resource.RLIM_INFINITY or want < soft:
                resource.setrlimit(resource.RLIMIT_AS, (want, hard))
    except (ImportError, OSError, ValueError):
        pass  # no /proc, no limits: the child runs uncapped, as the caller would


def _no_core_dump() -> None:
    """No core file of the child's crash (its soft limit 0; the parent's own limit stays)."""
    if resource is None:
        return
    try:
        resource.setrlimit(resource.RLIMIT_CORE, (0, resource.getrlimit(resource.RLIMIT_CORE)[1]))
    except (OSError, ValueError):
        pass  # no such limit here: the system's own setting stands


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
        _no_core_dump()
        try:
            result = work(lambda *message: conn.send(("message", message)))
            buffers = []
            data = pickle.dumps(result, protocol=5, buffer_callback=buffers.append)
            raws = [b.raw() for b in buffers]  # an array's bytes, not copied
        except ModelError as err:
            fields = {k: getattr(err, k) for k in _ERROR_FIELDS}
            try:
                pickle.dumps(fields["value"])
            except Exception:  # noqa: BLE001 - a value that cannot travel is shown as text
                fields["value"] = repr(fields["value"])
            conn.send(("error", fields))
            return
        except BaseException as err:  # noqa: BLE001 - a native library's failure, reported by the parent
            conn.send(("failed", _described(err)))
            return
        conn.send(("result", [r.nbytes for r in raws]))
        conn.send_bytes(data)
        for r in raws:
            _write_all(conn.fileno(), r)  # PickleBuffer.raw(): one-dimensional bytes
    finally:
        conn.close()


def _write_all(fd: int, view: memoryview) -> None:
    """All of ``view`` to the pipe ``fd`` (raw: the parent reads exactly as many bytes)."""
    done = 0
    while done < len(view):
        done += os.write(fd, view[done : done + _PIECE])


def _exit_status(proc) -> str:
    """How the child ended: ``signal SIGSEGV``, ``exit code 1``."""
    proc.join(1.0)
    code = proc.exitcode
    import signal

    try:
        return (
            f"signal {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit code {code}"
        )
    except ValueError:
        return f"signal {-code}"


def run_isolated(
    work: Callable[[Callable], object],
    *,
    timeout: float,
    error: Callable[[Failure], ModelError],
    on_message: Callable | None = None,
    memory: int | None = None,
):
    """``work(send)`` run in a forked child; its result, or one ModelError.

    Parameters
    ----------
    work : callable
        ``work(send) -> result``. ``send(*message)`` passes a message (picklable values) to
        ``on_message(*message)`` in the caller; ``result`` must be picklable (its arrays come back
        writeable, their bytes apart from the pickle). A ModelError it raises is raised again in
        the caller as it was (its value as text where it cannot be pickled).
    timeout : float
        Seconds the child may run, from its start, before it is stopped (also while it keeps
        sending), s.
    error : callable
        ``error(failure) -> ModelError`` for a child that crashed, ran out of time or raised
        something other than a ModelError (:class:`Failure`): the caller names what was being done
        and what is valid.
    on_message : callable, optional
        Receives the work's messages as they come.
    memory : int, optional
        Bytes of address space the child may add to what it inherits; None: uncapped.

    Returns
    -------
    object
        What ``work`` returned.

    Raises
    ------
    ModelError
        The work's own, or ``error(failure)``.
    """
    import multiprocessing

    def deliver(*message) -> None:
        if on_message is not None:
            on_message(*message)

    def fail(kind: str, detail: str = "") -> ModelError:
        return error(Failure(kind, detail, timeout))

    if not hasattr(os, "fork") or multiprocessing.current_process().daemon:
        try:
            return work(deliver)
        except ModelError:
            raise
        except Exception as err:  # noqa: BLE001 - the same report as from a child
            raise fail("failed", _described(err)) from None
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(work, send, memory), daemon=True)
    deadline = time.monotonic() + timeout

    def wait() -> None:
        """Until the child's next message is there; its death or the deadline is the one error."""
        while not recv.poll(min(_POLL_S, max(0.0, deadline - time.monotonic()))):
            if not proc.is_alive() and not recv.poll(0):
                raise fail("crashed", _exit_status(proc))
            if time.monotonic() > deadline:
                raise fail("timeout")
        if time.monotonic() > deadline:  # a child that keeps talking is stopped on time too
            raise fail("timeout")

    def take(read):
        """``read()`` of the pipe; its end (the child gone) is the child's crash."""
        try:
            return read()
        except (EOFError, OSError, multiprocessing.BufferTooShort):
            raise fail("crashed", _exit_status(proc)) from None

    finished = False  # the result whole in hand: the child is then reaped on a thread
    try:
        proc.start()
        send.close()  # the child's end: EOF here when the child is gone
        while True:
            wait()
            kind, payload = take(recv.recv)
            if kind != "message":
                break
            deliver(*payload)
        if kind == "error":
            raise ModelError(**payload)
        if kind == "failed":
            raise fail("failed", payload)
        wait()
        data = take(recv.recv_bytes)
        buffers = []
        import numpy as np  # the work returned arrays: numpy is loaded

        for size in payload:
            out = np.empty(size, dtype=np.uint8)  # writeable, and numpy's huge pages for a large one
            view, done = memoryview(out), 0
            while done < size:
                wait()
                piece = view[done : done + _PIECE]
                got = take(lambda piece=piece: os.readv(recv.fileno(), [piece]))
                if not got:  # the pipe ended early: the child is gone
                    raise fail("crashed", _exit_status(proc))
                done += got
            buffers.append(out)
        finished = True
    finally:
        recv.close()
        with contextlib.suppress(Exception):
            send.close()
        if proc.is_alive():
            proc.kill()  # done with, or failed: its Python exit is not waited for either
        if finished:
            _reap_later(proc)
        else:
            proc.join()
            proc.close()
    return pickle.loads(data, buffers=buffers)


def _reap_later(proc) -> None:
    """Join a child whose result is in hand on a thread of its own: the kernel's tearing down of a
    forked copy of a large process (its page tables, ~10 ms for a few hundred MB) need not hold up
    the caller; the thread collects its exit status, so no zombie is left."""
    import threading

    def reap() -> None:
        with contextlib.suppress(Exception):
            proc.join()
            proc.close()

    threading.Thread(target=reap, name="flexshaft-reaper", daemon=True).start()

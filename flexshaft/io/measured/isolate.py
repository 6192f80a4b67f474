"""Reading a measured file in a child process, so that a foreign reader's native code cannot take the
caller down with it.

HDF5's C library loops forever on some corrupted attributes, and asammdf's C extension can crash
(SIGSEGV) on a corrupted MDF 4 block: random byte flips in a small file found both within 200
tries. Neither can be caught in the process it happens in. So the reading (the format's library
and :func:`~.assemble.collect`) runs in a forked child that inherits the open file and the imported
library (a fork costs ~10 ms; nothing is imported again):

- a crash of the child, or its silence beyond :func:`timeout_s`, is one ModelError naming the file;
- the child's stdout and stderr go to /dev/null (a library's own diagnostics never reach the user);
- its address space is capped (:data:`EXTRA_MEMORY` above what it inherits plus twice the signal
  file's ceiling), so a hostile structure that makes native code allocate without end gets a
  MemoryError, refused as damage, instead of the machine's memory;
- the table comes back over a pipe, each array's bytes straight into the parent's array (the
  child's memory is freed when it ends: the peak is the child's and the parent's copy together).

Where there is no ``fork`` (Windows), and in a daemonic process (a ``multiprocessing.Pool`` worker,
which may start none), the reading runs in the caller's process.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import time

import numpy as np

from ...errors import ModelError
from ...inputs import MB, SIGNALS, ceiling_bytes
from ..signaltable import SignalTable

__all__ = ["EXTRA_MEMORY", "TIMEOUT_S", "SECONDS_PER_MB", "run_isolated", "timeout_s"]

#: Seconds a reading may take at least before it counts as hung (a file of a few MB reads in well
#: under a second; a hung HDF5 read never ends).
TIMEOUT_S = 60.0
#: And per MB of the file: asammdf and h5py read 50-500 MB/s; 5 MB/s is a slow disk's worst.
SECONDS_PER_MB = 0.2
#: Bytes of address space the child may add beyond what it inherits and twice the ceiling (the
#: libraries' own buffers and a record's pieces).
EXTRA_MEMORY = 1 << 30
_POLL_S = 0.2  # how often the parent looks whether a silent child is still alive
_ERROR_FIELDS = ("message", "file", "component", "field", "value", "unit", "valid", "has_value")


def timeout_s(size: int) -> float:
    """Seconds the reading of a file of ``size`` bytes may take."""
    return TIMEOUT_S + SECONDS_PER_MB * size / MB


def _cap_memory() -> None:
    """Limit the child's address space (Linux): what it has, twice the ceiling, :data:`EXTRA_MEMORY`."""
    try:
        import resource

        with open("/proc/self/statm") as fh:
            have = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        want = have + 2 * ceiling_bytes(SIGNALS) + EXTRA_MEMORY
        if hard == resource.RLIM_INFINITY or want < hard:
            if soft == resource.RLIM_INFINITY or want < soft:
                resource.setrlimit(resource.RLIMIT_AS, (want, hard))
    except (ImportError, OSError, ValueError, ModelError):
        pass  # no /proc, no limits: the child reads uncapped, as the caller would


def _child(work, conn) -> None:
    """In the child: run ``work``, send its table (or its ModelError) to the parent."""
    try:
        import faulthandler
        import gc

        gc.freeze()  # the inherited heap is never collected here: a failure's collection stays quick
        faulthandler.disable()  # a crash is the parent's to report, in one line
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        _cap_memory()
        try:
            table = work()
        except ModelError as err:
            fields = {k: getattr(err, k) for k in _ERROR_FIELDS}
            try:
                pickle.dumps(fields["value"])
            except Exception:  # noqa: BLE001 - a value that cannot travel is shown as text
                fields["value"] = repr(fields["value"])
            conn.send(("error", fields))
            return
        arrays = [("time", table.time), *table.columns.items()]
        meta = {
            "keys": list(table.columns),
            "sizes": [int(a.size) for _, a in arrays],
            "units": table.units,
            "rate_hz": table.rate_hz,
            "source": table.source,
            "notes": table.notes,
        }
        conn.send(("table", meta))
        for _, a in arrays:
            conn.send_bytes(np.ascontiguousarray(a, dtype=np.float64))
    finally:
        conn.close()


def _died(path, proc) -> ModelError:
    proc.join(1.0)
    code = proc.exitcode
    import signal

    how = f"signal {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit code {code}"
    return ModelError(
        f"is damaged: its reader crashed on it ({how})",
        file=str(path),
        valid="an undamaged, complete file",
    )


def _wait(path, conn, proc, deadline: float, limit: float) -> None:
    """Until the child's next message is there; a ModelError if it died or stays silent too long."""
    while not conn.poll(_POLL_S):
        if not proc.is_alive():
            if conn.poll(0):
                return
            raise _died(path, proc)
        if time.monotonic() > deadline:
            raise ModelError(
                f"is damaged or too large: reading it took more than {limit:.0f} s",
                file=str(path),
                valid="an undamaged file (a reader that loops on a corrupted structure is stopped)",
            )


def run_isolated(path, size: int, work) -> SignalTable:
    """``work()`` (a :class:`SignalTable` or a ModelError) run in a forked child; see the module docstring."""
    import multiprocessing

    if not hasattr(os, "fork") or multiprocessing.current_process().daemon:
        return work()  # no fork, or a daemonic worker (a multiprocessing pool's), which may have no child
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(work, send), daemon=True)
    limit = timeout_s(size)
    deadline = time.monotonic() + limit
    try:
        proc.start()
        send.close()  # the child's end: EOF here when the child is gone
        try:
            _wait(path, recv, proc, deadline, limit)
            kind, meta = recv.recv()
            if kind == "error":
                raise ModelError(**meta)
            arrays = []
            for n in meta["sizes"]:
                out = np.empty(n)
                _wait(path, recv, proc, deadline, limit)
                got = recv.recv_bytes_into(out)
                if got != out.nbytes:
                    raise _died(path, proc)
                arrays.append(out)
        except (EOFError, OSError):
            raise _died(path, proc) from None
    finally:
        recv.close()
        with contextlib.suppress(Exception):
            send.close()
        if proc.is_alive():
            proc.kill()
        proc.join()
        proc.close()
    time_, *values = arrays
    return SignalTable(
        time=time_,
        columns=dict(zip(meta["keys"], values)),
        units=meta["units"],
        rate_hz=meta["rate_hz"],
        source=meta["source"],
        notes=tuple(meta["notes"]),
    )

"""The C heap tuned around a benchmark's large solves (glibc): freed blocks reused, then handed back.

Kept out of the library (issue 34: no heap tuning inside the numerical code); the benchmarks that
time million-DOF solids wrap their run in :func:`reused_blocks` and call :func:`release_free_heap`
before the eigen-solver's workspace is taken, as flexshaft's solvers themselves did up to then.

An iteration on a million-DOF solid makes and drops tens of arrays of 50-250 MB each (products
with the stiffness, preconditioned blocks, Rayleigh-Ritz updates). glibc serves any block above its
mmap threshold (at most 32 MB) as a fresh mapping and unmaps it when it is freed, so every one of
those arrays is new memory whose pages the kernel faults in and zeroes on first touch: 20 modes of a
1 035 000-DOF PTSS tube spent 76 s of their 230 s in the kernel doing that, and 9 s of 156 s with the
freed blocks kept for reuse. :func:`reused_blocks` keeps them: inside it, no block is mapped on its
own (``M_MMAP_THRESHOLD`` 1 GiB) and the heap's free top is not handed back (``M_TRIM_THRESHOLD``);
on leaving, the thresholds are set to the values glibc's own dynamic rule settles at after freeing a
large block (32 MiB and twice that) and the free memory is handed back (``malloc_trim``). Where the
C library is not glibc (macOS, Windows, musl) it does nothing.

:func:`release_free_heap` hands the freed blocks back at once: glibc keeps blocks up to 32 MB when
freed, for reuse; after an assembly's temporaries that is ~120 MB at 1 M DOFs, which ARPACK's and
LOBPCG's large arrays (fresh mappings) never reuse, so without it they sit in the peak memory beside
the solver's workspace. ~2 ms.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import threading

__all__ = ["reused_blocks", "release_free_heap"]

# mallopt's parameter numbers (glibc's malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
#: Inside :func:`reused_blocks`: no block is mapped on its own below this size.
INSIDE_MMAP_THRESHOLD = 1 << 30
#: On leaving: glibc's largest dynamic mmap threshold (DEFAULT_MMAP_THRESHOLD_MAX on 64-bit) and its
#: trim threshold then (twice that), what a long-running process settles at anyway.
AFTER_MMAP_THRESHOLD = 32 << 20
AFTER_TRIM_THRESHOLD = 64 << 20

_lock = threading.Lock()
_depth = 0


@functools.cache
def _glibc():
    """glibc's (mallopt, malloc_trim), or None."""
    try:
        libc = ctypes.CDLL(None)
        mallopt, trim = libc.mallopt, libc.malloc_trim
    except (OSError, AttributeError, TypeError):  # no such library or function (TypeError: Windows)
        return None
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return mallopt, trim


@contextlib.contextmanager
def reused_blocks():
    """Keep freed large blocks in the heap for reuse while the block runs (module docstring).

    Nested uses (a solver inside an eigen-solver) set the thresholds once, at the outermost.
    """
    global _depth
    libc = _glibc()
    with _lock:
        _depth += 1
        if _depth == 1 and libc is not None:
            libc[0](_M_MMAP_THRESHOLD, INSIDE_MMAP_THRESHOLD)
            libc[0](_M_TRIM_THRESHOLD, 2**31 - 1)
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and libc is not None:
                libc[0](_M_MMAP_THRESHOLD, AFTER_MMAP_THRESHOLD)
                libc[0](_M_TRIM_THRESHOLD, AFTER_TRIM_THRESHOLD)
                libc[1](0)


def release_free_heap() -> None:
    """Hand the C heap's freed blocks back to the operating system (glibc; elsewhere nothing)."""
    libc = _glibc()
    if libc is not None:
        libc[1](0)

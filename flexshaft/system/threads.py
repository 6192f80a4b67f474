"""How many BLAS/OpenMP threads flexshaft's work runs on: one place, every entry point.

flexshaft's dense and sparse work is small or medium (a few hundred to a few
thousand DOFs dense; banded or sparse beyond), and on a machine whose cores are
busy - a laptop with a browser and an IDE open, a CI runner, a sweep's other
workers - multithreaded BLAS threads wait on each other: a 210x210
``scipy.linalg.eig`` took 4.0 s with OpenBLAS's two threads on two busy cores
and 0.036 s with one. ``benchmarks/bench_threads.py`` times the kinds of work
flexshaft does (dense eigensolves up to the dense limit, sparse shift-invert
Lanczos, sparse factorisations, the FRF's stacked solves) idle and busy, with
one and two threads: dense eigen-solves gain up to 1.7x from a second thread
idle and lose busy (several-fold beside another job), ARPACK's steps lose
badly busy, sparse factorisations gain nothing; only a large matrix product
gains idle without losing busy, and flexshaft's sit beside eigen-solves five
times their cost. So the policy is one thread for everything.

Who decides, first match wins:

1. ``threads=`` given to :func:`thread_policy` (the CLI's ``--threads N``);
2. the environment variable ``FLEXSHAFT_THREADS`` (a whole number >= 1);
3. the user's own ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``,
   ``MKL_NUM_THREADS`` or ``BLIS_NUM_THREADS``: flexshaft leaves the libraries
   as the user set them;
4. one thread.

Every public entry point (the functions :mod:`flexshaft` exports, and the CLI)
runs under the policy; on return the caller's thread settings are restored.
Nested calls (a calibration's thousands of modal solves) apply it once, at the
outermost call.
"""

from __future__ import annotations

import functools
import os
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

from ..errors import ModelError

__all__ = ["USER_THREAD_VARIABLES", "requested_threads", "thread_policy", "follows_policy", "cli_threads"]

# The variables with which a user sets the libraries' thread counts themselves (their value wins).
USER_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
MAX_THREADS = 1024  # a sanity ceiling for a typed number, far above any machine flexshaft runs on

F = TypeVar("F", bound=Callable)

_state = threading.local()  # depth of nested policy calls in this thread
_controller = None  # threadpoolctl's view of the loaded libraries, and the sys.modules size it was made at
_controller_modules = -1
_lock = threading.Lock()


def _parse(text: str, source: str) -> int:
    try:
        n = int(text.strip())
    except ValueError:
        raise ModelError(
            "not a whole number", field=source, value=text, valid=f"a whole number from 1 to {MAX_THREADS}"
        ) from None
    if not 1 <= n <= MAX_THREADS:
        raise ModelError(
            "out of range", field=source, value=n, valid=f"a whole number from 1 to {MAX_THREADS}"
        )
    return n


def requested_threads(threads: int | None = None) -> int | None:
    """The thread count the policy asks for, or None where the user's own settings stand.

    Parameters
    ----------
    threads : int, optional
        An explicit count (the CLI's ``--threads``); wins over the environment.

    Returns
    -------
    int or None
        ``threads``, else ``FLEXSHAFT_THREADS``, else None when the user set one of
        :data:`USER_THREAD_VARIABLES`, else 1.

    Raises
    ------
    ModelError
        ``threads`` or ``FLEXSHAFT_THREADS`` is not a whole number from 1 to 1024.
    """
    if threads is not None:
        return _parse(str(threads), "--threads")
    own = os.environ.get("FLEXSHAFT_THREADS")
    if own is not None and own.strip():
        return _parse(own, "FLEXSHAFT_THREADS")
    if any(os.environ.get(var, "").strip() for var in USER_THREAD_VARIABLES):
        return None
    return 1


def _libraries():
    """threadpoolctl's controller of the loaded BLAS/OpenMP libraries (rebuilt when modules were added)."""
    global _controller, _controller_modules
    # numpy's and scipy's BLAS are separate libraries (each wheel ships its own OpenBLAS); load both
    # now, so the limit covers the one a later import would bring.
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    from threadpoolctl import ThreadpoolController

    with _lock:
        # A new extension module may have brought a new library (0.7 ms to rescan, 12 µs to reuse).
        if _controller is None or len(sys.modules) != _controller_modules:
            _controller = ThreadpoolController()
            _controller_modules = len(sys.modules)
        return _controller


@contextmanager
def thread_policy(threads: int | None = None) -> Iterator[int | None]:
    """Run a block under flexshaft's thread policy, restoring the caller's settings after it.

    Parameters
    ----------
    threads : int, optional
        An explicit thread count (see :func:`requested_threads` for who decides otherwise).

    Yields
    ------
    int or None
        The thread count in force for flexshaft's libraries, or None where the user's own
        environment settings were left as they are. Inside an outer policy block an inner
        one without ``threads`` changes nothing.
    """
    depth = getattr(_state, "depth", 0)
    if depth and threads is None:
        _state.depth = depth + 1
        try:
            yield getattr(_state, "count", None)
        finally:
            _state.depth = depth
        return
    n = requested_threads(threads)
    previous = getattr(_state, "count", None)
    _state.depth, _state.count = depth + 1, n
    try:
        if n is None:
            yield None
        else:
            with _libraries().limit(limits=n):
                yield n
    finally:
        _state.depth, _state.count = depth, previous


def follows_policy(func: F) -> F:
    """Decorate a public entry point: it runs under :func:`thread_policy`."""

    @functools.wraps(func)
    def run(*args, **kwargs):
        with thread_policy():
            return func(*args, **kwargs)

    run.__flexshaft_thread_policy__ = True
    return run  # type: ignore[return-value]


def cli_threads(threads: int | None) -> int | None:
    """The CLI's part: settle the thread count before numpy loads, for this process and its children.

    Sets every variable of :data:`USER_THREAD_VARIABLES` (and ``FLEXSHAFT_THREADS``) to the count the
    policy asks for, so that each BLAS/OpenMP library starts with it and worker processes inherit
    it; where a library is loaded already (the CLI run inside Python) :func:`thread_policy` limits
    it for the command's duration instead.

    Returns
    -------
    int or None
        The count in force, or None where the user's own settings stand.
    """
    n = requested_threads(threads)
    if n is not None and "numpy" not in sys.modules:
        for var in (*USER_THREAD_VARIABLES, "FLEXSHAFT_THREADS"):
            os.environ[var] = str(n)
    return n

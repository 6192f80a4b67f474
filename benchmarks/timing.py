"""What the benchmark scripts share: the best wall time of a few runs, alone or in turns (imported as
``timing`` when a script runs from the repository root: its own folder is first on ``sys.path``)."""

from __future__ import annotations

import math
import time


def best(fn, repeat: int = 3):
    """The shortest of ``repeat`` timed calls of ``fn`` (time.perf_counter, s) and the last result.

    The minimum, not the mean: on a shared machine every disturbance only adds time.
    """
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def interleaved(fns: dict, repeats: int) -> dict:
    """The best wall time (s) of each of ``fns`` (name -> callable), the calls taken in turns: every one
    sees the same drift in the machine's load."""
    times = dict.fromkeys(fns, math.inf)
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name] = min(times[name], time.perf_counter() - t0)
    return times

"""What the benchmark scripts share: the best wall time of a few runs (imported as ``timing`` when a
script runs from the repository root: its own folder is first on ``sys.path``)."""

from __future__ import annotations

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

"""Progress of long work (slicing, meshing, sweeps, simulations), on stderr.

On a terminal a bar redrawn in place; into a pipe or a file, plain lines - one every
:data:`PLAIN_INTERVAL_S` seconds, and the last when the work ends - so a log shows life without
carriage returns, and work that ends within the interval prints nothing at all. A plain bar's line
comes on time even while the work reports nothing (a part built before its first slice, a mesher
between stages): a daemon thread repeats the last state; it ends with the work, or when the bar is
no longer referenced (the work stopped on an error).
"""

from __future__ import annotations

import sys
import threading
import time
import weakref

__all__ = ["PLAIN_INTERVAL_S", "ProgressBar"]

#: Off a terminal: at most one progress line this often, s (the first after this long).
PLAIN_INTERVAL_S = 5.0


class _Pace:
    """When the last plain line of a stretch of work was written (or the work began): the bars of one
    piece of work - slicing, then meshing, then reducing each part - share it, so its first line comes
    an interval after the work began however short each bar, and one follows every interval after."""

    def __init__(self, stream, now: float) -> None:
        self.stream, self.since, self.activity = stream, now, now


_shared_pace: list[_Pace] = []  # the real clock's: one stretch of work at a time
_pace_lock = threading.Lock()


def _pace(stream, now: float) -> _Pace:
    """The stretch of work a new bar on ``stream`` belongs to: the current one, unless it wrote elsewhere
    or has been idle for an interval (then a new one begins now)."""
    with _pace_lock:
        if (
            not _shared_pace
            or _shared_pace[0].stream is not stream
            or now - _shared_pace[0].activity > PLAIN_INTERVAL_S
        ):
            _shared_pace[:] = [_Pace(stream, now)]
        return _shared_pace[0]


class ProgressBar:
    """Callable ``bar(done, total)`` that draws ``label [#####.....] done/total`` on one line.

    Parameters
    ----------
    label : str
        What is being done.
    stream : file, optional
        Where to draw (default stderr).
    enabled : bool, optional
        True: the bar, redrawn in place; False: nothing. Default: the bar on a terminal, else plain
        lines (``label: done/total``) at most every :data:`PLAIN_INTERVAL_S` s - none for work that
        ends sooner.
    width : int
        Bar width in characters.
    clock : callable, optional
        The time in seconds (default :func:`time.monotonic`; tests pass their own).
    """

    def __init__(
        self, label: str, *, stream=None, enabled: bool | None = None, width: int = 30, clock=None
    ) -> None:
        from ..errors import shown

        self.label = shown(label)  # a part's name from a file: no control character reaches the terminal
        self.stream = sys.stderr if stream is None else stream
        tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.enabled = True if enabled is None else enabled
        self.plain = enabled is None and not tty  # lines now and then, not a bar
        self.width = width
        self._clock = time.monotonic if clock is None else clock
        self._start = self._clock()
        # a test's own clock paces only its bar
        self._pace = _pace(self.stream, self._start) if clock is None else _Pace(self.stream, self._start)
        self._last = None  # when the last plain line was written; None: none yet
        self._state = "under way"  # the last state told, repeated while the work is silent
        self._done = False
        self._lock = threading.Lock()
        if self.plain and self.enabled and clock is None:
            threading.Thread(target=_beat, args=(weakref.ref(self),), daemon=True).start()

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled or total <= 0:
            return
        if self.plain:
            self._line(f"{self.label}: {done}/{total}", done >= total)
            return
        filled = int(self.width * done / total)
        end = "\n" if done >= total else ""
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (self.width - filled)}] {done}/{total}{end}")
        self.stream.flush()

    def stage(self, stage: str, fraction: float | None) -> None:
        """Draw ``label: stage [#####.....] 40 %`` - for work reported as stages and a rough share
        done (meshing a solid, reducing it); ``fraction`` None before the share is known."""
        if not self.enabled:
            return
        from ..errors import shown

        share = 0.0 if fraction is None else min(max(float(fraction), 0.0), 1.0)
        if self.plain:
            self._line(f"{self.label}: {shown(stage)} {100 * share:.0f} %", share >= 1.0)
            return
        filled = int(self.width * share)
        end = "\n" if share >= 1.0 else ""
        line = f"{self.label}: {shown(stage)}"[:50].ljust(50)
        self.stream.write(f"\r{line} [{'#' * filled}{'.' * (self.width - filled)}] {100 * share:3.0f} %{end}")
        self.stream.flush()

    def _line(self, text: str, last: bool) -> None:
        """A plain line when the interval has passed since the last (or the start), and the last one
        when earlier lines were written: quiet for quick work, never silent for long."""
        with self._lock:
            self._state = text[len(self.label) + 2 :]
            self._done = self._done or last
            now = self._clock()
            if self._due(now) or (last and self._last is not None):
                self._write(now)

    def _due(self, now: float) -> bool:
        """An interval since the last line of this stretch of work (or its beginning)."""
        self._pace.activity = max(self._pace.activity, now)
        return now - self._pace.since >= PLAIN_INTERVAL_S

    def _write(self, now: float) -> None:
        self.stream.write(f"{self.label}: {self._state} ({now - self._start:.0f} s)\n")
        self.stream.flush()
        self._last = now
        self._pace.since = now

    def _beat(self) -> bool:
        """The last state again when the work has been silent for the interval; False once it ended."""
        with self._lock:
            if self._done:
                return False
            now = self._clock()
            if self._due(now):
                self._write(now)
            return True


def _beat(ref) -> None:
    """A plain bar's heartbeat: looks every second, holding the bar only while it looks."""
    while True:
        time.sleep(PLAIN_INTERVAL_S / 5)
        bar = ref()
        if bar is None or not bar._beat():
            return
        del bar

"""A progress bar for long work (slicing, meshing, sweeps), on stderr and only for a terminal."""

from __future__ import annotations

import sys

__all__ = ["ProgressBar"]


class ProgressBar:
    """Callable ``bar(done, total)`` that draws ``label [#####.....] done/total`` on one line.

    Parameters
    ----------
    label : str
        What is being done.
    stream : file, optional
        Where to draw (default stderr).
    enabled : bool, optional
        Draw at all; default: only when ``stream`` is a terminal, so pipes,
        files and tests get clean output.
    width : int
        Bar width in characters.
    """

    def __init__(self, label: str, *, stream=None, enabled: bool | None = None, width: int = 30) -> None:
        from ..errors import shown

        self.label = shown(label)  # a part's name from a file: no control character reaches the terminal
        self.stream = sys.stderr if stream is None else stream
        self.enabled = (
            (hasattr(self.stream, "isatty") and self.stream.isatty()) if enabled is None else enabled
        )
        self.width = width

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled or total <= 0:
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
        filled = int(self.width * share)
        end = "\n" if share >= 1.0 else ""
        line = f"{self.label}: {shown(stage)}"[:50].ljust(50)
        self.stream.write(f"\r{line} [{'#' * filled}{'.' * (self.width - filled)}] {100 * share:3.0f} %{end}")
        self.stream.flush()

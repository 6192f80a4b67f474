"""The stabilisation diagram of an operational modal identification, as a matplotlib figure.

Drawn on the Agg canvas like every figure of :mod:`flexshaft.views.plots`: no window, no global style
change; the figure is returned (and written to a file when asked).
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..validation import check_int

__all__ = ["stabilisation_figure"]


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=120)
    FigureCanvasAgg(fig)
    return fig


def stabilisation_figure(identification, run: int = 0, *, path=None, overwrite: bool = False):
    """The stabilisation diagram of one run: every pole's frequency (Hz) against its model order.

    Parameters
    ----------
    identification : flexshaft.measurement.identify.Identification
        The result of :func:`~flexshaft.measurement.identify.identify_modes`.
    run : int
        Which run's diagram (its whole record), from 0.
    path : str or Path, optional
        Also write the figure there (.png, .svg or .pdf, by the suffix).
    overwrite : bool
        Replace an existing file at ``path``.

    Returns
    -------
    matplotlib.figure.Figure
        Grey dots: poles that are not stable; black: stable, physical poles of no mode; coloured: the
        stable poles each mode was made of, its frequency dashed and labelled with its damping.
    """
    diagrams = identification.diagrams
    run = check_int(run, "run", lo=0, hi=max(0, len(diagrams) - 1))
    d = diagrams[run]
    fig = _figure(7.5, 4.8)
    ax = fig.add_subplot()
    loose = ~d.stable | ~d.physical
    ax.plot(
        d.frequency_hz[loose],
        d.order[loose],
        ".",
        color="0.75",
        ms=3,
        label="not stable / not physical",
        gid="loose",
    )
    lone = d.stable & d.physical & (d.mode < 0)
    ax.plot(
        d.frequency_hz[lone],
        d.order[lone],
        "o",
        mfc="none",
        mec="k",
        ms=4,
        label="stable, no mode",
        gid="lone",
    )
    for m, mode in enumerate(identification.modes):
        colour = f"C{m % 10}"
        at = d.mode == m
        ax.plot(d.frequency_hz[at], d.order[at], "o", color=colour, ms=4, gid=f"mode {m}")
        ax.axvline(mode.frequency_hz, color=colour, ls="--", lw=0.8)
        ax.annotate(
            f"{mode.frequency_hz:.4g} Hz\n{100 * mode.damping_ratio:.3g} %",
            (mode.frequency_hz, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(3, -3),
            textcoords="offset points",
            va="top",
            fontsize=7,
            color=colour,
        )
    ax.set_xlim(0.0, identification.max_hz)
    orders = np.asarray(identification.orders)
    ax.set_ylim(0.0, orders.max() + 2)
    ax.axvspan(0.0, identification.min_hz, color="0.92", zorder=0)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("model order")
    summary = identification.runs[run]
    source = f" ({summary.source})" if summary.source else ""
    from .plots import as_written  # a file name as written

    title = f"stabilisation diagram, run {run}{source}: SSI-COV, {summary.duration_s:g} s"
    ax.set_title(as_written(title), fontsize=9)
    ax.legend(loc="lower right", fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    if path is not None:
        from pathlib import Path

        from ..system.atomic import atomic_write_bytes
        from .plots import picture

        target = Path(path)
        if target.suffix.lower() not in (".png", ".svg", ".pdf"):
            raise ModelError(
                "unknown picture type", field="path", value=str(path), valid=".png, .svg or .pdf"
            )
        atomic_write_bytes(target, picture(fig, target.suffix), overwrite=overwrite)
    return fig

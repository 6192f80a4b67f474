"""Plots as PNG bytes or figure handles: never a window, never a global style change."""

from __future__ import annotations

import io

__all__ = ["twist_figure", "twist_plot"]


def twist_figure(result):
    """The twist test's rotation along the shaft (the study's twist-versus-length line).

    Returns a matplotlib Figure (Agg canvas, not shown); rotation in mrad
    against axial position in m, stations marked.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(result.x, 1e3 * result.theta, "-", lw=1.5)
    for name, node in result.stations:
        ax.plot(result.x[node], 1e3 * result.theta[node], "o", ms=4, color="k")
        ax.annotate(
            name,
            (result.x[node], 1e3 * result.theta[node]),
            textcoords="offset points",
            xytext=(4, 4),
            fontsize=7,
        )
    ax.set_xlabel("axial position x (m)")
    ax.set_ylabel("rotation θ (mrad)")
    ax.set_title(
        f"twist test: {result.torque:g} N·m at {result.load!r}, clamped at {result.clamp!r}", fontsize=9
    )
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def twist_plot(result) -> bytes:
    """:func:`twist_figure` as PNG bytes."""
    buf = io.BytesIO()
    twist_figure(result).savefig(buf, format="png")
    return buf.getvalue()

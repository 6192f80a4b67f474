"""Engineering plots of results: figure handles or PNG bytes, never a window, never a global style change.

Every function returns a matplotlib ``Figure`` drawn on the Agg canvas (save it with
``fig.savefig(path)``; in Jupyter it displays itself). The result objects call them - their
``.plot()`` (``ModalResult.plot(...)``, ``TwistResult.plot()``, ...) - and are given, never imported:
views sit below the analyses.
"""

from __future__ import annotations

import io

import numpy as np

__all__ = [
    "twist_figure",
    "twist_plot",
    "mode_shapes_figure",
    "energy_figure",
    "torque_figure",
    "bode_figure",
    "simulation_figure",
    "campbell_figure",
    "spectrum_figure",
    "spectrogram_figure",
    "speed_varies",
    "listed_peaks",
    "signal_figure",
    "sensitivity_figure",
    "forced_figure",
    "sweep_figure",
    "calibration_figure",
    "reduction_figure",
    "png",
    "picture",
    "PICTURE_SUFFIXES",
]


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=120)
    FigureCanvasAgg(fig)
    return fig


def as_written(text) -> str:
    """A name (from a file) as a figure's text shows it as written: a ``$`` escaped (``\\$``), so two
    of them are no mathtext formula - which draws something else or, malformed, raises when the
    figure is drawn - and control characters escaped as :func:`flexshaft.errors.shown` does, not
    drawn as a missing glyph's box with a warning. flexshaft's own labels use no mathtext."""
    from ..errors import shown

    return shown(text, keep="\n").replace("$", "\\$")


def png(fig) -> bytes:
    """A figure as PNG bytes."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


PICTURE_SUFFIXES = (".png", ".svg", ".pdf")
"""The file types a plot is written in (matplotlib's Agg, SVG and PDF backends)."""

# No creation date in SVG and PDF files: the same figure gives the same bytes.
_NO_DATE = {".svg": {"Date": None}, ".pdf": {"CreationDate": None}, ".png": None}


def picture(fig, suffix: str) -> bytes:
    """A figure as the bytes of a ``.png``, ``.svg`` or ``.pdf`` file (the suffix, any case, picks)."""
    from ..errors import ModelError

    kind = suffix.lower()
    if kind not in PICTURE_SUFFIXES:
        raise ModelError(
            "unknown picture type", field="--plot", value=suffix, valid=", ".join(PICTURE_SUFFIXES)
        )
    import matplotlib

    buf = io.BytesIO()
    # A fixed salt for SVG's element ids (random otherwise), for this one save only.
    with matplotlib.rc_context({"svg.hashsalt": "flexshaft"}):
        fig.savefig(buf, format=kind[1:], metadata=_NO_DATE[kind])
    return buf.getvalue()


def twist_figure(result):
    """The twist test: rotation along the shaft, and each part's own twist.

    Returns a matplotlib Figure (Agg canvas, not shown). Top: rotation (mrad) against axial position
    (m), stations marked and named without overlapping. Bottom: each part's twist on a log scale, so
    a soft coupling's large twist does not hide the shafts' small ones, with each part's stiffness.
    """
    fig = _figure(7.5, 6.2)
    ax, bars = fig.subplots(2, 1, gridspec_kw={"height_ratios": [3, 2]})
    x = np.asarray(result.x, dtype=float)
    if not x[-1] > x[0]:
        x = np.arange(x.size, dtype=float)
    (line,) = ax.plot(x, 1e3 * result.theta, "-", lw=1.5, gid="twist")
    ax.autoscale_view()  # the limits now: a label's extent is measured where it will be drawn
    ax.set_ylim(*_widened(ax.get_ylim(), 0.25))  # room above and below the line for the names
    fig.tight_layout()  # the axes where they will be drawn: the labels are placed in pixels
    renderer = fig.canvas.get_renderer()
    placed = []
    for k, (name, node) in enumerate(result.stations):
        at = (x[node], 1e3 * result.theta[node])
        ax.plot(*at, "o", ms=4, color="k")
        _place_clear(ax, line, as_written(name), at, k, placed, renderer)
    ax.set_xlabel("axial position x (m)" if result.x[-1] > result.x[0] else "along the chain (schematic)")
    ax.set_ylabel("rotation θ (mrad)")
    ax.set_title(
        as_written(f"twist test: {result.torque:g} N·m at {result.load!r}, clamped at {result.clamp!r}"),
        fontsize=9,
    )
    ax.grid(True, alpha=0.3)
    parts = list(result.parts)
    twist = np.array([abs(p.twist) for p in parts]) * 1e3
    pos = np.arange(len(parts))
    bars.bar(pos, np.where(twist > 0, twist, np.nan), color="C0")
    for i, p in enumerate(parts):
        bars.annotate(
            f"{p.stiffness:.3g} N·m/rad",
            (i, twist[i]),
            textcoords="offset points",
            xytext=(0, 3),
            ha="center",
            fontsize=7,
        )
    bars.set_xticks(pos, [as_written(p.name) for p in parts], fontsize=8)
    if np.any(twist > 0):
        bars.set_yscale("log")
        bars.set_ylim(twist[twist > 0].min() / 3, twist.max() * 6)
    bars.set_ylabel("each part's twist (mrad)")
    bars.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def _widened(limits, fraction: float) -> tuple[float, float]:
    lo, hi = limits
    pad = fraction * (hi - lo)
    return lo - pad, hi + pad


def _place_clear(ax, line, text: str, at, k: int, placed: list, renderer) -> None:
    """A station's name beside its point, inside the axes, clear of the line and of the names already
    ``placed`` (window extents), with a leader to its point: above or below (alternating), right or
    left of the point, further out each try. Where no try is clear, the nearest one inside the axes
    with a see-through box (the line shows through it)."""
    from matplotlib.text import Text

    path = line.get_path().transformed(line.get_transform())
    inside = ax.get_window_extent(renderer)
    box = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85}
    leader = {"arrowstyle": "-", "color": "0.45", "lw": 0.6, "shrinkA": 0, "shrinkB": 2}

    def name(dx, dy, bbox):
        return ax.annotate(
            text, at, textcoords="offset points", xytext=(dx, dy), fontsize=7, bbox=bbox, arrowprops=leader,
            va="bottom" if dy > 0 else "top", ha="left" if dx > 0 else "right", gid="station-label",
        )  # fmt: skip

    fallback = None
    for step in range(16):
        dy = (1 if (k + step) % 2 == 0 else -1) * (8 + 9 * (step // 2))
        for dx in (4, -4):
            t = name(dx, dy, box)
            t.update_positions(renderer)
            bb = Text.get_window_extent(t, renderer)  # the name's own box, not its leader's
            within = inside.x0 <= bb.x0 and bb.x1 <= inside.x1 and inside.y0 <= bb.y0 and bb.y1 <= inside.y1
            free = not any(bb.overlaps(o) for o in placed)
            if within and free and not path.intersects_bbox(bb, filled=False):
                placed.append(bb)
                return
            t.remove()
            if within and fallback is None:
                fallback = (dx, dy)
    t = name(*(fallback or (4, 8)), dict(box, alpha=0.0))
    t.update_positions(renderer)
    placed.append(Text.get_window_extent(t, renderer))


def twist_plot(result) -> bytes:
    """:func:`twist_figure` as PNG bytes."""
    return png(twist_figure(result))


def _abscissa(model) -> tuple[np.ndarray, str]:
    """Node positions (m), or - a chain given by numbers only has no length - a schematic position."""
    if model.x[-1] > model.x[0]:
        return model.x, "axial position x (m)"
    return np.arange(model.n_nodes, dtype=float), "along the chain (schematic: no lengths given)"


def _schematic_ticks(ax, model, x) -> None:
    """A numbers-only chain's axis: its stations by name at their places in the chain."""
    if model.x[-1] > model.x[0]:
        return
    names = [as_written(st.name) for st in model.stations]
    ax.set_xticks([x[st.node] for st in model.stations], names, rotation=30, ha="right", fontsize=7)


def _shade_components(ax, model, x, *, names: bool = True) -> None:
    """Each flexible component's span shaded (alternating), rigid inertias as dashed lines.

    With ``names`` each component is named above the panel (outside the curves' area).
    """

    def label(name, at, **style):
        if names:
            where = {"xycoords": ("data", "axes fraction"), "fontsize": 7, "va": "bottom"}
            ax.annotate(as_written(name), (at, 1.02), **where, **style)

    k = 0
    for ci, comp in enumerate(model.drivetrain.components):
        s, e = int(model.start_node[ci]), int(model.end_node[ci])
        if comp.type == "rigid":
            ax.axvline(x[s], color="0.3", lw=1.2, ls="--")
            label(comp.name, x[s], rotation=90, ha="center")
        elif x[e] > x[s]:
            ax.axvspan(x[s], x[e], color=("0.93" if k % 2 else "0.85"), lw=0)
            label(comp.name, 0.5 * (x[s] + x[e]), ha="center")
            k += 1
        else:  # a component without length (a coupling, a gear, a shaft given by numbers): the line jumps
            ax.axvline(x[s], color="C3", lw=0.8, ls=":")
            label(comp.name, x[s], rotation=90, ha="center", color="C3")


def mode_shapes_figure(result, modes=None, *, dof: str = "θx"):
    """Mode shapes against axial position, one panel per mode, component spans shaded.

    Parameters
    ----------
    result : ModalResult
    modes : sequence of int, optional
        Which modes (as ``flexshaft modes`` numbers them); default: the
        elastic ones among the first six.
    dof : str
        The node DOF drawn (``"θx"`` torsion, ``"uy"`` bending, ...), each
        mode scaled so its largest ``|value|`` is 1.
    """
    if modes is None:
        modes = [i for i in range(min(result.count, 6 + int(result.rigid.sum()))) if not result.rigid[i]][:6]
    modes = list(modes)
    for i in modes:
        if not 0 <= i < result.count:
            from ..errors import ModelError

            raise ModelError("no such mode", field="mode", value=i, valid=f"0 … {result.count - 1}")
    x, label = _abscissa(result.model)
    shapes = result.dof_shapes(dof)
    fig = _figure(7, 1.8 + 1.6 * max(len(modes), 1))
    axes = fig.subplots(max(len(modes), 1), 1, sharex=True, squeeze=False)[:, 0]
    for row, (ax, i) in enumerate(zip(axes, modes)):
        v = shapes[:, i]
        peak = np.max(np.abs(v))
        v = v / peak if peak > 0 else v
        _shade_components(ax, result.model, x, names=row == 0)
        ax.plot(x, v, "-", lw=1.5, color="C0", gid="shape")
        ax.axhline(0.0, color="0.5", lw=0.6)
        z = result.damping_ratios[i]
        ax.set_title(
            f"mode {i}: {result.frequencies_hz[i]:.4g} Hz, damping {100 * z:.3g} % - {dof}, max-normalised",
            fontsize=8,
            pad=40 if row == 0 else 6,  # the top panel's title above the component names
        )
        ax.set_ylim(-1.15, 1.15)
        ax.set_ylabel(dof, fontsize=8)
    axes[-1].set_xlabel(label)
    _schematic_ticks(axes[-1], result.model, x)
    fig.tight_layout()
    return fig


def _hz(f: float) -> str:
    """A frequency in plain digits (no exponent below 1e5 Hz), 3-4 significant."""
    if f >= 1e5:
        return f"{f / 1e3:.0f} kHz"
    if f >= 100:
        return f"{f:.0f} Hz"
    return f"{f:.3g} Hz"


def _mode_labels(result, modes) -> list[str]:
    return [f"{i}\n{_hz(result.frequencies_hz[i])}" for i in modes]


def _readable_ticks(ax, count: int) -> None:
    """Mode labels that never run into each other: upright on one line when there are many, and
    every second (fourth, ...) one only if even those would touch."""
    if count <= 8:
        return
    labels = ax.get_xticklabels()
    for t in labels:
        t.set_text(t.get_text().replace("\n", ": "))
        t.set_rotation(90)
        t.set_fontsize(6)
    ax.set_xticks(ax.get_xticks(), [t.get_text() for t in labels], rotation=90, fontsize=6)
    fig = ax.figure
    step = 1
    while step < count:
        ticks = ax.get_xticklabels()
        for k, t in enumerate(ticks):
            t.set_visible(k % step == 0)
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        boxes = [t.get_window_extent(r) for t in ticks if t.get_visible()]
        if not any(a.overlaps(b) for a, b in zip(boxes, boxes[1:])):
            return
        step *= 2


def energy_figure(result, *, kind: str = "strain", modes=None):
    """Each mode's strain (or kinetic) energy split by component, as stacked bars (shares, 0-1).

    ``modes``: which modes (default: every elastic one for strain, every one for kinetic).
    """
    from ..validation import check_choice

    check_choice(kind, "kind", ("strain", "kinetic"))
    shares = result.strain_energy_fractions() if kind == "strain" else result.kinetic_energy_fractions()
    if modes is None:
        modes = np.flatnonzero(~result.rigid) if kind == "strain" else np.arange(result.count)
    modes = np.asarray(modes, dtype=int)
    names = result.model.component_names
    fig = _figure(7, 4)
    ax = fig.add_subplot()
    bottom = np.zeros(modes.size)
    for ci, name in enumerate(names):
        h = shares[modes, ci]
        if np.any(h > 0):
            ax.bar(np.arange(modes.size), h, bottom=bottom, label=as_written(name))
            bottom += h
    ax.set_xticks(np.arange(modes.size), _mode_labels(result, modes), fontsize=7)
    _readable_ticks(ax, modes.size)
    ax.set_ylabel(f"share of the mode's {kind} energy")
    ax.set_ylim(0, 1.05)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.18))
    fig.tight_layout()
    return fig


def torque_figure(result):
    """Peak elastic torque per component and mode, N·m per rad of peak station rotation (grouped bars)."""
    torques = result.component_torques()
    modes = np.flatnonzero(~result.rigid)
    comps = [ci for ci, c in enumerate(result.model.drivetrain.components) if c.type != "rigid"]
    fig = _figure(7, 4)
    ax = fig.add_subplot()
    width = 0.8 / max(len(comps), 1)
    for k, ci in enumerate(comps):
        ax.bar(
            np.arange(modes.size) + k * width,
            torques[modes, ci],
            width,
            label=as_written(result.model.component_names[ci]),
        )
    ax.set_xticks(np.arange(modes.size) + 0.4 - width / 2, _mode_labels(result, modes), fontsize=7)
    _readable_ticks(ax, modes.size)
    ax.set_ylabel("peak torque (N·m per rad)")
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    return fig


def bode_figure(response, *, damping: str | None = None, before=None):
    """Magnitude (log) and phase (degrees) of a frequency response against frequency, Hz.

    ``damping``: the damping assumption the response is under, named in the title (a study draws one
    response per assumption: the titles tell them apart). ``before``: the same response of the model
    before calibration (same inputs and outputs), drawn dashed in the same colours.
    """
    fig = _figure(7, 5)
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for j, (name, unit) in enumerate(zip(response.outputs, response.output_units)):
        h = response.H[:, j, 0]
        tuned = " (tuned)" if before is not None else ""
        (line,) = ax_m.semilogy(
            response.frequencies_hz, np.abs(h), label=as_written(f"{name} ({unit} per N·m){tuned}")
        )
        # unwrapped along the frequency axis: a resonance turns the phase by 180° without a ±360° jump
        ax_p.plot(response.frequencies_hz, np.degrees(np.unwrap(np.angle(h))), color=line.get_color())
        if before is not None:
            hb = before.H[:, j, 0]
            style = {"color": line.get_color(), "linestyle": "--", "linewidth": 0.8}
            ax_m.semilogy(before.frequencies_hz, np.abs(hb), label="  before calibration", **style)
            ax_p.plot(before.frequencies_hz, np.degrees(np.unwrap(np.angle(hb))), **style)
    ax_m.set_ylabel("|H|")
    ax_m.legend(fontsize=7)
    title = f"input: torque at {response.inputs[0]}" + (f"\ndamping: {damping}" if damping else "")
    ax_m.set_title(as_written(title), fontsize=9)
    ax_p.set_ylabel("phase (°, unwrapped)")
    ax_p.set_xlabel("frequency (Hz)")
    for ax in (ax_m, ax_p):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def simulation_figure(result, outputs=None, *, speed_unit: str = "rpm"):
    """Simulated outputs against time, s: one panel per unit (torques, speeds, angles).

    ``speed_unit``: speeds drawn in rpm (the unit the commands take a speed in) or rad/s.
    """
    from ..validation import check_choice

    check_choice(speed_unit, "speed_unit", ("rpm", "rad/s"))
    names = list(result.outputs) if outputs is None else list(outputs)

    def shown(n):
        if result.units[n] == "rad/s" and speed_unit == "rpm":
            return "rpm", np.asarray(result.outputs[n]) * 60 / (2 * np.pi)
        return result.units[n], np.asarray(result.outputs[n])

    units = list(dict.fromkeys(shown(n)[0] for n in names))
    fig = _figure(8, 2.2 * len(units) + 0.8)
    axes = np.atleast_1d(fig.subplots(len(units), 1, sharex=True))
    for ax, unit in zip(axes, units):
        for n in names:
            u, y = shown(n)
            if u == unit:
                ax.plot(result.time, y, lw=0.8, label=as_written(n))
        ax.set_ylabel(unit)
        ax.legend(fontsize=7, loc="best")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    axes[0].set_title(f"{result.scenario.kind} run at {result.rate_hz:g} Hz", fontsize=9)
    fig.tight_layout()
    return fig


def campbell_figure(diagram):
    """Eigenfrequencies (horizontal: no speed-dependent terms) and order lines against speed, rpm."""
    fig = _figure(7, 5)
    ax = fig.add_subplot()
    n = diagram.speeds_rpm
    for i, m in enumerate(diagram.modes):
        ax.plot(n, diagram.frequencies_hz[:, i], "-", color="C0", lw=1.2)
        ax.annotate(f"mode {m}", (n[-1], diagram.frequencies_hz[-1, i]), fontsize=7, ha="right", va="bottom")
    for k in diagram.orders:
        ax.plot(n, diagram.order_line(k), "--", color="0.4", lw=0.9)
    for c in diagram.crossings:
        ax.plot(c.speed_rpm, c.frequency_hz, "o", ms=5, mfc="none", color="C3")
    top = max([1.0] + [float(diagram.frequencies_hz.max(initial=0.0))] + [max(diagram.orders) * n[-1] / 60])
    ax.set_ylim(0, 1.05 * top)
    ax.set_xlim(n[0], n[-1])
    for k in diagram.orders:
        _order_label(ax, k, n[-1], 1.05 * top, color="0.2")
    ax.set_xlabel(as_written(f"speed of {diagram.reference!r} (rpm)"))
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Campbell diagram: modes, order lines and their crossings (○)", fontsize=9)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def _order_label(ax, k: float, n_end: float, top: float, **style) -> None:
    """Order ``k``'s name at the end of its line k·n/60 inside the axes: at the right edge, or where
    the line leaves through the top."""
    f_end = k * n_end / 60.0
    at = (n_end, f_end) if f_end <= top else (60.0 * top / k, top)
    ax.annotate(
        f"{k:g}×", at, textcoords="offset points", xytext=(-3, -3 if f_end > top else 2), fontsize=7,
        ha="right", va="top" if f_end > top else "bottom", gid="order-label", **style,
    )  # fmt: skip


#: Decades of amplitude a spectrum shows at most: 160 dB, beyond a 24-bit recorder's range (about
#: 144 dB), so round-off (a free decay's 0 Hz bin at 1e-12 of the rest) does not set the axis.
SPECTRUM_DECADES = 8


def _wrapped(text: str, width: int = 90) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) if len(text) > width else text


def spectrum_figure(spectrum, *, title: str = "", unit: str = "", marks=(), peaks=(), threshold=None):
    """Single-sided amplitude spectrum (log amplitude) against frequency, Hz.

    ``marks`` (Hz, dashed): a model's eigenfrequencies. ``peaks``: the listed peaks as (Hz, amplitude),
    marked; ``threshold``: the amplitude a peak must reach to be listed, a dotted line - so the plot
    shows why a resonance it draws is not in the table. The amplitude axis is scaled on the bins
    above 0 Hz and shows at most :data:`SPECTRUM_DECADES` decades.
    """
    fig = _figure(7, 4)
    ax = fig.add_subplot()
    amp = np.asarray(spectrum.amplitude, dtype=float)
    ax.semilogy(spectrum.frequencies_hz, np.maximum(amp, 1e-300), lw=0.8)
    for j, f in enumerate(marks):
        ax.axvline(f, color="0.5", ls="--", lw=0.8, label="model eigenfrequencies" if j == 0 else None)
    if len(peaks):
        fp, ap = np.asarray(peaks, dtype=float).reshape(-1, 2).T
        ax.plot(fp, 1.6 * ap, "v", color="C3", ms=6, label="listed peaks", gid="peaks")
    if threshold is not None and threshold > 0:
        ax.axhline(threshold, color="C3", ls=":", lw=1.0, label="peak threshold", gid="threshold")
    above = amp[1:][amp[1:] > 0]
    if above.size:
        top = 3.0 * float(above.max())
        low = max(0.5 * float(above.min()), top * 10.0**-SPECTRUM_DECADES)
        if threshold is not None and threshold > 0:
            low = min(low, threshold / 3.0)
        ax.set_ylim(low, top)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(as_written(f"amplitude ({unit})") if unit else "amplitude")
    ax.set_title(_wrapped(as_written(title)) or f"spectrum, {spectrum.window} window", fontsize=9)
    if len(marks) or len(peaks) or threshold is not None:
        ax.legend(fontsize=7, loc="upper right")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def speed_varies(spec, orders=()) -> bool:
    """Whether a spectrogram's speed axis tells anything: the highest order's line k·n/60 moves by at
    least one frequency bin over the record. A coast stop that holds its speed within a fraction of
    an rpm does not - its spectrogram is drawn against time."""
    if spec.speed_rpm is None or spec.frequencies_hz.size < 2:
        return False
    k = max([abs(float(o)) for o in orders] or [1.0])
    resolution = float(spec.frequencies_hz[1] - spec.frequencies_hz[0])
    return k * float(np.ptp(spec.speed_rpm)) / 60.0 >= resolution


def spectrogram_figure(
    spec, *, orders=(), eigenfrequencies=(), title: str = "", max_hz: float | None = None, unit: str = ""
):
    """Amplitude (dB re 1 ``unit``, its colour bar beside) over shaft speed, rpm - or over time, s,
    when there is no speed or it barely changes (:func:`speed_varies`) - and frequency, with order
    lines (k·n/60) and the model's eigenfrequencies (dotted) overlaid."""
    fig = _figure(8, 5)
    ax = fig.add_subplot()
    by_speed = speed_varies(spec, orders)
    x = spec.speed_rpm if by_speed else spec.times_s
    amp = 20 * np.log10(np.maximum(spec.amplitude, 1e-12 * max(float(spec.amplitude.max()), 1e-300)))
    f = spec.frequencies_hz
    top = max_hz if max_hz is not None else f[-1]
    if by_speed:
        order = np.argsort(x, kind="stable")
        mesh = ax.pcolormesh(x[order], f, amp[:, order], shading="nearest", cmap="viridis", rasterized=True)
        n = np.linspace(np.min(x), np.max(x), 50)
        for k in orders:
            ax.plot(n, k * n / 60.0, "w--", lw=0.8)
        ax.ticklabel_format(axis="x", style="plain", useOffset=False)
    else:
        mesh = ax.pcolormesh(x, f, amp, shading="nearest", cmap="viridis", rasterized=True)
        if spec.speed_rpm is not None:  # a steady speed: its orders are steady lines
            mean = float(np.mean(spec.speed_rpm))
            for k in orders:
                if 0 < k * mean / 60.0 < top:
                    ax.axhline(k * mean / 60.0, color="w", ls="--", lw=0.8)
                    ax.annotate(
                        f"{k:g}× ({mean:.4g} rpm)", (x[-1], k * mean / 60.0), textcoords="offset points",
                        xytext=(-3, 2), ha="right", va="bottom", color="w", fontsize=7, gid="order-label",
                    )  # fmt: skip
    for fe in eigenfrequencies:
        ax.axhline(fe, color="r", ls=":", lw=0.8)
    ax.set_ylim(0, top)
    if by_speed:
        ax.set_xlim(float(np.min(x)), float(np.max(x)))
        for k in orders:
            _order_label(ax, k, float(np.max(x)), top, color="w")
    ax.set_xlabel("speed (rpm)" if by_speed else "time (s)")
    ax.set_ylabel("frequency (Hz)")
    title = as_written(title) or f"spectrogram (dB), {spec.window} window, {spec.segment_s:g} s segments"
    if spec.speed_rpm is not None and not by_speed:
        span, mean = float(np.ptp(spec.speed_rpm)), float(np.mean(spec.speed_rpm))
        title += f"\nagainst time: the speed spans only {span:.2g} rpm about {mean:.4g} rpm"
    ax.set_title(title, fontsize=9)
    bar = fig.colorbar(mesh, ax=ax, pad=0.02)
    bar.set_label(as_written(f"amplitude (dB re 1 {unit})") if unit else "amplitude (dB re 1 signal unit)")
    fig.tight_layout()
    return fig


def signal_figure(analysis, *, spectrogram: bool = False, orders=(), marks=None):
    """The figure of an analysed signal (:class:`~flexshaft.measurement.analyse.SignalAnalysis`).

    Its amplitude spectrum; with a shaft speed, or ``spectrogram=True``, its spectrogram (Hann,
    ``analysis.segment`` s segments, else 1 s) against speed (rpm) or time (s), with the ``orders``'
    lines. ``marks`` (Hz, dashed; default the analysis' eigenfrequencies) show a model's modes.
    """
    from ..measurement.spectrogram import spectrogram as spectrogram_of

    if marks is None:
        marks = [f for _, f in analysis.eigenfrequencies]
    if analysis.speed_rpm is not None or spectrogram:
        sg = spectrogram_of(
            analysis.x,
            analysis.rate_hz,
            segment=analysis.segment or 1.0,
            window="hann",
            speed=analysis.speed_rpm,
        )
        title = f"{analysis.name} [{analysis.unit}]"
        return spectrogram_figure(sg, orders=orders, eigenfrequencies=marks, title=title, unit=analysis.unit)
    title = f"{analysis.name}: {analysis.method}"
    return spectrum_figure(
        analysis.spectrum, title=title, unit=analysis.unit, marks=marks, **listed_peaks(analysis)
    )


def listed_peaks(analysis, threshold: float | None = None) -> dict:
    """An analysed signal's listed peaks and the threshold they passed, as :func:`spectrum_figure`
    takes them: the plot and the peak table agree. ``threshold``: the caller's, if it has it."""
    if threshold is None:
        from ..measurement.peaks import peak_threshold

        threshold, _ = peak_threshold(analysis.spectrum)
    return {"peaks": [(p["frequency_hz"], p["amplitude"]) for p in analysis.peaks], "threshold": threshold}


def sensitivity_figure(sens):
    """Normalised sensitivities (% per %) as a heat map: parameters down, modes across."""
    values = sens.normalised.T
    fig = _figure(2.0 + 0.9 * values.shape[1], 1.2 + 0.28 * values.shape[0])
    ax = fig.add_subplot()
    lim = max(float(np.nanmax(np.abs(values))), 1e-12)
    im = ax.imshow(values, cmap="RdBu_r", vmin=-lim, vmax=lim, aspect="auto")
    ax.set_yticks(range(values.shape[0]), [as_written(p.name) for p in sens.parameters], fontsize=7)
    ax.set_xticks(
        range(values.shape[1]),
        [f"{m}\n{f:.4g} Hz" for m, f in zip(sens.modes, sens.frequencies_hz)],
        fontsize=7,
    )
    for i in range(values.shape[0]):
        for j in range(values.shape[1]):
            if abs(values[i, j]) >= 0.005:
                ax.text(j, i, f"{values[i, j]:.2f}", ha="center", va="center", fontsize=6)
    fig.colorbar(im, ax=ax, label="% change of f per % change of p")
    ax.set_xlabel("mode")
    ax.set_title("frequency sensitivities (p/f · ∂f/∂p)", fontsize=9)
    fig.tight_layout()
    return fig


def forced_figure(response):
    """A forced response: each part's peak dynamic torque (N·m, log scale) at each excitation, a group of
    bars per excitation frequency."""
    parts = [k for k, s in enumerate(response.signals) if s.startswith("torque:")]
    f = np.asarray(response.frequencies_hz, dtype=float)
    fig = _figure(max(5.0, 1.5 + 0.5 * f.size * max(1, len(parts)) ** 0.5), 4.0)
    ax = fig.add_subplot()
    width = 0.8 / max(1, len(parts))
    for j, k in enumerate(parts):
        amp = np.maximum(np.asarray(response.amplitudes[:, k], dtype=float), 1e-300)
        ax.bar(
            np.arange(f.size) + (j - (len(parts) - 1) / 2) * width,
            amp,
            width,
            label=as_written(response.signals[k][7:]),
        )
    labels = [f"mode {m}\n{fk:.4g} Hz" if m >= 0 else f"{fk:.4g} Hz" for m, fk in zip(response.modes, f)]
    ax.set_xticks(range(f.size), labels, fontsize=7)
    ax.set_yscale("log")
    ax.set_ylabel("peak dynamic torque (N·m)")
    ax.set_title(as_written(f"forced response to {response.amplitude:g} N·m at {response.input}"), fontsize=9)
    if parts:
        ax.legend(fontsize=7)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def sweep_figure(result):
    """A parameter sweep: each mode's frequency (Hz) against the first parameter, one marker per point
    (the points a model was refused at are left out)."""
    x = np.asarray(result.values[:, 0], dtype=float)
    fig = _figure(7.0, 4.5)
    ax = fig.add_subplot()
    order = np.argsort(x, kind="stable")
    for k in range(result.frequencies_hz.shape[1]):
        f = np.asarray(result.frequencies_hz[order, k], dtype=float)
        ax.plot(x[order], f, ".-" if len(result.names) == 1 else ".", lw=0.8, label=f"mode {k + 1}")
    unit = result.units[0]
    ax.set_xlabel(as_written(f"{result.names[0]} ({unit})" if unit else result.names[0]))
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("frequencies over the sweep", fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def calibration_figure(staged):
    """A staged calibration: each frequency target's error (%) before and after tuning, its tolerance
    shaded; beside it each parameter's change (%). One row of panels per stage."""
    n = len(staged.stages)
    fig = _figure(9.0, 0.6 + 2.8 * n)
    axes = np.atleast_2d(fig.subplots(n, 2, squeeze=False))
    for (ax1, ax2), st in zip(axes, staged.stages):
        res = st.result
        k = np.arange(len(res.targets))
        if res.targets:
            goal = np.array([t.value for t in res.targets])
            tol = np.array([100 * t.tolerance for t in res.targets])
            ax1.bar(k - 0.2, 100 * (res.initial_values / goal - 1), 0.4, label="initial", color="0.6")
            ax1.bar(k + 0.2, 100 * res.errors, 0.4, label="tuned", color="C0")
            ax1.bar(k, 2 * tol, 0.9, bottom=-tol, color="C2", alpha=0.15, label="tolerance")
            ax1.set_xticks(k, [as_written(t.label) for t in res.targets], fontsize=7)
            ax1.legend(fontsize=7)
        ax1.axhline(0.0, color="0.3", lw=0.8)
        ax1.set(ylabel="error (%)", title=as_written(f"stage {st.name!r}: targets"))
        change = np.nan_to_num(res.change_percent, nan=0.0)  # a damper from 0 has no % change
        ax2.barh(np.arange(len(res.names)), change, color="C1")
        ax2.set_yticks(np.arange(len(res.names)), [as_written(nm) for nm in res.names], fontsize=7)
        ax2.axvline(0.0, color="0.3", lw=0.8)
        ax2.set(xlabel="change (%)", title="parameters")
    fig.tight_layout()
    return fig


def reduction_figure(
    name: str, reduced_hz, full_hz, *, max_hz: float | None = None, tolerance: float | None = None
):
    """A flexible body against its part: free-free frequencies, and the reduction's error per mode.

    Parameters
    ----------
    name : str
        The part.
    reduced_hz, full_hz : array_like
        Elastic free-free frequencies of the Craig–Bampton body and of the full part model, Hz,
        lowest first (paired by number).
    max_hz : float, optional
        The range of interest, Hz, drawn as a line.
    tolerance : float, optional
        The relative error past which a mode is flagged (drawn as a line, flagged modes in red).
    """
    red = np.asarray(reduced_hz, dtype=float)
    full = np.asarray(full_hz, dtype=float)
    n = min(red.size, full.size)
    fig = _figure(8.0, 3.2)
    ax1, ax2 = fig.subplots(1, 2)
    k = np.arange(1, n + 1)
    ax1.plot(k, full[:n], "o", mfc="none", label="full part")
    ax1.plot(k, red[:n], "x", label="flexible body")
    if max_hz is not None:
        ax1.axhline(max_hz, color="0.6", lw=0.8, ls="--", label=f"max_hz {max_hz:g} Hz")
    ax1.set(xlabel="free-free elastic mode", ylabel="frequency, Hz", yscale="log", title=as_written(name))
    ax1.legend(fontsize=8)
    err = np.abs(red[:n] - full[:n]) / full[:n]
    ax2.semilogy(k, np.maximum(err, 1e-16), "s-")
    if tolerance is not None:
        ax2.axhline(tolerance, color="C3", ls="--", lw=0.9, label=f"flagged past {100 * tolerance:g} %")
        bad = err > tolerance
        ax2.plot(k[bad], err[bad], "s", color="C3", gid="flagged")
        ax2.legend(fontsize=8, loc="upper left")
    ax2.set(xlabel="free-free elastic mode", ylabel="|reduced − full| / full", title="reduction error")
    fig.tight_layout()
    return fig


def stepped_sine_figure(sweep):
    """A stepped sine's response curves: a panel per mode, a curve per drive amplitude, the linear
    frequency and each apparent one marked."""
    m = len(sweep.modes)
    fig = _figure(4.0 * m + 1.0, 3.6)
    axes = np.atleast_1d(fig.subplots(1, m))
    for j, ax in enumerate(axes):
        for i, a in enumerate(sweep.amplitudes):
            (line,) = ax.semilogy(
                sweep.frequencies_hz[j], sweep.response[i, j], ".-", lw=1.0, label=f"{a:g} N·m"
            )
            if np.isfinite(sweep.apparent_hz[i, j]):
                ax.axvline(sweep.apparent_hz[i, j], color=line.get_color(), lw=0.6, ls=":")
        ax.axvline(sweep.linear_hz[j], color="k", lw=0.8, ls="--", label="linear")
        ax.set_title(f"mode {int(sweep.modes[j])}: {sweep.linear_hz[j]:.4g} Hz linear", fontsize=9)
        ax.set_xlabel("frequency (Hz)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[0].set_ylabel(f"{as_written(sweep.measure)} [{sweep.unit}] per N·m")
    fig.tight_layout()
    return fig

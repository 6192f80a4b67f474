"""3D pictures of modes: PNG stills and GIF animations, or a pyvista plotter handle.

pyvista (VTK, off-screen: Mesa/EGL, no display) draws the surface only - the deformed drivetrain
coloured by its field, its generator lines, the undeformed lines as a faint ghost, the discs -
with a parallel projection fitted to the drivetrain. matplotlib then composes the picture around
that render: part and station labels placed so that none overlaps another (rows above and below,
leader lines to their anchors, boxed so they read on any colour), a colour bar with round ticks
and its title clear of them, a length scale (exact: parallel projection), an axis triad, and the
title with the exaggeration written on it. A GIF runs through exactly the frames asked for over
one period, the colours following the instantaneous phase, with a phase mark on every frame.

Nothing opens a window unless ``interactive=True`` is asked of :func:`mode_plotter`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..validation import check_int
from .deformed import ModeSurface, generator_segments, mode_surface

__all__ = [
    "mode_plotter",
    "mode_figure",
    "mode_picture",
    "mode_png",
    "mode_gif",
    "twist_picture",
    "twist_png",
    "compose",
    "VIEW_DIRECTION",
]

#: The direction the camera looks from (x along the line, z up): from the side, a little ahead and
#: above, so a long thin line runs nearly across the picture and its discs show as ellipses.
VIEW_DIRECTION = (0.3, -1.0, 0.4)
_WINDOW = (1200, 520)  # the 3D render, px: the composed picture adds the margins around it
_DPI = 100


def _pyvista():
    # VTK looks for an X display first and warns when there is none; off-screen EGL needs none.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    return pv


def _faces(surface: ModeSurface) -> np.ndarray:
    quads = np.hstack([np.full((surface.faces.shape[0], 1), 4), surface.faces]).ravel()
    tris = np.hstack([np.full((surface.triangles.shape[0], 1), 3), surface.triangles]).ravel()
    return np.concatenate([quads, tris]).astype(np.int64)


def _generator_cells(surface: ModeSurface) -> np.ndarray | None:
    """The generator lines (:func:`~flexshaft.views.deformed.generator_segments`) as VTK line cells."""
    pairs = generator_segments(surface)
    if not pairs.size:
        return None
    return np.column_stack([np.full(pairs.shape[0], 2), pairs]).ravel()


def _limits(surface: ModeSurface) -> tuple[float, float, str]:
    """The colour range: symmetric about 0 for twist and stress (they swing), from 0 for energy."""
    top = float(np.max(np.abs(surface.scalars))) or 1.0
    if surface.colour == "energy":
        return 0.0, top, "OrRd"
    return -top, top, "coolwarm"


class _Scene:
    """The pyvista plotter with the surface, lines, ghost and discs; moves them for an animation."""

    def __init__(self, surface: ModeSurface, window=_WINDOW, interactive: bool = False):
        pv = _pyvista()
        self.surface = surface
        self.plotter = plotter = pv.Plotter(off_screen=not interactive, window_size=list(window))
        plotter.set_background("white")
        self.lo, self.hi, self.cmap = _limits(surface)
        self.mesh = pv.PolyData(surface.deformed.copy(), _faces(surface))
        self.mesh.point_data["field"] = surface.scalars
        plotter.add_mesh(
            self.mesh,
            scalars="field",
            cmap=self.cmap,
            clim=(self.lo, self.hi),
            smooth_shading=True,
            show_scalar_bar=False,
        )
        cells = _generator_cells(surface)
        self.lines = None
        if cells is not None:
            self.lines = pv.PolyData(surface.deformed.copy(), lines=cells)
            plotter.add_mesh(self.lines, color="black", line_width=2)
            ghost = pv.PolyData(surface.points.copy(), lines=cells)
            plotter.add_mesh(ghost, color="#9a9a9a", line_width=1, opacity=0.5)
        r_max = float(np.max(np.hypot(surface.points[:, 1], surface.points[:, 2])))
        thickness = 0.01 * max(float(np.ptp(surface.points[:, 0])), 1e-3)
        self.discs = []
        for name, x, radius in surface.discs:
            rad = max(radius, 1.2 * r_max)
            plotter.add_mesh(
                pv.Cylinder(center=(x, 0, 0), direction=(1, 0, 0), radius=rad, height=thickness),
                color="#d0d0d0",
            )
            self.discs.append((name, x, rad))
        self._camera()

    def _camera(self) -> None:
        p = self.plotter
        P = self.surface.points
        lo, hi = P.min(axis=0), P.max(axis=0)
        for _, x, rad in self.discs:
            lo = np.minimum(lo, [x, -rad, -rad])
            hi = np.maximum(hi, [x, rad, rad])
        centre = 0.5 * (lo + hi)
        d = np.asarray(VIEW_DIRECTION, dtype=float)
        d /= np.linalg.norm(d)
        span = float(np.max(hi - lo)) or 1.0
        p.enable_parallel_projection()
        p.camera.focal_point = tuple(centre)
        p.camera.position = tuple(centre + 4 * span * d)
        p.camera.up = (0.0, 0.0, 1.0)
        # parallel scale: half the picture's height in metres - the box's corners, seen along d, fit
        # with a margin (labels go around the drawing in the composed picture)
        up = np.array([0.0, 0.0, 1.0]) - d * d[2]
        up /= np.linalg.norm(up)
        right = np.cross(d, up)
        corners = np.array(
            [[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])]
        )
        rel = corners - centre
        w, h = float(np.max(np.abs(rel @ right))), float(np.max(np.abs(rel @ up)))
        aspect = self.plotter.window_size[0] / self.plotter.window_size[1]
        p.camera.parallel_scale = 1.04 * max(h, w / aspect)
        p.camera.clipping_range = (0.01 * span, 10 * span)

    def move(self, factor: float) -> None:
        """The surface at ``factor`` times the mode (sin of the phase); colours at that instant."""
        s = self.surface
        moved = s.at(factor)
        self.mesh.points = moved
        self.mesh.point_data["field"] = s.scalars * (factor**2 if s.colour == "energy" else factor)
        if self.lines is not None:
            self.lines.points = moved

    def image(self) -> np.ndarray:
        self.plotter.render()
        return self.plotter.screenshot(return_img=True)

    def project(self, points) -> np.ndarray:
        """World points (m) to pixel positions (x right, y down) of the render."""
        import vtk

        c = vtk.vtkCoordinate()
        c.SetCoordinateSystemToWorld()
        ren = self.plotter.renderer
        height = self.plotter.window_size[1]
        out = []
        for p in np.atleast_2d(points):
            c.SetValue(*map(float, p))
            x, y = c.GetComputedDoubleDisplayValue(ren)
            out.append((x, height - y))
        return np.array(out)

    def metres_per_pixel(self) -> float:
        return 2 * self.plotter.camera.parallel_scale / self.plotter.window_size[1]

    def close(self) -> None:
        self.plotter.close()


def _anchors(scene: _Scene) -> tuple[list[str], np.ndarray, list[bool]]:
    s = scene.surface
    texts = [t for t, _ in s.labels] + [name for name, _, _ in scene.discs]
    where = [p for _, p in s.labels] + [(x, 0.0, 1.05 * rad) for _, x, rad in scene.discs]
    below = [p[2] < 0 for _, p in s.labels] + [False] * len(scene.discs)
    return texts, np.asarray(where, dtype=float), below


def _nice(x: float) -> float:
    """The largest 1, 2 or 5 times a power of ten not above ``x``."""
    p = 10.0 ** np.floor(np.log10(x))
    return next(m * p for m in (5, 2, 1) if m * p <= x)


def _length_text(metres: float) -> str:
    return f"{metres:g} m" if metres >= 1 else f"{metres * 1e3:g} mm"


def _place_labels(fig, ax, anchors, texts, below, margin_top: int, w: int, H: int) -> None:
    """The labels of :func:`compose`, each with its leader line: in rows outward from the line (the
    anchor's own side first, then alternating), clear of each other and of the title."""
    from ..errors import shown as shown_text

    # labels: rows outward from the line, the anchor's own side first, then alternating
    renderer = fig.canvas.get_renderer()
    placed = []
    order = np.argsort(anchors[:, 0], kind="stable") if len(texts) else []
    for i in order:
        ax_x, ax_y = anchors[i, 0], anchors[i, 1] + margin_top
        t = ax.text(
            ax_x,
            ax_y,
            shown_text(texts[i]),
            ha="center",
            va="center",
            fontsize=10,
            parse_math=False,
            bbox={"boxstyle": "round,pad=0.25", "fc": "white", "ec": "#777777", "alpha": 0.95},
        )
        t.draw(renderer)  # sizes the box around the text (its padding included)
        bb = t.get_bbox_patch().get_window_extent(renderer)
        bw, bh = bb.width, bb.height
        spot = None
        for k in range(30):
            side_ = 1 if (k % 2 == 0) == bool(below[i]) else -1  # +1: below (y grows downwards)
            out = 22 + (k // 2) * (bh + 6)
            cx = min(max(ax_x, bw / 2 + 4), w - bw / 2 - 4)
            cy = ax_y + side_ * (out + bh / 2)
            box = (cx - bw / 2 - 2, cy - bh / 2 - 2, cx + bw / 2 + 2, cy + bh / 2 + 2)
            if box[1] < 50 or box[3] > H - 4:
                continue
            if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in placed):
                spot = (cx, cy, box)
                break
        if spot is None:
            spot = (ax_x, ax_y - 30, (ax_x - bw / 2, ax_y - 30 - bh / 2, ax_x + bw / 2, ax_y - 30 + bh / 2))
        placed.append(spot[2])
        t.set_position((spot[0], spot[1]))
        edge = spot[1] - np.sign(spot[1] - ax_y) * bh / 2
        ax.plot([ax_x, spot[0]], [ax_y, edge], color="#444444", lw=0.8, zorder=1)
        ax.plot([ax_x], [ax_y], "o", ms=2.5, color="#222222", zorder=1)


def _scale_and_triad(ax, w: int, bottom: int, metres_per_pixel: float | None, axes) -> None:
    """The length scale (bottom right) and the axis triad (bottom left) of :func:`compose`, under the
    render whose lower edge is at ``bottom`` (figure pixels). ``metres_per_pixel`` None: a drawing
    without lengths (a chain given by numbers), said in place of the scale."""
    x1 = w - 20
    y0 = bottom + 40
    if metres_per_pixel is None:
        ax.text(x1, y0, "schematic: no lengths given", ha="right", va="center", fontsize=10, color="#444444")
    else:  # length scale: parallel projection, so one bar holds for the whole drivetrain
        length = _nice(0.18 * w * metres_per_pixel)
        px = length / metres_per_pixel
        ax.plot([x1 - px, x1], [y0, y0], color="black", lw=2.5, solid_capstyle="butt", gid="length-scale")
        ax.plot([x1 - px, x1 - px], [y0 - 5, y0 + 5], color="black", lw=1.2)
        ax.plot([x1, x1], [y0 - 5, y0 + 5], color="black", lw=1.2)
        ax.text(x1 - px / 2, y0 + 10, _length_text(length), ha="center", va="top", fontsize=10)
    # axis triad, bottom left
    ox, oy = 55, bottom + 55
    for (dx, dy), name, c in zip(axes, "xyz", ("#c0392b", "#27ae60", "#2c3e80")):
        n = float(np.hypot(dx, dy))
        if n < 1e-6:
            ax.text(ox, oy, name, color=c, fontsize=10, ha="center", va="center", fontweight="bold")
            continue
        ax.annotate(
            "",
            xy=(ox + 35 * dx, oy + 35 * dy),
            xytext=(ox, oy),
            arrowprops={"arrowstyle": "-|>", "color": c, "lw": 1.6},
        )
        ax.text(
            ox + 47 * dx,
            oy + 47 * dy,
            name,
            color=c,
            fontsize=10,
            ha="center",
            va="center",
            fontweight="bold",
        )


def compose(
    image, *, anchors, texts, below, colour, unit, limits, cmap, title, metres_per_pixel, axes, phase=None
):
    """The published picture around a 3D render: a matplotlib Figure (Agg).

    Parameters
    ----------
    image : ndarray, shape (h, w, 3)
        The render (white background).
    anchors : ndarray, shape (k, 2)
        Where each label points, render pixels (x right, y down).
    texts, below : list
        Each label's text, and whether it belongs under the line (a station inside a part).
    colour, unit, limits, cmap : str, str, (float, float), str
        The colour field's name, unit, range and matplotlib colour map.
    title : str
        Two lines: what is drawn, and the exaggeration.
    metres_per_pixel : float or None
        The render's scale (parallel projection: the same everywhere); None for a drawing without
        lengths (no length scale then).
    axes : ndarray, shape (3, 2)
        The x, y, z unit vectors as they appear in the picture (x right, y down), for the triad.
    phase : (int, int), optional
        Frame k of n of an animation: a phase mark.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from ..errors import shown as shown_text

    h, w = image.shape[:2]
    margin_top, margin_bottom, side = 150, 110, 150
    W, H = w + side, h + margin_top + margin_bottom
    fig = Figure(figsize=(W / _DPI, H / _DPI), dpi=_DPI)
    FigureCanvasAgg(fig)
    # the render in pixel coordinates of the whole figure (y down, origin top left)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, W)
    ax.set_ylim(H, 0)
    ax.axis("off")
    shown = ax.imshow(image, extent=(0, w, margin_top + h, margin_top), interpolation="antialiased")
    # names from files drawn as written (no mathtext, controls escaped): see plots.as_written
    title = shown_text(title, keep="\n")
    ax.text(12, 14, title, va="top", ha="left", fontsize=12, linespacing=1.5, parse_math=False)
    _place_labels(fig, ax, anchors, texts, below, margin_top, w, H)
    # colour bar: its title above it, clear of the ticks
    cax = fig.add_axes((1 - 95 / W, 0.22, 16 / W, 0.5))
    bar = fig.colorbar(ScalarMappable(norm=Normalize(*limits), cmap=cmap), cax=cax)
    bar.locator = MaxNLocator(nbins=6, steps=[1, 2, 5, 10])  # round ticks: 1, 2 or 5 times 10^k
    bar.update_ticks()
    bar.ax.tick_params(labelsize=9)
    cax.set_title(f"{colour}\n{unit}", fontsize=10, pad=10)
    _scale_and_triad(ax, w, margin_top + h, metres_per_pixel, axes)
    fig._flexshaft = {"image": shown}  # what an animation changes from frame to frame
    if phase is not None:
        k, n = phase
        x0, x1p, yb = 160, 400, margin_top + h + 40
        ax.plot([x0, x1p], [yb, yb], color="#bbbbbb", lw=4, solid_capstyle="round")
        (done,) = ax.plot([x0, x0], [yb, yb], color="#333333", lw=4, solid_capstyle="round")
        label = ax.text(x0, yb + 12, "", ha="left", va="top", fontsize=9)

        def at(k: int) -> None:
            done.set_xdata([x0, x0 + (x1p - x0) * k / max(n - 1, 1)])
            label.set_text(f"phase {k + 1} of {n} (one period)")

        at(k)
        fig._flexshaft["phase"] = at
    return fig


def _axes_on_screen(scene: _Scene) -> np.ndarray:
    """The x, y, z unit vectors as drawn (pixels, y down), the longest of them 1: an axis seen end-on
    (along the view) is short, as in the render."""
    span = 0.1 * max(float(np.ptp(scene.surface.points[:, 0])), 1e-3)
    ends = scene.project(np.vstack([np.zeros(3), span * np.eye(3)]))
    v = ends[1:] - ends[0]
    return v / (float(np.max(np.hypot(v[:, 0], v[:, 1]))) or 1.0)


def _picture(scene: _Scene, title: str, phase=None):
    s = scene.surface
    texts, where, below = _anchors(scene)
    anchors = scene.project(where) if len(texts) else np.zeros((0, 2))
    return compose(
        scene.image(),
        anchors=anchors,
        texts=texts,
        below=below,
        colour=s.colour,
        unit=s.unit,
        limits=(scene.lo, scene.hi),
        cmap=scene.cmap,
        title=title,
        metres_per_pixel=scene.metres_per_pixel() if s.has_length else None,
        axes=_axes_on_screen(scene),
        phase=phase,
    )


def _mode_title(result, mode: int, surface: ModeSurface) -> str:
    f, z = result.frequencies_hz[mode], result.damping_ratios[mode]
    what = {"twist": "twist", "stress": "shear stress", "energy": "strain-energy density"}[surface.colour]
    return (
        f"{result.model.drivetrain.name} - mode {mode}: {f:.4g} Hz, damping {100 * z:.3g} %\n"
        f"deformation exaggerated: the largest station rotation drawn as {np.degrees(surface.scale):.0f}°; "
        f"colour: {what} at {1e3 * surface.amplitude:g} mrad peak; grey lines: undeformed"
    )


def mode_plotter(
    result,
    mode: int,
    *,
    colour: str = "twist",
    scale: float = 0.3,
    window=(1000, 500),
    interactive: bool = False,
):
    """A pyvista Plotter showing one mode on the drivetrain's surface (not shown; see its ``screenshot``).

    The surface, its generator lines, the undeformed ghost and the discs, with a colour bar and the
    title; the composed pictures (:func:`mode_picture`) add the placed labels, length scale and triad.
    ``interactive=True`` makes a plotter that can open a window (``.show()``).
    """
    surface = mode_surface(result, mode, colour=colour, scale=scale)
    scene = _Scene(surface, window, interactive)
    scene.plotter.add_scalar_bar(title=f"{surface.colour} ({surface.unit})", color="black")
    scene.plotter.add_text(_mode_title(result, mode, surface), font_size=9, color="black")
    return scene.plotter


def _png(fig) -> bytes:
    from .plots import png

    return png(fig)


def twist_picture(drivetrain, twist, *, colour: str = "stress", scale: float = 0.3) -> bytes:
    """The twist test's deformed shape as PNG bytes, coloured at its own torque (shear stress by default)."""
    from .deformed import twist_surface

    surface = twist_surface(drivetrain, twist, colour=colour, scale=scale)
    title = (
        f"{drivetrain.name} - twist test: {twist.torque:g} N·m at {twist.load!r}, "
        f"clamped at {twist.clamp!r}\nlargest rotation {1e3 * surface.amplitude:.4g} mrad, drawn as "
        f"{np.degrees(scale):.0f}° (exaggerated); grey lines: undeformed"
    )
    scene = _Scene(surface)
    try:
        return _png(_picture(scene, title))
    finally:
        scene.close()


def mode_figure(result, mode: int, *, colour: str = "twist", scale: float = 0.3):
    """One mode's composed 3D picture as a matplotlib Figure (Agg), at its largest deflection."""
    surface = mode_surface(result, mode, colour=colour, scale=scale)
    scene = _Scene(surface)
    try:
        return _picture(scene, _mode_title(result, mode, surface))
    finally:
        scene.close()


def mode_picture(result, mode: int, *, colour: str = "twist", scale: float = 0.3) -> bytes:
    """One mode's 3D picture as PNG bytes (off-screen), at its largest deflection."""
    return _png(mode_figure(result, mode, colour=colour, scale=scale))


def twist_png(
    drivetrain, twist, path, *, colour: str = "stress", scale: float = 0.3, overwrite: bool = False
) -> Path:
    """The twist test's deformed shape as a PNG file (see :func:`twist_picture`), written atomically."""
    from ..system.atomic import atomic_write_bytes

    p = _target(path, ".png", overwrite)
    return atomic_write_bytes(
        p, twist_picture(drivetrain, twist, colour=colour, scale=scale), overwrite=overwrite
    )


def _target(path, suffix: str, overwrite: bool) -> Path:
    p = Path(path)
    if p.suffix.lower() != suffix:
        raise ModelError("wrong file type", field="output", value=str(p), valid=f"a {suffix} file")
    if p.exists() and not overwrite:
        raise ModelError("file exists", field="output", value=str(p), valid="a new path, or --force")
    return p


def mode_png(
    result, mode: int, path, *, colour: str = "twist", scale: float = 0.3, overwrite: bool = False
) -> Path:
    """One mode as a PNG picture (off-screen), written atomically."""
    from ..system.atomic import atomic_write_bytes

    p = _target(path, ".png", overwrite)
    return atomic_write_bytes(p, mode_picture(result, mode, colour=colour, scale=scale), overwrite=overwrite)


def mode_gif(
    result,
    mode: int,
    path,
    *,
    frames: int = 30,
    colour: str = "twist",
    scale: float = 0.3,
    overwrite: bool = False,
) -> Path:
    """One period of a mode as an animated GIF of exactly ``frames`` pictures, written atomically.

    Frame k shows the mode at sin(2πk/frames) of its drawn deflection, coloured at that instant, with
    a phase mark (so no two frames are alike and none is dropped); the GIF loops.
    """
    from ..system.atomic import atomic_write_bytes

    frames = check_int(frames, "frames", lo=2, hi=360)
    p = _target(path, ".gif", overwrite)
    surface = mode_surface(result, mode, colour=colour, scale=scale)
    scene = _Scene(surface, window=(960, 420))
    title = _mode_title(result, mode, surface)
    pictures = []
    try:
        fig = None
        for k in range(frames):
            scene.move(np.sin(2 * np.pi * k / frames))
            if fig is None:  # composed once: the labels, bar, scale and triad stay; the render changes
                fig = _picture(scene, title, phase=(k, frames))
            else:
                fig._flexshaft["image"].set_data(scene.image())
                fig._flexshaft["phase"](k)
            fig.canvas.draw()
            pictures.append(np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy())
    finally:
        scene.close()
    import io

    import imageio.v3 as iio

    buf = io.BytesIO()
    iio.imwrite(buf, np.stack(pictures), extension=".gif", duration=round(1000 / frames), loop=0)
    return atomic_write_bytes(p, buf.getvalue(), overwrite=overwrite)

"""3D pictures of modes with pyvista, off-screen: PNG and GIF files, or a plotter handle.

pyvista (and VTK behind it) is imported only here and only when a picture is asked for; it
renders without a display (Mesa/EGL off-screen). Nothing opens a window unless
``interactive=True`` is asked for.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..validation import check_int
from .surface import ModeSurface, mode_surface

__all__ = ["mode_plotter", "mode_picture", "mode_png", "mode_gif", "twist_picture", "twist_png"]


def _pyvista():
    # VTK looks for an X display first and warns when there is none; off-screen EGL needs none.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    return pv


def _mesh(pv, surface: ModeSurface, points: np.ndarray):
    quads = np.hstack([np.full((surface.faces.shape[0], 1), 4), surface.faces]).ravel()
    tris = np.hstack([np.full((surface.triangles.shape[0], 1), 3), surface.triangles]).ravel()
    faces = np.concatenate([quads, tris]).astype(np.int64)
    mesh = pv.PolyData(points, faces)
    mesh.point_data[f"{surface.colour} ({surface.unit})"] = surface.scalars
    return mesh


def _generator_lines(pv, surface: ModeSurface, points: np.ndarray):
    """Segments along the axis at four angles (0°, 90°, 180°, 270°) of every ring, as line cells."""
    seg = int(np.max(surface.faces[:, 1] - surface.faces[:, 0] + 1))  # points around a ring
    start = surface.faces[:, 0]
    along = surface.faces[np.isin(start % seg, [0, seg // 4, seg // 2, 3 * seg // 4])]
    cells = np.column_stack([np.full(along.shape[0], 2), along[:, 0], along[:, 3]]).ravel()
    return pv.PolyData(points, lines=cells)


def _build(result, mode, colour, scale, window, interactive):
    """The plotter, the surface mesh drawn in it, and the surface, for one mode."""
    surface = mode_surface(result, mode, colour=colour, scale=scale)
    f, z = result.frequencies_hz[mode], result.damping_ratios[mode]
    title = (
        f"{result.model.drivetrain.name} - mode {mode}: {f:.4g} Hz, damping {100 * z:.3g} %\n"
        f"twist drawn {np.degrees(scale):.0f}° at the largest station rotation"
    )
    return _draw(surface, title, f"at {1e3 * surface.amplitude:g} mrad peak", window, interactive)


def _draw(surface: ModeSurface, title: str, at: str, window, interactive):
    """A plotter with the deformed surface, its generator lines, discs and labels."""
    pv = _pyvista()
    plotter = pv.Plotter(off_screen=not interactive, window_size=list(window))
    plotter.set_background("white")
    mesh = _mesh(pv, surface, surface.deformed)
    name = f"{surface.colour} ({surface.unit})"
    bar = {"title": f"{name} {at}", "color": "black"}
    plotter.add_mesh(mesh, scalars=name, cmap="coolwarm", smooth_shading=True, scalar_bar_args=bar)
    # A round shaft turned about its axis looks the same: four lines along its surface, straight
    # before, show the twist as they turn into helices.
    lines = _generator_lines(pv, surface, surface.deformed) if surface.faces.size else None
    if lines is not None:
        plotter.add_mesh(lines, color="black", line_width=2)
    mesh._flexshaft_lines = lines  # kept with the surface so an animation moves both
    r_max = float(np.max(np.hypot(surface.points[:, 1], surface.points[:, 2])))
    thickness = 0.01 * max(float(np.ptp(surface.points[:, 0])), 1e-3)
    for _, x, radius in surface.discs:
        disc = pv.Cylinder(
            center=(x, 0, 0), direction=(1, 0, 0), radius=max(radius, 1.2 * r_max), height=thickness
        )
        plotter.add_mesh(disc, color="lightgray")
    labels = [t for t, _ in surface.labels] + [d[0] for d in surface.discs]
    where = [p for _, p in surface.labels]
    where += [(x, 0.0, 1.3 * max(radius, 1.2 * r_max)) for _, x, radius in surface.discs]
    plotter.add_point_labels(
        np.array(where),
        labels,
        font_size=12,
        text_color="black",
        shape=None,
        show_points=False,
        always_visible=True,
    )
    plotter.add_text(title, font_size=10, color="black")
    plotter.view_isometric()
    plotter.camera.zoom(1.3)
    return plotter, mesh, surface


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

    The title states the mode, frequency, damping and the visual scale; the colour bar the
    quantity, its unit and the amplitude it is given for; rigid inertias are labelled discs and
    every part is labelled. ``interactive=True`` makes a plotter that can open a window
    (``.show()``); otherwise it renders off-screen.
    """
    return _build(result, mode, colour, scale, window, interactive)[0]


def twist_picture(drivetrain, twist, *, colour: str = "stress", scale: float = 0.3) -> bytes:
    """The twist test's deformed shape as PNG bytes, coloured at its own torque (shear stress by default)."""
    from .surface import twist_surface

    surface = twist_surface(drivetrain, twist, colour=colour, scale=scale)
    title = (
        f"{drivetrain.name} - twist test: {twist.torque:g} N·m at {twist.load!r}, "
        f"clamped at {twist.clamp!r}\n"
        f"largest rotation {1e3 * surface.amplitude:.4g} mrad, drawn {np.degrees(scale):.0f}°"
    )
    return _png_bytes(_draw(surface, title, f"at {twist.torque:g} N·m", (1000, 500), False)[0])


def mode_picture(result, mode: int, *, colour: str = "twist", scale: float = 0.3) -> bytes:
    """One mode's 3D picture as PNG bytes (off-screen)."""
    return _png_bytes(mode_plotter(result, mode, colour=colour, scale=scale))


def twist_png(
    drivetrain, twist, path, *, colour: str = "stress", scale: float = 0.3, overwrite: bool = False
) -> Path:
    """The twist test's deformed shape as a PNG file (see :func:`twist_picture`), written atomically."""
    from ..atomic import atomic_write_bytes

    p = _target(path, ".png", overwrite)
    return atomic_write_bytes(
        p, twist_picture(drivetrain, twist, colour=colour, scale=scale), overwrite=overwrite
    )


def _png_bytes(plotter) -> bytes:
    import io

    import imageio.v3 as iio

    try:
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    buf = io.BytesIO()
    iio.imwrite(buf, image, extension=".png")
    return buf.getvalue()


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
    from ..atomic import atomic_write_bytes

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
    """One period of a mode as an animated GIF (``frames`` pictures, 24-36 by default 30), atomically."""
    from ..atomic import atomic_write_bytes

    frames = check_int(frames, "frames", lo=2, hi=360)
    p = _target(path, ".gif", overwrite)
    plotter, mesh, surface = _build(result, mode, colour, scale, (800, 400), False)
    pictures = []
    try:
        for k in range(frames):
            moved = surface.at(np.sin(2 * np.pi * k / frames))  # one period of the motion
            mesh.points = moved
            if mesh._flexshaft_lines is not None:
                mesh._flexshaft_lines.points = moved
            plotter.render()
            pictures.append(plotter.screenshot(return_img=True))
    finally:
        plotter.close()
    import io

    import imageio.v3 as iio

    buf = io.BytesIO()
    iio.imwrite(buf, np.stack(pictures), extension=".gif", duration=1000 / frames, loop=0)
    return atomic_write_bytes(p, buf.getvalue(), overwrite=overwrite)

"""One self-contained HTML report of a model: summary, parts, modes, energies, pictures, twist test.

``DIR/index.html`` embeds every picture as a data URI (no network, no second file needed to view
it) and ``DIR/modes.json`` is the ``flexshaft modes --json`` document. Both are written
atomically, into a folder that is new, empty or marked as flexshaft's own (``.flexshaft-output``);
a marked folder's report files are replaced only with ``overwrite``.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from .html import img as _img
from .html import table as _table

__all__ = ["write_report", "report_html"]


def _fmt(x, spec: str = ".6g") -> str:
    return "-" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def report_html(
    result, *, twist=None, pictures: int = 3, max_modes: int = 12, progress=None, mesh=None
) -> str:
    """The report of a modal result (and optionally its twist test) as one HTML document.

    Parameters
    ----------
    result : ModalResult
    twist : TwistResult, optional
    pictures : int
        How many of the first elastic modes get a 3D picture and a shape plot.
    max_modes : int
        How many of the lowest modes the tables and energy bars show (all are in ``modes.json``).
    progress : callable, optional
        ``progress(done, total)`` while the pictures render.
    mesh : MeshConvergence, optional
        Adds each mode's estimated mesh error (see :func:`flexshaft.mesh_convergence`).
    """
    from .plots import energy_figure, mode_shapes_figure, png, twist_figure
    from .render import mode_picture, twist_picture  # pyvista itself loads only when one is drawn

    mdl = result.model
    comps = mdl.drivetrain.components
    parts = []
    for c in comps:
        length = c.sections.length if getattr(c, "sections", None) is not None else None
        mass = c.sections.mass(c.material.rho) if getattr(c, "sections", None) is not None else None
        if c.type == "gear":
            # Each wheel about its own shaft; the mesh referred to the driving side.
            stiff = "rigid mesh" if c.rigid_mesh else _fmt(c.mesh_stiffness)
            wheels = f"{_fmt(c.inertia_in)} / {_fmt(c.inertia_out)}"
            parts.append([c.name, f"gear, ratio {c.ratio:g}", stiff, wheels, "", ""])
            continue
        parts.append(
            [c.name, c.type, _fmt(getattr(c, "stiffness", None)), _fmt(c.inertia), _fmt(mass), _fmt(length)]
        )
    dominant = result.dominant_components()
    modes = [
        [
            i,
            _fmt(result.frequencies_hz[i], ".4f"),
            "-" if result.rigid[i] else _fmt(100 * result.damping_ratios[i], ".4f"),
            "rigid-body mode" if result.rigid[i] else dominant[i],
        ]
        + ([] if mesh is None else ["-" if result.rigid[i] else _mesh_cell(mesh, i)])
        for i in range(min(result.count, max_modes))
    ]
    mode_head = ["mode", "frequency Hz", "damping %", "dominant component (strain energy)"]
    mesh_note = ""
    if mesh is not None:
        mode_head.append("mesh error %")
        mesh_note = (
            "<p>Mesh error: the estimated distance of each frequency from the mesh-converged one "
            "(every shaft at twice its elements, Richardson extrapolation); above "
            f"{100 * mesh.tolerance:g} % it is marked ⚠ - give the shafts more elements.</p>"
        )
    elastic = [i for i in range(result.count) if not result.rigid[i]][:pictures]
    shown = [i for i in range(min(result.count, max_modes)) if not result.rigid[i]]
    sections = [
        f"<h1>{html.escape(mdl.drivetrain.name)}</h1>",
        f"<p>{len(comps)} components, {mdl.n_dof} DOFs ({mdl.dofs}), {mdl.inertia_model} inertia, "
        f"{'damped' if result.damped is not None else 'undamped'}. Units: stiffness N·m/rad, inertia "
        "kg·m², mass kg, length m, frequency Hz, damping %.</p>",
        "<h2>Parts</h2>",
        _table(["component", "type", "stiffness N·m/rad", "inertia kg·m²", "mass kg", "length m"], parts),
        "<h2>Modes</h2><p>"
        + (
            f"All {result.count} computed modes."
            if result.count <= max_modes
            else f"The lowest {max_modes} of the {result.count} computed (all of them in modes.json beside "
            "this page)."
        )
        + "</p>",
        _table(mode_head, modes),
        mesh_note,
        "<h2>Energy shares</h2>",
        _img(png(energy_figure(result, kind="strain", modes=shown)), "strain energy by component"),
        "<h2>Mode shapes</h2>",
        _img(png(mode_shapes_figure(result, modes=elastic)), "mode shapes along the shaft")
        if elastic
        else "",
    ]
    from .webview import VIEWER_CSP, viewer_block, viewer_data, viewer_scripts

    scripts = ""
    if shown:
        sections += [
            "<h2>Mode shapes in 3D</h2><p>Turn, zoom and pan with the mouse; pick the mode, the colour and "
            "the exaggeration above the drawing.</p>",
            viewer_block(viewer_data(result, shown), "fs-report-viewer"),
        ]
        scripts = viewer_scripts()
    total = len(elastic)
    for k, i in enumerate(elastic):
        try:
            pic = mode_picture(result, i)
            sections.append(
                f"<h3>Mode {i}: {result.frequencies_hz[i]:.4g} Hz</h3>{_img(pic, f'mode {i} in 3D')}"
            )
        except ImportError:  # pyvista missing: the report still says everything else
            sections.append(f"<p>Mode {i}: no 3D picture (pyvista is not installed).</p>")
        if progress is not None:
            progress(k + 1, total)
    if twist is not None:
        rows = [
            # one format per kind of number: stiffness and twist in 5 significant digits, positions in mm
            [
                p.name,
                _fmt(p.stiffness, ".4e"),
                _fmt(p.twist, ".4e"),
                _fmt(p.x_start, ".3f"),
                _fmt(p.x_end, ".3f"),
            ]
            for p in twist.parts
        ]
        sections += [
            f"<h2>Twist test</h2><p>Clamped at {html.escape(twist.clamp)}, {twist.torque:g} N·m at "
            f"{html.escape(twist.load)}; clamp to load {twist.total_stiffness:.6g} N·m/rad.</p>",
            _table(["part", "stiffness N·m/rad", "twist rad", "x start m", "x end m"], rows),
            _img(png(twist_figure(twist)), "twist along the shaft"),
        ]
        try:
            sections.append(_img(twist_picture(mdl.drivetrain, twist), "the twisted shaft, by shear stress"))
        except ImportError:
            pass
    style = (
        "body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
        "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;"
        "text-align:right}th{background:#eee}img{max-width:100%;display:block;margin:1em 0}"
    )
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{VIEWER_CSP}">'
        f"<title>{html.escape(mdl.drivetrain.name)} - flexshaft report</title><style>{style}</style>"
        "</head><body>" + scripts + "\n".join(sections) + "</body></html>\n"
    )


def _mesh_cell(mesh, i: int) -> str:
    e = mesh.error[i]
    text = "> 100" if e >= 1 else f"{100 * e:.2g}"
    return text + (" ⚠" if e > mesh.tolerance else "")


def write_report(
    result,
    folder,
    *,
    twist=None,
    document: dict | None = None,
    overwrite: bool = False,
    progress=None,
    mesh=None,
    inputs=(),
    option: str = "output",
) -> Path:
    """Write ``folder/index.html`` (and ``folder/modes.json`` given the document); returns the HTML path.

    The folder is new, empty or one flexshaft wrote (see :func:`flexshaft.system.atomic.check_output_folder`:
    never a link, the root or a home folder, nor one holding an input); it is judged before the
    pictures are drawn and again before anything is written. ``overwrite`` replaces the report's
    own files in a folder flexshaft wrote, nothing else. ``inputs`` are the files the report was
    made from; ``option`` is what errors call the folder (the CLI's ``-o``).
    """
    from ..errors import ModelError
    from ..system.atomic import OUTPUT_MARKER, atomic_write_text, check_output_folder, prepare_output_folder

    files = ("index.html",) + (("modes.json",) if document is not None else ())
    rules = {"force": overwrite, "inputs": tuple(inputs), "files": files, "option": option}
    check_output_folder(folder, **rules)  # before the rendering: a refusal costs nothing
    text = report_html(result, twist=twist, progress=progress, mesh=mesh)
    new = not (Path(folder).exists() or Path(folder).is_symlink())
    d = Path(folder)
    try:
        d = prepare_output_folder(folder, writer="flexshaft report", **rules)
        if document is not None:
            atomic_write_text(
                d / "modes.json", json.dumps(document, indent=1, ensure_ascii=False) + "\n", overwrite=True
            )
        return atomic_write_text(d / "index.html", text, overwrite=True)
    except ModelError:
        # a full disk or a quota met halfway: a folder made for this report goes again, so no report
        # without its page is left (in an earlier report's folder each file is whole, old or new)
        if new:
            _remove_new_report(d, (*files, OUTPUT_MARKER))
        raise


def _remove_new_report(d: Path, names) -> None:
    """Remove a report folder this call made: its files, then the folder (only if nothing else came)."""
    import contextlib

    for name in names:
        with contextlib.suppress(OSError):
            (d / name).unlink(missing_ok=True)
    with contextlib.suppress(OSError):
        d.rmdir()

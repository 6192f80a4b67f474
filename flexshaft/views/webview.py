"""Mode shapes you can turn in the browser: a self-contained HTML viewer (WebGL, three.js inlined).

The page carries the drivetrain's surface (:mod:`flexshaft.views.deformed`: shafts as surfaces of
revolution, CAD parts as their own tessellated surface) and, per mode, each surface point's
normalised twist, its shear stress and strain-energy density at the stated amplitude, and a 6-DOF
mode's lateral motion. The browser animates one period, and the user turns, zooms and pans it,
picks the mode, the colour and the exaggeration. Arrays travel as base64: points as float32,
per-mode fields as int16 fractions of their largest magnitude (1/32767 of it: far below what a
colour or a pixel resolves), so a CAD model's page is a few MB.

Nothing is fetched: three.js (``viewer/vendor/three-fs3.min.js``, MIT, pinned and vendored from the npm
registry with its licence) and flexshaft's ``viewer/viewer.js`` are inlined, and the page's
Content-Security-Policy forbids any network request.
"""

from __future__ import annotations

import base64
import html
from functools import cache
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..validation import check_int, check_real
from .deformed import STRESS_AMPLITUDE, generator_segments, mode_surface

__all__ = ["viewer_data", "viewer_html", "viewer_scripts", "viewer_block", "mode_html", "VIEWER_CSP"]

_HERE = Path(__file__).resolve().parent / "viewer"
_VENDOR = _HERE / "vendor"  # third-party code, with its licence, as published
#: A station's hand reaches this fraction of the drawing's length from the axis (at least 1.3 times
#: the largest radius): turned by the drawn twist (17° by default) its tip moves by ~3.5 % of the length.
HAND_LENGTH = 0.12
_LISTED = 20  # = flexshaft.analysis.modal.DEFAULT_LISTED (a test holds them equal)
#: The Content-Security-Policy of a page with the viewer: inline scripts and styles, data: images,
#: nothing from the network.
VIEWER_CSP = "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:"

_STYLE = """
.fs-viewer{font:14px/1.4 system-ui,-apple-system,"Segoe UI",sans-serif;max-width:1100px}
.fs-bar{display:flex;gap:.6em;align-items:center;flex-wrap:wrap;margin:.3em 0}
.fs-stage{position:relative;width:100%;border:1px solid #ccc;overflow:hidden}
.fs-stage canvas{display:block}
.fs-labels,.fs-leaders{position:absolute;left:0;top:0;pointer-events:none}
.fs-label{position:absolute;padding:1px 4px;background:rgba(255,255,255,.9);border:1px solid #999;
 border-radius:3px;font-size:12px;white-space:nowrap;color:#111}
.fs-colourbar{position:absolute;right:6px;top:6px}
.fs-triad{position:absolute;left:4px;bottom:4px;pointer-events:none}
.fs-scale{position:absolute;right:12px;bottom:8px;font-size:12px;text-align:center;
 background:rgba(255,255,255,.85);padding:2px 4px}
.fs-scale-bar{height:5px;border:1px solid #111;border-top:none;margin:auto}
.fs-caption{color:#333;font-size:13px;margin:.3em 0 1em}
"""


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _quantised(values: np.ndarray) -> dict:
    """``values`` as int16 fractions of their largest magnitude (``max``), base64."""
    v = np.asarray(values, dtype=float).ravel()
    top = float(np.max(np.abs(v))) if v.size else 0.0
    q = np.zeros(v.size, dtype="<i2") if top == 0 else np.rint(v / top * 32767).astype("<i2")
    return {"max": top, "data": _b64(q)}


def _grid(P: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> dict:
    """Points as int16 steps across their bounding box, per axis (``lo``, ``hi`` in m), base64."""
    span = np.where(hi > lo, hi - lo, 1.0)
    q = np.rint((P - lo) / span * 65534 - 32767).astype("<i2")
    return {"lo": lo.tolist(), "hi": (lo + span).tolist(), "data": _b64(q)}


def viewer_data(
    result,
    modes=None,
    *,
    colour: str = "twist",
    scale: float = 0.3,
    first: int | None = None,
    max_hz: float | None = None,
) -> dict:
    """What the browser viewer draws, as a JSON-able dict (arrays base64; SI).

    Parameters
    ----------
    result : ModalResult
    modes : sequence of int, optional
        The modes to offer, as ``flexshaft modes`` numbers them; default every elastic mode up
        to the model's ``max_hz`` (or the lowest 20 elastic modes).
    colour : {"twist", "stress", "energy"}
        The colour the viewer opens with.
    scale : float
        The visual twist it opens with, rad, at the largest station rotation.
    first : int, optional
        The mode it opens on (added to ``modes`` if missing); default the first of them.
    max_hz : float, optional
        The range of interest for the default ``modes``, Hz; default the model's ``max_hz``.
    """
    from ..validation import check_choice
    from .deformed import COLOURS

    check_choice(colour, "colour", COLOURS)
    scale = check_real(scale, "scale", "rad", lo=0.0, lo_open=True, hi=np.pi)
    if modes is None:
        elastic = np.flatnonzero(~result.rigid)  # a rigid-body mode deforms nothing
        top = result.model.drivetrain.max_hz if max_hz is None else max_hz
        if top is not None:
            elastic = elastic[result.frequencies_hz[elastic] <= top]
        # the lowest 20, as `flexshaft modes` lists them (analysis.modal.DEFAULT_LISTED; not imported:
        # the modal result draws itself through this module, and an import back would be a cycle)
        modes = [int(m) for m in elastic[:_LISTED]]
    modes = [check_int(m, "mode", lo=0, hi=result.count - 1) for m in modes]
    if first is not None:
        first = check_int(first, "mode", lo=0, hi=result.count - 1)
        modes = sorted(set(modes) | {first})
    if not modes:
        raise ModelError("no mode to show", field="modes", valid="one or more elastic modes")
    opening = modes.index(first) if first is not None else 0
    first = None
    out_modes = []
    for m in modes:
        s = mode_surface(result, m, scale=scale)  # every colour at once (s.fields)
        first = first or s
        lateral = s.lateral / scale if np.any(s.lateral) else None
        out_modes.append(
            {
                "index": m,
                "frequency_hz": float(result.frequencies_hz[m]),
                "damping_ratio": float(result.damping_ratios[m]),
                "phi": _quantised(s.phi / scale),
                "twist_max": float(np.max(np.abs(s.theta))) * 1e3,
                "stress": _quantised(s.fields["stress"][0]),
                "energy": _quantised(s.fields["energy"][0]),
                "lateral": None if lateral is None else _quantised(lateral),
                "discs": (s.disc_phi / scale).tolist(),  # each disc's normalised twist (its node's)
                "hands": (s.station_phi / scale).tolist(),  # each station's
            }
        )
    P = first.points
    tris = np.vstack([first.triangles, first.faces[:, [0, 1, 2]], first.faces[:, [0, 2, 3]]])
    lines = generator_segments(first)
    index_type = "u16" if P.shape[0] < 65536 else "u32"
    itype = "<u2" if index_type == "u16" else "<u4"
    r_max = float(np.max(np.hypot(P[:, 1], P[:, 2])))
    length = float(np.ptp(P[:, 0])) or 1.0
    discs = []
    for k, (name, x, radius) in enumerate(first.discs):
        rad = max(radius, 1.2 * r_max)
        discs.append(
            {
                "name": name,
                "x": float(x),
                "radius": float(rad),
                "thickness": 0.01 * length,
                "phi": [md["discs"][k] for md in out_modes],
            }
        )
    labels = [{"text": t, "p": [float(v) for v in p], "below": bool(p[2] < 0)} for t, p in first.labels]
    labels += [{"text": d["name"], "p": [d["x"], 0.0, 1.05 * d["radius"]], "below": False} for d in discs]
    lo = P.min(axis=0)
    hi = P.max(axis=0)
    for d in discs:
        lo = np.minimum(lo, [d["x"], -d["radius"], -d["radius"]])
        hi = np.maximum(hi, [d["x"], d["radius"], d["radius"]])
    hands = _hands(first, discs, out_modes, length, r_max)
    for h in hands:
        hi = np.maximum(hi, [h["x"], h["length"], h["length"]])  # two arms: +y and +z
    for md in out_modes:
        md.pop("discs", None)
        md.pop("hands", None)
    return {
        "model": result.model.drivetrain.name,
        "n_points": int(P.shape[0]),
        # int16 steps of the bounding box per axis: 1/65534 of it (0.15 mm on a 10 m line), far below
        # a pixel; half the size of float32
        "points": _grid(P, P.min(axis=0), P.max(axis=0)),
        "index_type": index_type,
        "triangles": _b64(tris.astype(itype)),
        "lines": _b64(lines.astype(itype)),
        "bounds": [lo.tolist(), hi.tolist()],
        "discs": discs,
        "hands": hands,
        "lengths": bool(first.has_length),  # False: a schematic line, no length scale
        "labels": labels,
        "amplitude": STRESS_AMPLITUDE,
        "scale": scale,
        "colour": colour,
        "initial": opening,
        "units": {"length": "m", "twist": "mrad", "stress": "MPa", "energy": "J/m³", "frequency": "Hz"},
        "modes": out_modes,
    }


def _hands(surface, discs: list, modes: list, length: float, r_max: float) -> list[dict]:
    """A hand at every station (but on a disc as large), turning with its twist (each mode's ``"hands"``).

    A slender shaft turned by the drawn twist moves its surface by a few pixels only (r/L ~ 1/50); a
    hand of :data:`HAND_LENGTH` of the drawing's length moves its tip by about 3.5 % of it - the
    mode's motion is seen wherever it is. Two arms (+y, +z): from any side one of them turns across
    the line of sight.
    """
    hands = []
    reach = max(HAND_LENGTH * length, 1.3 * r_max)
    for k, (name, x) in enumerate(surface.stations):
        # a disc as large turns its own radius marks as far: no hand on it
        if any(abs(x - d["x"]) <= 1e-9 * length and d["radius"] >= reach for d in discs):
            continue
        hands.append({"name": name, "x": float(x), "length": reach, "phi": [m["hands"][k] for m in modes]})
    return hands


@cache
def _script(name: str) -> str:
    return (_HERE / name).read_text(encoding="utf-8")


def viewer_scripts() -> str:
    """The viewer's scripts and style, once per page: three.js (its licence named) and viewer.js."""
    # "</script" cannot occur inside an inline script; neither file holds it (checked by a test).
    return (
        f"<style>{_STYLE}</style>\n"
        "<!-- three.js r187, MIT licence (c) 2010-2026 three.js authors: flexshaft/views/viewer/vendor/"
        "THREE-LICENSE -->\n"
        f"<script>{_script('vendor/three-fs3.min.js')}</script>\n<script>{_script('viewer.js')}</script>\n"
    )


def viewer_block(data: dict, ident: str) -> str:
    """One viewer: its element, its data (JSON) and the line that starts it. ``ident``: unique on the page."""
    from .html import script_json

    i = html.escape(ident)
    return (
        f'<div id="{i}" class="fs-viewer-root"></div>\n'
        f'<script type="application/json" id="{i}-data">{script_json(data)}</script>\n'
        f"<script>flexshaftViewer({script_json(ident)}, {script_json(ident + '-data')});</script>\n"
    )


def viewer_html(
    result,
    modes=None,
    *,
    title: str | None = None,
    colour: str = "twist",
    scale: float = 0.3,
    first: int | None = None,
) -> str:
    """A self-contained HTML page with the browser viewer of ``modes`` (see :func:`viewer_data`)."""
    data = viewer_data(result, modes, colour=colour, scale=scale, first=first)
    name = title or f"{result.model.drivetrain.name} - mode shapes"
    return (
        '<!doctype html>\n<html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{VIEWER_CSP}">'
        f'<title>{html.escape(name)}</title></head><body>\n<h1 style="font:600 20px system-ui,sans-serif">'
        f"{html.escape(name)}</h1>\n{viewer_scripts()}{viewer_block(data, 'fs-view-1')}</body></html>\n"
    )


def mode_html(
    result, mode: int, path, *, colour: str = "twist", scale: float = 0.3, overwrite: bool = False
) -> Path:
    """The browser viewer as an HTML file, opening on ``mode`` with the listed modes to pick from.

    The modes offered are the elastic ones up to the model's ``max_hz`` (or the lowest 20) among
    those ``result`` holds, and ``mode``; written atomically, an existing file only with ``overwrite``.
    """
    from ..system.atomic import atomic_write_bytes

    p = Path(path)
    if p.suffix.lower() != ".html":
        raise ModelError("wrong file type", field="output", value=str(p), valid="a .html file")
    if p.exists() and not overwrite:
        raise ModelError("file exists", field="output", value=str(p), valid="a new path, or --force")
    page = viewer_html(result, colour=colour, scale=scale, first=mode)
    return atomic_write_bytes(p, page.encode("utf-8"), overwrite=overwrite)

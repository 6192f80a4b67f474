"""The report's opening: what a reader needs before the sections - the set-ups, the key frequencies
measured against the model with a verdict each, and what needs a look (failed stages, meshes not
converged, flexible bodies past their accuracy, targets missed). Everything from ``results.json``.
"""

from __future__ import annotations

import os.path

from ..views.html import escape as _e
from ..views.html import table as _table

__all__ = ["summary"]


def _same_file(a: str, b: str) -> bool:
    return os.path.normpath(os.path.abspath(a)) == os.path.normpath(os.path.abspath(b))


def _mesh_check(results: dict, s: str) -> dict:
    """The modes stage's mesh check of set-up ``s`` (empty without one)."""
    docs = results.get("modes", {}).get(s) or {}
    return (docs[next(iter(docs))].get("mesh_check") or {}) if docs else {}


def _mesh_state(mesh: dict, check: dict) -> str:
    if not mesh:
        return "-"
    if mesh.get("max_hz") is None:
        state = "as given (no max_hz)"
    else:
        state = "converged" if mesh.get("converged", True) else "NOT converged"
    flagged = check.get("flagged_modes") or []
    return state + (f"; modes {', '.join(map(str, flagged))} flagged" if flagged else "")


def _elastic(results: dict, s: str) -> list[dict]:
    docs = results.get("modes", {}).get(s) or {}
    if not docs:
        return []
    first = docs[next(iter(docs))]
    return [m for m in first["modes"] if not m["rigid"]]


def _setups_table(results: dict, setups: list) -> str:
    rows = []
    for s in setups:
        su = results.get("setups", {}).get(s)
        if su is None:
            rows.append([s, "-", "-", "-", "-", "did not run"])
            continue
        elastic = _elastic(results, s)
        mesh = su.get("mesh", {})
        rows.append(
            [
                s,
                os.path.basename(su["model_file"]),
                len(su["components"]),
                len(elastic),
                ", ".join(f"{m['frequency_hz']:.4g}" for m in elastic[:3]) or "-",
                _mesh_state(mesh, _mesh_check(results, s)),
            ]
        )
    head = ["set-up", "model file", "components", "elastic modes listed", "f1, f2, f3 (model) Hz", "mesh"]
    return _table(head, rows)


def _verdict(error: float | None, tolerance: float | None, met: bool | None = None) -> str:
    """Within or off, as ``met`` says (the calibration's own verdict, where it gave one)."""
    if error is None or tolerance is None:
        return "-"
    if abs(error) <= tolerance if met is None else met:
        return f"within ±{100 * tolerance:.3g} %"
    return f"off by {100 * error:+.2f} %"


def _stage_setup(stage: dict, results: dict, setups: list) -> str:
    """The set-up a calibration stage tunes: the one with its model file, else its own name."""
    for s in setups:
        su = results.get("setups", {}).get(s)
        if su and _same_file(stage.get("model", ""), su["model_file"]):
            return s
    return stage.get("name", "")


def _targets_table(results: dict, setups: list) -> tuple[str, list[str]]:
    """The measured targets against the model as built and as tuned; the misses, as sentences."""
    rows, missed = [], []
    for st in (results.get("calibration") or {}).get("stages", []):
        s = _stage_setup(st, results, setups)
        for key, pct in (("targets", False), ("damping_targets", True)):
            for t in st.get(key, []):
                value, initial = t.get("value"), t.get("initial")
                before = initial / value - 1 if value and initial is not None else None
                shown = (lambda v: f"{100 * v:.4g} %") if pct else (lambda v: f"{v:.5g}")
                label = str(t.get("target", "")).split(" = ")[0]
                rows.append(
                    [
                        s,
                        label,
                        "-" if value is None else shown(value),
                        "-" if initial is None else shown(initial),
                        _verdict(before, t.get("tolerance")),
                        "-" if t.get("tuned") is None else shown(t["tuned"]),
                        _verdict(t.get("error"), t.get("tolerance"), t.get("met")),
                    ]
                )
                if not t.get("met", True):
                    missed.append(f"{s}: {label} missed by {100 * t['error']:+.2f} % even tuned")
    if not rows:
        return "", missed
    head = ["set-up", "target", "measured", "model as built", "verdict as built", "tuned", "verdict tuned"]
    text = (
        "<p>Key frequencies, measured against the model (the calibration's targets; a ratio to f1 "
        "where the study measured ratios). The tuned models are written beside this page.</p>"
    )
    return text + _table(head, rows), missed


def _attention(results: dict, setups: list, anchors: dict, runs, missed: list) -> str:
    items = []
    for r in runs:
        if r.status in ("failed", "skipped"):
            items.append(f"{_e(r.title)}: {_e(r.status)} - {_e(r.error)}")
    for s in setups:
        mesh = (results.get("setups", {}).get(s) or {}).get("mesh", {})
        if mesh and not mesh.get("converged", True):
            link = f'<a href="#{anchors[s]}">{_e(s)}</a>'
            items.append(f"{link}: mesh not converged for the range of interest - {_e(mesh.get('message'))}")
        check = _mesh_check(results, s)
        if check.get("flagged_modes"):
            modes = ", ".join(map(str, check["flagged_modes"]))
            items.append(
                f'<a href="#{anchors[s]}">{_e(s)}</a>: modes {_e(modes)} '
                f"estimated more than {100 * check['tolerance']:g} % from the mesh-converged frequency (the "
                "modes table's mesh error): more elements, or a max_hz to mesh for"
            )
        for part, e in (results.get("exports", {}).get(s) or {}).items():
            tol, err = e.get("free_hz_tolerance"), e.get("free_hz_error", [])
            bad = [k for k, x in enumerate(err) if tol is not None and x > tol]
            if bad:
                where = e.get("full_part_free_hz", [])
                since = f" (from {where[bad[0]]:.4g} Hz)" if bad[0] < len(where) else ""
                items.append(
                    f'<a href="#{anchors[s]}">{_e(s)}</a>: flexible body {_e(part)} - free-free modes '
                    f"{_e(', '.join(str(k + 1) for k in bad))}{since} more than {100 * tol:g} % from the "
                    "full part's"
                )
    items += [_e(m) + ' (see <a href="#calibration">Calibration</a>)' for m in missed]
    if not items:
        targets = ", every target met" if (results.get("calibration") or {}).get("stages") else ""
        return (
            f"<p>Nothing needs a look: every stage has its result, no mode flagged by a check{targets}.</p>"
        )
    return "<p>Needs a look:</p><ul>" + "".join(f"<li>{i}</li>" for i in items) + "</ul>"


def _measured(results: dict, setups: list) -> str:
    """One line per set-up with recordings: what was identified and trusted, and what calibration met
    and moved."""
    lines = []
    for s in setups:
        doc = results.get("measurement", {}).get(s)
        if doc is None:
            continue
        modes = doc["identified"]
        trusted = sum(m["frequency_target"] for m in modes)
        runs = len(doc["runs"])
        line = (
            f"{_e(s)}: {len(modes)} mode{'s' if len(modes) != 1 else ''} identified from {runs} "
            f"recording{'s' if runs != 1 else ''}, {trusted} trusted as targets"
        )
        cal = doc.get("calibration")
        if cal:
            met = sum(t["met"] for t in cal["targets"])
            moved = ", ".join(
                f"{_e(p['name'])} {p['change_percent']:+.2f} %"
                for p in cal["parameters"]
                if p.get("change_percent") is not None
            )
            line += f"; calibrated: {met} of {len(cal['targets'])} frequency targets met ({moved})"
        lines.append(f"<li>{line}.</li>")
    return f"<p>From the recordings:</p><ul>{''.join(lines)}</ul>" if lines else ""


def summary(results: dict, setups: list, anchors: dict, runs) -> str:
    """The report's summary as HTML: set-ups, key frequencies measured vs model with verdicts, and
    what needs a look.

    Parameters
    ----------
    results : dict
        The content of ``results.json``.
    setups : list of str
        The set-ups in the study's order.
    anchors : dict
        Each set-up's section id on the page.
    runs : sequence of StageRun
        How each stage went.
    """
    # what the results are, not how this run got them (ran or reused: the stages' table at the end)
    failed = sum(r.status in ("failed", "skipped") for r in runs)
    counts = f"{len(runs)} stages, " + (f"{failed} failed or skipped" if failed else "each with its result")
    targets, missed = _targets_table(results, setups)
    return (
        f"<p>{len(setups)} set-up{'s' if len(setups) != 1 else ''}; {counts}.</p>"
        + _setups_table(results, setups)
        + _measured(results, setups)
        + targets
        + _attention(results, setups, anchors, runs, missed)
    )

"""The report's "Measurement" section of a set-up: its recordings, the modes identified run by run (the
study's Tables 1-2), the stabilisation diagram, measured against the model before and after
calibration, the parameters with their bounds, and a verdict per target."""

from __future__ import annotations

import math
import os.path

from ..views.html import escape as _e
from ..views.html import table as _table

__all__ = ["measurement_section"]


def _num(x, spec: str) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def _pct(x, spec: str = ".3f") -> str:
    return "-" if x is None else format(100 * x, spec)


def _stats(values: list) -> tuple[str, str, str]:
    """Mean, standard deviation (n − 1) and range of the finite values, as the study's tables give them."""
    v = [x for x in values if x is not None and math.isfinite(x)]
    if not v:
        return "-", "-", "-"
    mean = sum(v) / len(v)
    std = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else math.nan
    return mean, std, (min(v), max(v))


def _runs_table(doc: dict) -> str:
    return _table(
        ["run", "file", "duration s", "rate Hz", "segments", "channels"],
        [
            [
                k + 1,
                os.path.basename(r["file"]),
                _num(r["duration_s"], ".4g"),
                _num(r["rate_hz"], ".6g"),
                r["segments"],
            ]
            + [", ".join(r["channels"])]
            for k, r in enumerate(doc["runs"])
        ],
    )


def _per_run_table(doc: dict) -> str:
    """Per run each mode's frequency and damping; then mean, standard deviation and range (Tables 1-2)."""
    modes = doc["identified"]
    runs = len(doc["runs"])
    head = ["run"] + [f"f{k + 1} Hz / ζ{k + 1} %" for k in range(len(modes))]
    rows = []
    for r in range(runs):
        rows.append(
            [r + 1]
            + [
                f"{_num(m['run_frequencies_hz'][r], '.4f')} / {_pct(m['run_damping_ratios'][r])}"
                for m in modes
            ]
        )
    for label, pick in (("mean", 0), ("std", 1), ("range", 2)):
        cells = []
        for m in modes:
            f, z = _stats(m["run_frequencies_hz"])[pick], _stats(m["run_damping_ratios"])[pick]
            if pick == 2 and f != "-":
                cells.append(f"{f[0]:.4f}…{f[1]:.4f} / {100 * z[0]:.3f}…{100 * z[1]:.3f}")
            else:
                fz = _num(f, ".4f") if f != "-" else "-"
                cells.append(f"{fz} / {_pct(z) if isinstance(z, float) and math.isfinite(z) else '-'}")
        rows.append([label] + cells)
    return _table(head, rows)


def _against_model(doc: dict) -> str:
    """Each identified mode against the model's paired mode, before and (tuned) after."""
    after = {
        t["mode"]: t for t in (doc.get("calibration") or {}).get("targets", []) if "ratio" not in t["target"]
    }
    rows = []
    for m in doc["identified"]:
        f, mode = m["frequency_hz"], m["paired_mode"]
        before = m["model_frequency_hz"]
        tuned = after.get(mode, {}).get("tuned")
        use = (
            "target"
            if m["frequency_target"] and m["damping_target"]
            else "frequency only: " + m["damping_doubt"]
            if m["frequency_target"]
            else m["frequency_doubt"] or m["unpaired"] or "-"
        )
        rows.append(
            [
                _num(f, ".4f"),
                _pct(m["damping_ratio"]),
                _num(m["mpc"], ".3f"),
                "-" if mode is None else mode,
                _num(before, ".4f"),
                "-" if before is None else f"{100 * (before / f - 1):+.3f}",
                _num(tuned, ".4f"),
                "-" if tuned is None else f"{100 * (tuned / f - 1):+.3f}",
                _num(m["mac"], ".3f"),
                use,
            ]
        )
    return _table(
        [
            "measured Hz",
            "damping %",
            "MPC",
            "mode",
            "model Hz",
            "error %",
            "tuned Hz",
            "error %",
            "MAC",
            "used as",
        ],
        rows,
    )


def _verdicts(cal: dict) -> str:
    """One line per target: met, or missed and by how much; a damping target with no damping parameter
    tuned is compared only (the model's ratio before and after)."""
    lines = []
    for t in cal.get("targets", []) + cal.get("damping_targets", []):
        miss = f"{100 * t['error']:+.3f} %"
        tol = f"{100 * t['tolerance']:.3g} %"
        if t in cal.get("damping_targets", []) and not cal.get("damping_tuned", True):
            lines.append(
                f"<li>{_e(t['target'])}: compared, not tuned (no damping parameter): the model has "
                f"{_pct(t['initial'])} % before, {_pct(t['tuned'])} % after</li>"
            )
        elif t["met"]:
            lines.append(f'<li class="verdict-ok">{_e(t["target"])}: met ({miss}, within ±{tol})</li>')
        else:
            lines.append(
                f'<li class="verdict-off">{_e(t["target"])}: missed by {miss} (tolerance ±{tol})</li>'
            )
    return "<ul>" + "".join(lines) + "</ul>" if lines else ""


def measurement_section(page, results: dict, s: str, stage_id: str | None) -> None:
    """Write set-up ``s``'s measurement section onto ``page`` (the study report's page)."""
    if stage_id is None:
        return
    page.heading(3, "Measurement")
    if page.failed(stage_id):
        return
    doc = results.get("measurement", {}).get(s)
    if doc is None:
        return
    band = doc["band"]
    page.add(
        f"<p>{len(doc['runs'])} recording(s), identified by SSI-COV between {band['min_hz']:.4g} and "
        f"{band['max_hz']:.4g} Hz ({_e(band['reason'])}); the targets calibrated to: "
        f"{_e(doc['targets_file'])}.</p>",
        _runs_table(doc),
        "<p>Each run's modes (frequency / damping ratio), their mean, standard deviation and range:</p>",
        _per_run_table(doc),
        page.figure(stage_id, "stabilisation", "stabilisation diagram of the first run"),
        "<p>Measured against the model before and after calibration (a doubted mode or damping is no "
        "target: why, in the last column):</p>",
        _against_model(doc),
    )
    if doc["notes"]:
        page.add("<ul>" + "".join(f"<li>{_e(n)}</li>" for n in doc["notes"]) + "</ul>")
    cal = doc.get("calibration")
    if not cal:
        return
    page.add(
        _table(
            ["parameter", "initial", "tuned", "lower", "upper", "change %"],
            [
                [
                    p["name"],
                    _num(p["initial"], ".6g"),
                    _num(p["tuned"], ".6g"),
                    _num(p["lower"], ".6g"),
                    _num(p["upper"], ".6g"),
                    _num(p.get("change_percent"), "+.3f"),
                ]
                for p in cal["parameters"]
            ],
        ),
        _verdicts(cal),
        f"<p>Tuned model: {_e(doc.get('tuned_model', '-'))}.</p>",
    )
    for k, r in enumerate(doc.get("responses", [])):
        page.add(
            f"<p>The study's FRF from {_e(r['input'])} on the tuned model (dashed: before calibration); "
            "largest resonance of each output: "
            + "; ".join(
                f"{_e(o['output'])} {o['before']['frequency_hz']:.4g} → {o['after']['frequency_hz']:.4g} Hz"
                for o in r["outputs"]
            )
            + ".</p>",
            page.figure(stage_id, f"frf {k + 1}", "FRF before and after calibration"),
        )

"""The report - of a study, and of ``flexshaft report MODEL`` (a study with the default plan): one
self-contained HTML page from results.json's content and the figures.

Every picture is a data URI (the page needs no second file and no network); every number on it
is in ``results.json`` beside it. The page opens on a summary (:mod:`.report_summary`: the set-ups,
key frequencies measured against the model, verdicts) and a table of contents linking every
section; then per set-up the parts and sections, twist test, mesh, modes with energy and damping
shares, FRFs, forced responses, time runs with their spectra, Campbell, mode views, exports and
the recordings (identified, and the set-up calibrated to them);
then the calibration; last the provenance and each stage's time. A stage that failed shows why, in
place of its section.
"""

from __future__ import annotations

from ..views.html import escape as _e
from ..views.html import img as _img
from ..views.html import table as _table

__all__ = ["study_html"]


def _g(x, spec: str = ".6g") -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, float)):
        return format(x, spec)
    return str(x)


def _shown(path: str, results: dict) -> str:
    """A file as the study names it: relative to the study file's folder (results.json has it whole)."""
    import os.path

    base = os.path.dirname(os.path.abspath(results["provenance"]["study_file"]))
    full = os.path.abspath(path)
    try:
        rel = os.path.relpath(full, base)
    except ValueError:  # another drive (Windows)
        return path
    return full if rel.startswith(os.pardir + os.sep + os.pardir) else rel


def _pct(x, spec: str = ".4f") -> str:
    return "-" if x is None else format(100 * x, spec)


class _Page:
    def __init__(self, figures: dict, runs: dict):
        self.parts: list[str] = []
        self.figures = figures
        self.runs = runs
        self.scripts = False  # a mode viewer is on the page: its scripts go in once
        self.headings: list[tuple[int, str, str]] = []  # (level, text, id): the table of contents
        self.prefix = "top"

    def add(self, *chunks: str) -> None:
        self.parts.extend(c for c in chunks if c)

    def heading(self, level: int, text: str, ident: str | None = None) -> None:
        """A section's heading with an id (HTML ids hold no spaces), listed in the table of contents."""
        from .plan import slug

        if ident is None:
            ident = f"{self.prefix}-{slug(text)}"
        taken = {h[2] for h in self.headings}
        base, n = ident, 2
        while ident in taken:
            ident, n = f"{base}-{n}", n + 1
        self.headings.append((level, text, ident))
        self.add(f'<h{level} id="{_e(ident)}">{_e(text)}</h{level}>')

    def contents(self) -> str:
        """The table of contents: every section (h2) with its subsections (h3), linked."""
        out, in_section, in_sub = ['<nav class="toc"><h2>Contents</h2><ul>'], False, False
        for level, text, ident in self.headings:
            link = f'<a href="#{_e(ident)}">{_e(text)}</a>'
            if level == 2:
                out += ["</ul>"] * in_sub + ["</li>"] * in_section + [f"<li>{link}"]
                in_section, in_sub = True, False
            elif level == 3:
                out += ["<ul>"] * (not in_sub) + [f"<li>{link}</li>"]
                in_sub = True
        out += ["</ul>"] * in_sub + ["</li>"] * in_section + ["</ul></nav>"]
        return "".join(out)

    def figure(self, stage_id: str, name: str, alt: str) -> str:
        png = self.figures.get(stage_id, {}).get(name)
        return _img(png, alt) if png else ""

    def failed(self, stage_id: str) -> bool:
        """Write the stage's failure (or skip) in place of its section; True if it did not run."""
        run = self.runs.get(stage_id)
        if run is None or run.status not in ("failed", "skipped"):
            return False
        self.add(f'<p class="failed">{_e(run.title)}: {_e(run.status)} - {_e(run.error)}</p>')
        return True


def _opening(page: _Page, results: dict) -> None:
    """What the reader needs before the numbers: the range of interest and the damping assumptions."""
    p = results["provenance"]
    if p.get("max_hz"):
        page.add(
            f"<p>Range of interest: up to {_g(p['max_hz'])} Hz - every shaft and CAD part is meshed so "
            "each mode below it is within 1 % of the mesh-converged frequency.</p>"
        )
    page.add(_damping_words(results))


def _provenance(page: _Page, results: dict, runs) -> None:
    p = results["provenance"]
    m = p.get("machine", {})
    page.prefix = "provenance"
    page.heading(2, "Provenance", "provenance")
    page.add(
        f"<p>flexshaft {_e(p['flexshaft'])}, {_e(p['date'])}, on {_e(m.get('host'))} "
        f"({_e(m.get('platform'))}, {_e(m.get('cpus'))} CPUs, Python {_e(m.get('python'))}, numpy "
        f"{_e(m.get('numpy'))}, SciPy {_e(m.get('scipy'))}). Study file {_e(p['study_file'])} "
        f"(SHA-256 {_e(str(p.get('study_sha256'))[:16])}…). Units: SI - N·m/rad, kg·m², m, N·m, rad, "
        "Hz; damping ratios in % in the tables, as fractions in results.json.</p>",
    )
    page.heading(3, "Stages")
    page.add(
        _table(
            ["stage", "status", "time s", "note"],
            [[r.title, r.status, f"{r.seconds:.2f}" if r.status == "ran" else "", _note(r)] for r in runs],
        ),
    )
    page.heading(3, "Input files")
    page.add(
        _table(
            ["file (from the study file's folder)", "SHA-256"],
            [[_shown(f, results), (h or "missing")[:16] + "…"] for f, h in p.get("inputs", {}).items()],
        ),
    )


def _note(run) -> str:
    """A stage's note: why it failed, or why it ran again although it had a stored result."""
    if run.error:
        return run.error
    return f"redone: {run.why}" if run.why else ""


def _damping_words(results: dict) -> str:
    p = results["provenance"]
    choice = p.get("damping", "parts")
    words = {
        "parts": "<b>per part</b>: each flexible part's own damping ratio on its own modes (the study's "
        "multibody model) - system modes get only the share of their strain energy the damped parts "
        "carry, so far less than the parts' ratio",
        "system": f"<b>system</b>: Rayleigh damping fitted so the first two elastic system modes carry "
        f"{_pct(p.get('system_damping_ratio'), '.3g')} % (the study's matrix model)",
    }
    if choice == "both":
        return (
            "<p>Damping: every response is computed twice, side by side - "
            + words["parts"]
            + "; and "
            + words["system"]
            + ". Resonant amplitudes scale with 1/damping: read each with its assumption.</p>"
        )
    return f"<p>Damping: {words[choice]}. Every amplitude below is under this assumption.</p>"


def _anchor(k: int) -> str:
    # HTML ids hold no spaces (a set-up's name may): the set-up's place in the study names it
    return f"setup-{k + 1}"


def _setup(page: _Page, results: dict, s: str, ids: dict, anchor: str) -> None:
    su = results["setups"].get(s)
    page.prefix = anchor
    page.heading(2, f"Set-up {s}", anchor)
    if page.failed(ids.get("setup")) or su is None:
        return
    mesh = su.get("mesh", {})
    page.add(
        f"<p>Model file {_e(_shown(su['model_file'], results))} (“{_e(su['model'])}”), "
        f"{_e(su['dofs'])} DOFs per node, "
        f"{_e(su['inertia_model'])} inertia.</p>",
        _table(
            ["component", "type", "stiffness N·m/rad", "inertia kg·m²", "elements", "damping ratio %"],
            [
                [
                    c["name"],
                    c["type"],
                    _g(c.get("stiffness")),
                    _g(c.get("inertia")),
                    _g(mesh.get("elements", {}).get(c["name"], c.get("elements"))),
                    _pct(c.get("damping_ratio"), ".3g") if c.get("damping_ratio") else "-",
                ]
                for c in su["components"]
            ],
        ),
    )
    if mesh:
        state = "converged" if mesh.get("converged", True) else "NOT converged"
        page.add(
            f"<p>Mesh for the range of interest: {_e(state)}"
            + (f" after {_e(mesh['rounds'])} round(s)" if "rounds" in mesh else "")
            + (f" - {_e(mesh['message'])}" if mesh.get("message") else "")
            + ".</p>"
        )
    parts = results["parts"].get(s)
    if parts:
        page.heading(3, "Parts from geometry")
        page.add(
            _table(
                ["part", "source", "material", "length m", "stiffness N·m/rad", "inertia kg·m²", "mass kg"],
                [
                    [
                        p["name"],
                        p["source"],
                        p["material"]["name"],
                        _g(p["length"], ".4g"),
                        _g(p["stiffness"]),
                        _g(p["inertia"]),
                        _g(p["mass"], ".5g"),
                    ]
                    for p in parts["parts"]
                ],
            ),
        )
        for p in parts["parts"]:
            page.add(_section_table(p))
    _twist(page, results, s, ids)
    _modes(page, results, s, ids)


def _section_table(part: dict) -> str:
    """One part's section table (``flexshaft sections``), folded: a CAD part has tens of rows."""
    t = part.get("table")
    if not t:
        return ""
    n = len(t["area"])
    check = part.get("mass_check")
    checked = (
        f" Table against the solid: volume {_g(check['volume_error'], '+.2e')}, axial inertia "
        f"{_g(check['axial_inertia_error'], '+.2e')} (relative)."
        if check
        else ""
    )
    rows = [
        [
            _g(t["x"][i], ".5f"),
            _g(t["x"][i + 1], ".5f"),
            _g(t["area"][i], ".5e"),
            _g(t["ip"][i], ".5e"),
            _g(t["j"][i], ".5e"),
            _g(t["shear_area_y"][i], ".5e"),
            _g(t["shear_area_z"][i], ".5e"),
            t["method"][i] if "method" in t else "",
        ]
        for i in range(n)
    ]
    source = f"Sliced from {part['geometry']}." if part.get("geometry") else ""
    head = ["x start m", "x end m", "area m²", "Ip m⁴", "J m⁴", "As,y m²", "As,z m²", "method"]
    return (
        f"<details><summary>Section table of {_e(part['name'])} ({n} intervals; Ip polar moment, J "
        f"St-Venant torsion constant, As shear areas)</summary><p>{_e(source + checked)}</p>"
        f"{_table(head, rows)}</details>"
    )


def _twist(page: _Page, results: dict, s: str, ids: dict) -> None:
    page.heading(3, "Twist test")
    if page.failed(ids.get("twist")):
        return
    t = results["twist"].get(s)
    if t is None:
        return
    page.add(
        f"<p>Clamped at {_e(t['clamp'])}, {_g(t['torque'])} N·m at {_e(t['load'])}: clamp to load "
        f"{_g(t['total_stiffness'])} N·m/rad; the same at every torque of the ramp (spread "
        f"{_g(t['load_spread'], '.1e')}).</p>",
        _table(
            ["part", "stiffness N·m/rad", "twist rad", "torque N·m"],
            [
                [p["name"], _g(p["stiffness"], ".4e"), _g(p["twist"], ".4e"), _g(p["torque"], ".4g")]
                for p in t["parts"]
            ],
        ),
        page.figure(ids["twist"], "twist", "twist along the shaft"),
    )


def _modes(page: _Page, results: dict, s: str, ids: dict) -> None:
    page.heading(3, "Modes")
    if page.failed(ids.get("modes")):
        return
    docs = results["modes"].get(s)
    if not docs:
        return
    variants = list(docs)
    first = docs[variants[0]]
    head = ["mode", "frequency Hz"] + [f"damping % ({v})" for v in variants] + ["dominant (strain energy)"]
    mesh = "mesh_check" in first
    if mesh:
        head.append("mesh error %")
    rows = []
    for k, m in enumerate(first["modes"]):
        row = [m["index"], _g(m["frequency_hz"], ".4f")]
        for v in variants:
            mv = docs[v]["modes"][k]
            row.append("-" if mv["rigid"] else _pct(mv["damping_ratio"]))
        row.append("rigid-body mode" if m["rigid"] else m["dominant_component"])
        if mesh:
            err = m.get("mesh_error")
            row.append(
                "-"
                if m["rigid"] or err is None
                else (f"{100 * err:.2g}" + (" ⚠" if err > first["mesh_check"]["tolerance"] else ""))
            )
        rows.append(row)
    shown = len(first["modes"])
    page.add(f"<p>{shown} modes listed ({first['n_dof']} DOFs in the model).</p>", _table(head, rows))
    # damping shares: which component gives each mode its damping (per variant)
    for v in variants:
        contrib = [m.get("damping_contribution") for m in docs[v]["modes"] if not m["rigid"]]
        if contrib and contrib[0]:
            names = list(contrib[0])
            page.add(
                f"<p>Damping shares ({_e(v)}): each component's part of the mode's damping ratio, %.</p>",
                _table(
                    ["mode"] + names,
                    [
                        [m["index"]] + [_pct(m["damping_contribution"][n], ".3g") for n in names]
                        for m in docs[v]["modes"]
                        if not m["rigid"]
                    ],
                ),
            )
    page.add(
        page.figure(ids["modes"], "energy", "strain energy by component"),
        page.figure(ids["modes"], "shapes", "mode shapes along the shaft"),
    )


def _responses(page: _Page, results: dict, s: str, ids: dict) -> None:
    if "frf" in ids:
        page.heading(3, "Frequency response")
        if not page.failed(ids["frf"]):
            for k, e in enumerate(results["frf"].get(s, [])):
                page.add(f"<p>{_e(e['input'])} → {_e(', '.join(e['outputs']))}</p>")
                for v, doc in e["variants"].items():
                    units = doc.get("units", {})
                    per = dict(zip(doc.get("outputs", []), units.get("output", [])))
                    into = (units.get("input") or [""])[0]
                    page.add(
                        f"<p>damping: {_e(doc.get('damping_is', v))}</p>",
                        _table(
                            ["output", "peak Hz", "|H|", "unit", "half-power damping %"],
                            [
                                [
                                    p.get("output", ""),
                                    _g(p["frequency_hz"], ".4f"),
                                    _g(p["magnitude"], ".4g"),
                                    f"{per.get(p.get('output'), '?')} per {into}",
                                    _pct(p.get("damping_ratio")),
                                ]
                                for p in doc["peaks"]
                            ],
                        ),
                        page.figure(ids["frf"], f"frf {k + 1} {v}", f"Bode plot {k + 1} ({v})"),
                    )
    if "forced" in ids:
        page.heading(3, "Forced response at the eigenfrequencies")
        if not page.failed(ids["forced"]):
            for e in results["forced"].get(s, []):
                for v, doc in e["variants"].items():
                    parts = (
                        [k for k in doc["excitations"][0]["amplitude"] if k.startswith("torque:")]
                        if doc["excitations"]
                        else []
                    )
                    page.add(
                        f"<p>{_g(e['amplitude'])} N·m at {_e(e['input'])}, damping: {_e(v)} - peak dynamic "
                        "torque per part, N·m</p>",
                        _table(
                            ["mode", "frequency Hz"] + [p[7:] for p in parts] + ["largest"],
                            [
                                [x["mode"], _g(x["frequency_hz"], ".4f")]
                                + [_g(x["amplitude"][p], ".4g") for p in parts]
                                + [x["largest_torque"]]
                                for x in doc["excitations"]
                            ],
                        ),
                    )
    for run_id in ids.get("simulate", []):
        name = run_id.split("/", 2)[2]
        page.heading(3, f"Time run {name}")
        if page.failed(run_id):
            continue
        runs = results["simulation"].get(s, {}).get(name, {})
        spectra = results["spectra"].get(s, {}).get(name, {})
        for v, doc in runs.items():
            page.add(
                f"<p>{_e(doc['scenario'])}, {_g(doc['duration_s'])} s at {_g(doc['rate_hz'])} Hz "
                f"({doc['samples']} samples, {_e(doc['method'])}), damping: {_e(v)}; samples in "
                f"{_e(doc['samples_file'])}</p>",
                _table(
                    ["output", "unit", "min", "max", "final"],
                    [
                        [n, o["unit"], _g(o["min"], ".5g"), _g(o["max"], ".5g"), _g(o["final"], ".5g")]
                        for n, o in doc["outputs"].items()
                    ],
                ),
                page.figure(run_id, f"run {v}", f"time run ({v})"),
            )
            if "nonlinear" in doc:
                page.add(*_nonlinear_run(doc["nonlinear"]))
            for sig, a in spectra.get(v, {}).get("signals", {}).items():
                page.add(
                    f"<p>Spectrum of {_e(sig)}: {_e(a['method'])}, resolution "
                    f"{_g(a['resolution_hz'], '.4g')} Hz</p>",
                    _table(
                        ["frequency Hz", "amplitude", "damping %", "mode", "note"],
                        [
                            [
                                _g(p["frequency_hz"], ".4f"),
                                _g(p["amplitude"], ".4g"),
                                _pct(p.get("damping_ratio")),
                                _g(p.get("mode")),
                                p.get("damping_missing") or "",
                            ]
                            for p in a["peaks"]
                        ],
                    ),
                    _no_peak_note(a),
                    page.figure(run_id, f"spectrum {sig} {v}", f"spectrum of {sig}"),
                    page.figure(run_id, f"spectrogram {sig} {v}", f"spectrogram of {sig}"),
                )
    if "campbell" in ids:
        page.heading(3, "Campbell diagram")
        if not page.failed(ids["campbell"]):
            c = results["campbell"].get(s)
            if c:
                page.add(
                    _table(
                        ["speed rpm", "order", "mode", "frequency Hz", "damping %"],
                        [
                            [
                                _g(x["speed_rpm"], ".2f"),
                                _g(x["order"]),
                                x["mode"],
                                _g(x["frequency_hz"], ".4f"),
                                _pct(x["damping_ratio"]),
                            ]
                            for x in c["crossings"]
                        ],
                    )
                    if c["crossings"]
                    else "<p>No order line crosses a mode in this speed range.</p>",
                    page.figure(ids["campbell"], "campbell", "Campbell diagram"),
                )


def _no_peak_note(a: dict) -> str:
    """Why a spectrum's peak table is empty, where the plot shows its resonances all the same."""
    if a["peaks"]:
        return ""
    t = a.get("peak_threshold")
    if not t:
        return "<p>No peak listed: none passes the peak test (see flexshaft.find_peaks).</p>"
    return (
        f"<p>No peak listed: none reaches the threshold, {_g(t['relative'], 'g')} of the largest amplitude "
        f"above 0 Hz ({_g(t['amplitude'], '.3g')} {_e(a['unit'])}, the dotted line; the largest is at "
        f"{_g(t['largest_hz'], '.3g')} Hz). The "
        "resonances the plot shows at the model's eigenfrequencies (dashed) lie below it.</p>"
    )


def _drivetrain_exports(e: dict) -> str:
    """What a drivetrain export wrote: the FMU (its interface and damping) and the modes' universal file."""
    items = []
    if f := e.get("fmu"):
        what = f"built for {f['platform']}" if f.get("platform") else _e(f.get("note") or "sources only")
        items.append(
            f"<li>FMU (FMI {_e(f['fmi_version'])}, model exchange and co-simulation) {_e(f['path'])}: "
            f"{f['states']} states; inputs (N·m) {_e(', '.join(f['inputs']))}; outputs "
            f"{_e(', '.join(f['outputs']))}; damping_variant starts at {_e(f['damping_variant'])}; "
            f"{what}</li>"
        )
    if u := e.get("uff"):
        items.append(
            f"<li>Universal file {_e(u['path'])}: {u['modes']} modes ({_e(u['damping'])} damping), SI</li>"
        )
    return "<ul>" + "".join(items) + "</ul>"


def _views_exports(page: _Page, results: dict, s: str, ids: dict) -> None:
    if "views" in ids:
        page.heading(3, "Mode shapes in 3D")
        if not page.failed(ids["views"]):
            v = results["views"].get(s, {})
            if v.get("note"):
                page.add(f"<p>{_e(v['note'])}</p>")
            blob = page.figures.get(ids["views"], {}).get("viewer")
            if blob:
                import json

                from ..views.webview import viewer_block

                page.scripts = True
                page.add(
                    "<p>Turn, zoom and pan with the mouse; pick the mode, colour and exaggeration above the "
                    "drawing. Below: stills of the first modes.</p>",
                    viewer_block(json.loads(blob), f"fs-viewer-{len(page.parts)}"),
                )
            for m in v.get("modes", []):
                page.add(
                    f"<h4>Mode {m['mode']}: {_g(m['frequency_hz'], '.4g')} Hz</h4>",
                    page.figure(ids["views"], f"mode {m['mode']}", f"mode {m['mode']} in 3D"),
                )
    for ex_id in ids.get("export", []):
        part = ex_id.split("/", 2)[2]
        e = results["exports"].get(s, {}).get(part)
        if e is not None and "formats" in e:  # the whole drivetrain (an export without a part)
            page.heading(3, "The drivetrain, exported")
            if not page.failed(ex_id):
                page.add(_drivetrain_exports(e))
            continue
        page.heading(3, f"Flexible body {part}")
        if page.failed(ex_id):
            continue
        if not e:
            continue
        chk = e.get("check", {})
        page.add(
            f"<p>{e.get('part_dofs')} DOFs → {e.get('boundary_dofs')} boundary DOFs + {e.get('modes')} "
            f"fixed-interface modes + {e.get('residual_vectors')} residual vectors. cb_check: rigid-body "
            f"mass error {_g(chk.get('rigid_mass_error'), '.1e')}, interface stiffness against static "
            f"condensation {_g(chk.get('static_error'), '.1e')} (relative).</p>",
            _body_modes(e),
            page.figure(ex_id, "reduction", f"{part}: flexible body against the full part"),
            "<p>Files: " + ", ".join(_e(f) for f in e.get("files", [])) + "</p>",
        )


def _body_modes(e: dict) -> str:
    """A flexible body's free-free modes against the full part's, each with its reduction error and a
    flag past the tolerance the study holds its meshes to (a body mode worse than that is less
    accurate than the mesh it was reduced from: fine for a body used below it, not above)."""
    full, err = e.get("full_part_free_hz", []), e.get("free_hz_error", [])
    tol = e.get("free_hz_tolerance")
    rows, flagged, k = [], 0, 0
    for f, z in zip(e.get("free_hz", []), e.get("damping_ratios", [])):
        row = [_g(f, ".2f"), _pct(z, ".3f")]
        if full and f <= 0:  # a rigid-body mode: the full part's list holds the elastic ones
            row += ["-", "-", ""]
        elif full:
            bad = k < len(err) and tol is not None and err[k] > tol
            flagged += bad
            row += [
                _g(full[k], ".2f") if k < len(full) else "-",
                _g(100 * err[k], ".2g") if k < len(err) else "-",
                ("⚠ past " + _g(100 * tol) + " %") if bad else "",
            ]
            k += 1
        rows.append(row)
    head = ["free-free mode Hz", "damping %"]
    if full:
        head += ["full part Hz", "reduction error %", "accuracy"]
    note = ""
    if flagged:
        note = (
            f'<p class="flag">{flagged} of the body\'s modes are more than {_g(100 * tol)} % from the full '
            "part's (the study's mesh tolerance): use the body only below the first flagged mode, or "
            "reduce with more modes (a higher cutoff_hz).</p>"
        )
    return _table(head, rows) + note


def _calibration(page: _Page, results: dict, stage_id: str | None) -> None:
    if stage_id is None:
        return
    page.prefix = "calibration"
    page.heading(2, "Calibration", "calibration")
    if page.failed(stage_id):
        return
    c = results["calibration"]
    for st in c.get("stages", []):
        page.heading(3, f"Stage {st['name']}")
        page.add(
            f"<p>model {_e(st['model'])}; tuned model "
            f"{_e(st.get('tuned_model', '-'))}; cost {_g(st.get('cost'), '.4g')}.</p>"
        )
        if st.get("carried"):
            page.add(
                "<p>Carried, fixed: "
                + ", ".join(f"{_e(k)} = {_g(v)}" for k, v in st["carried"].items())
                + "</p>"
            )
        params = st.get("parameters", [])
        if params:
            page.add(
                _table(
                    ["parameter", "initial", "tuned", "lower", "upper", "change %", "at bound"],
                    [
                        [
                            p.get("name"),
                            _g(p.get("initial")),
                            _g(p.get("tuned")),
                            _g(p.get("lower")),
                            _g(p.get("upper")),
                            _g(p.get("change_percent"), ".3f"),
                            p.get("active_bound") or "",
                        ]
                        for p in params
                    ],
                )
            )
        # frequency targets and damping targets: one table each, the same columns
        for key, first, value, unit in (
            ("targets", "target", lambda v: _g(v, ".5g"), ""),
            ("damping_targets", "damping target", lambda v: _pct(v, ".4f"), " %"),
        ):
            targets = st.get(key, [])
            if targets:
                page.add(
                    _table(
                        [first, "mode", "initial" + unit, "tuned" + unit, "error %", "tolerance %", "met"],
                        [
                            [
                                t.get("target"),
                                t.get("mode"),
                                value(t.get("initial")),
                                value(t.get("tuned")),
                                _pct(t.get("error"), ".3f"),
                                _pct(t.get("tolerance"), ".2f"),
                                _g(t.get("met")),
                            ]
                            for t in targets
                        ],
                    )
                )
        for u in st.get("unmet", []):
            need = "; ".join(
                f"{e['parameter']} {e['change_percent']:+.1f} %" for e in u.get("alone_would_need", [])
            )
            page.add(
                f"<p>{_e(u['target'])} is missed by {_pct(u['error'], '+.2f')} %: alone it would need "
                f"{_e(need)}.</p>"
            )


_STYLE = (
    "body{font-family:sans-serif;max-width:1150px;margin:2em auto;color:#222;line-height:1.4}"
    "table{border-collapse:collapse;margin:.6em 0 1.2em}td,th{border:1px solid #bbb;padding:3px 8px;"
    "text-align:right}th{background:#eee}td:first-child,th:first-child{text-align:left}"
    "img{max-width:100%;display:block;margin:1em 0}.failed{color:#a00;font-weight:bold}"
    "h2{border-bottom:2px solid #ccc;margin-top:2em}.toc ul{margin:.2em 0;padding-left:1.4em}"
    ".toc>ul>li{margin:.3em 0}.toc ul ul li{display:inline;margin-right:1em}.flag{color:#a00}"
    ".verdict-ok{color:#060}.verdict-off{color:#a00;font-weight:bold}"
)


def study_html(results: dict, figures: dict, stages, runs) -> str:
    """The study report as one HTML document.

    Parameters
    ----------
    results : dict
        The content of ``results.json``.
    figures : dict
        ``stage id -> {figure name -> PNG bytes}``.
    stages : sequence of Stage
        The study's stages (their ids say which set-up and entry each belongs to).
    runs : sequence of StageRun
        How each stage went (failed and skipped stages are shown with their reason).
    """
    from .report_measurement import measurement_section
    from .report_summary import summary

    page = _Page(figures, {r.id: r for r in runs})
    setups = list(dict.fromkeys(st.setup for st in stages if st.setup is not None))
    anchors = {s: _anchor(k) for k, s in enumerate(setups)}
    page.heading(2, "Summary", "summary")
    page.add(summary(results, setups, anchors, runs))
    _opening(page, results)
    body_from = len(page.parts)
    for s in setups:
        ids: dict = {}
        for st in stages:
            if st.setup != s:
                continue
            if st.kind in ("simulate", "export"):
                ids.setdefault(st.kind, []).append(st.id)
            else:
                ids[st.kind] = st.id
        _setup(page, results, s, ids, anchors[s])
        _responses(page, results, s, ids)
        _views_exports(page, results, s, ids)
        measurement_section(page, results, s, ids.get("measurement"))
    _calibration(page, results, next((st.id for st in stages if st.kind == "calibration"), None))
    _provenance(page, results, runs)
    page.parts.insert(body_from, page.contents())
    title = _e(results["provenance"]["study"])
    scripts, csp = "", ""
    if page.scripts:  # the mode viewer's scripts, once; the page may then run only its own inline code
        from ..views.webview import VIEWER_CSP, viewer_scripts

        scripts = viewer_scripts()
        csp = f'<meta http-equiv="Content-Security-Policy" content="{VIEWER_CSP}">'
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">{csp}<title>{title} - flexshaft study'
        f"</title><style>{_STYLE}</style></head><body>{scripts}<h1>{title}</h1>\n"
        + "\n".join(page.parts)
        + "</body></html>\n"
    )


def _nonlinear_run(doc: dict) -> tuple:
    """The nonlinear elements of a time run: what each did, and how its events were found."""
    from ..analysis.hybrid import ACTIVE_MEANS as active

    return (
        f"<p>Nonlinear elements: {doc['events']} events ({_e(doc['tolerance'])}).</p>",
        _table(
            ["element", "law", "events", "time active s", "active means", "peak torque N·m", "dissipated J"],
            [
                [
                    e["name"],
                    e["law"],
                    e["events"],
                    _g(e["active_time_s"], ".6g"),
                    active[e["law"]],
                    _g(e["peak_torque"], ".6g"),
                    _g(e["dissipated_J"], ".6g") if e["law"] == "slip" else "",
                ]
                for e in doc["elements"]
            ],
        ),
    )

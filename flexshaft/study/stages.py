"""What each stage of a study does: the library's stage functions, called as the CLI calls them.

Every stage takes the context (the memoised set-ups and modes), the stage and the output folder,
and returns an :class:`~flexshaft.study.plan.Output`: JSON-able results (SI, units stated),
figures as PNG bytes, and the files it wrote into the folder. Responses that depend on damping
(modes, FRF, forced response, time runs and their spectra) are computed under each damping
assumption the study names (``"parts"``, ``"system"``), side by side, and every result says
which one it is under.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.systemdamping import DAMPING_DESCRIPTIONS
from ..errors import ModelError
from .folder import folder_for
from .measurementstage import run_measurement
from .plan import Output, Stage, slug

__all__ = ["STAGES"]


def _png(fig) -> bytes:
    from ..views.plots import png

    return png(fig)


def _variant_doc(study, variant: str) -> dict:
    doc = {"damping": variant, "damping_is": DAMPING_DESCRIPTIONS[variant]}
    if variant == "system":
        doc["system_damping_ratio"] = study.system_damping_ratio
    return doc


def _damping_title(study, variant: str) -> str:
    """A damping assumption in a few words, for a figure's title (the full text is in the report)."""
    short = DAMPING_DESCRIPTIONS[variant].split(":")[0]
    if variant == "system":
        return f"{short}, {100 * study.system_damping_ratio:.3g} % on the first two elastic modes"
    return short


def _elastic(result, count: int | None = None) -> list[int]:
    idx = [i for i in range(result.count) if not result.rigid[i]]
    return idx if count is None else idx[:count]


# --- model stages ----------------------------------------------------------------------------------


def _mesh_doc(choice) -> dict:
    """The mesh chosen for the range of interest (a :class:`MeshChoice`), as plain numbers."""
    return {
        "max_hz": choice.max_hz,
        "converged": bool(choice.converged),
        "rounds": int(choice.rounds),
        "message": choice.message,
        "elements": {str(k): int(v) for k, v in choice.elements.items()},
        "fixed_by_the_file": list(choice.fixed),
    }


def run_setup(ctx, stage: Stage, folder: Path) -> Output:
    """Load the set-up's model file, mesh it for the range of interest: components and sections."""
    from ..model.describe import component_summary, sections_document

    spec = ctx.study.setup(stage.setup)
    choice = ctx.mesh_choice(stage.setup)
    d = choice.drivetrain
    shafts = [c for c in d.components if getattr(c, "sections", None) is not None]
    setup = {
        "model_file": str(spec.model),
        "model": d.name,
        "dofs": d.dofs,
        "inertia_model": d.inertia_model,
        "units": {"stiffness": "N·m/rad", "inertia": "kg·m²", "length": "m", "frequency": "Hz"},
        "components": [component_summary(c) for c in d.components],
        "mesh": _mesh_doc(choice),
    }
    return Output({"setups": setup, "parts": sections_document(shafts) if shafts else None})


def run_twist(ctx, stage: Stage, folder: Path) -> Output:
    """The twist test: clamped at the driving end, 1 kN·m at the far end; per-part stiffness."""
    from ..analysis.twist import twist_test

    result = twist_test(ctx.drivetrain(stage.setup), 1000.0)
    return Output({"twist": result.to_dict()}, {"twist": _png(result.plot())})


def run_modes(ctx, stage: Stage, folder: Path) -> Output:
    """Modes and damped modes (each damping assumption), energy and damping shares, the mesh check."""
    from ..analysis.convergence import mesh_convergence

    study = ctx.study
    docs, figures, mesh = {}, {}, None
    for k, variant in enumerate(study.variants):
        result = ctx.modes(stage.setup, variant)
        if k == 0 and study.modes.mesh_check:
            mesh = mesh_convergence(result)  # undamped: the same for every damping assumption
        doc = result.to_dict(max_hz=ctx.max_hz(stage.setup), mesh=mesh, count=study.modes.count)
        docs[variant] = _variant_doc(study, variant) | doc
        if k == 0:
            listed = [m["index"] for m in doc["modes"] if not m["rigid"]]
            if listed:
                figures["energy"] = _png(result.plot("strain", modes=listed[:12]))
                figures["shapes"] = _png(result.plot("shapes", modes=listed[:4]))
    return Output({"modes": docs}, figures)


def run_views(ctx, stage: Stage, folder: Path) -> Output:
    """3D pictures of the chosen modes on the drivetrain's surface."""
    result = ctx.modes(stage.setup)
    wanted = ctx.study.views.modes
    if wanted is None:
        wanted = _elastic(result, 3)
    for m in wanted:
        if m >= result.count:
            raise ModelError(
                "no such mode among those computed",
                component="[views]",
                field="modes",
                value=m,
                valid=f"0 … {result.count - 1} (or raise [modes] count)",
            )
    figures, shown = {}, []
    try:
        from ..views.render import mode_picture

        for m in wanted:
            figures[f"mode {m}"] = mode_picture(result, m)
            shown.append({"mode": m, "frequency_hz": float(result.frequencies_hz[m]), "figure": f"mode {m}"})
        note = None
    except ImportError:  # pyvista missing: the numbers stand, the pictures say why they are absent
        note = "no 3D pictures: pyvista is not installed (pip install flexshaft[view])"
        shown = [{"mode": m, "frequency_hz": float(result.frequencies_hz[m])} for m in wanted]
    doc = {"units": {"frequency": "Hz"}, "modes": shown, "colour": "twist (θx, max-normalised)"}
    if note:
        doc["note"] = note
    # the browser viewer: the elastic modes the modes stage lists, JSON beside the pictures
    import json

    from ..views.webview import viewer_data

    data = viewer_data(result, max_hz=ctx.max_hz(stage.setup))
    figures["viewer"] = json.dumps(data, separators=(",", ":")).encode("utf-8")
    doc["viewer_modes"] = [m["index"] for m in data["modes"]]
    return Output({"views": doc}, figures)


# --- responses -------------------------------------------------------------------------------------


def _frf_doc(resp) -> dict:
    """``flexshaft frf --json``'s document, with the peaks of every output (each labelled)."""
    peaks = [p | {"output": o} for j, o in enumerate(resp.outputs) for p in resp.peaks(output=j)]
    return resp.to_dict() | {"peaks": peaks}


def run_frf(ctx, stage: Stage, folder: Path) -> Output:
    """Frequency responses between named signals, under each damping assumption."""
    from ..analysis.statespace import default_frf_range, frequency_grid, frequency_response, state_space

    study = ctx.study
    entries, figures = [], {}
    for k, e in enumerate(stage.config["frf"]):
        entry = {"input": e["input"], "outputs": list(e["outputs"]), "variants": {}}
        for variant in study.variants:
            result = ctx.response_modes(stage.setup, variant)
            entry["input"] = at = e["input"] or result.model.stations[0].name  # None: the driving end
            ss = state_space(result, [at], list(e["outputs"]), max_hz=None)
            f_from, f_to = default_frf_range(ss, e["from_hz"], e["to_hz"] or ctx.max_hz(stage.setup))
            resp = frequency_response(ss, frequency_grid(ss, f_from, f_to, e["points"]))
            entry["variants"][variant] = _variant_doc(study, variant) | _frf_doc(resp)
            figures[f"frf {k + 1} {variant}"] = _png(resp.plot(damping=_damping_title(study, variant)))
        entries.append(entry)
    return Output({"frf": entries}, figures)


def run_forced(ctx, stage: Stage, folder: Path) -> Output:
    """Sinusoidal torque at each eigenfrequency: the dynamic torque every part carries."""
    from ..analysis.forced import forced_response

    study = ctx.study
    entries = []
    for e in stage.config["forced"]:
        entry = {"input": e["input"], "amplitude": e["amplitude"], "variants": {}}
        for variant in study.variants:
            result = ctx.response_modes(stage.setup, variant)
            top = ctx.max_hz(stage.setup)  # the excitations stop at the range of interest
            fr = forced_response(result, e["input"], amplitude=e["amplitude"], max_hz=top)
            entry["input"] = fr.input  # the station named, or the driving end
            entry["variants"][variant] = _variant_doc(study, variant) | fr.to_dict()
        entries.append(entry)
    return Output({"forced": entries})


def _speed_signal(result, cfg) -> str:
    """The speed output whose mean gives the orders: the driving station's."""
    at = cfg["options"].get("at") or result.model.stations[0].name
    return f"speed:{at}"


def run_simulate(ctx, stage: Stage, folder: Path) -> Output:
    """A time run under each damping assumption; the spectra (and spectrogram) of its outputs."""
    from ..analysis.scenario import Scenario
    from ..analysis.simulate import simulate
    from ..measurement.analyse import analyse_signal
    from ..measurement.peaks import MIN_RELATIVE, peak_threshold
    from ..measurement.signalfile import read_torque_history, write_signals
    from ..measurement.spectrogram import spectrogram
    from ..views.plots import listed_peaks, simulation_figure, spectrogram_figure, spectrum_figure

    study, cfg = ctx.study, stage.config
    runs, spectra, figures, files = {}, {}, {}, []
    torque = None
    if cfg["scenario"] == "csv":
        try:
            torque = read_torque_history(cfg["series"], cfg["column"])
        except ModelError as err:
            raise err.located(component=f"[[simulate]] {stage.name!r}") from None
    for variant in study.variants:
        result = ctx.response_modes(stage.setup, variant)
        sc = Scenario.of(cfg["scenario"], cfg["options"], result, series=torque)
        outputs = list(cfg["outputs"])
        speed = _speed_signal(result, cfg)
        extra = speed not in outputs
        run = simulate(
            result,
            sc,
            outputs + ([speed] if extra else []),
            rate=cfg["rate_hz"],
            duration=cfg["duration_s"],
            max_hz=cfg["max_hz"],
        )
        rel = f"runs/{slug(stage.setup)}/{slug(stage.name)}-{variant}.csv"
        folder_for(folder, rel)
        cols = {n: (y, run.units[n]) for n, y in run.outputs.items()}
        write_signals(folder / rel, run.time, cols, overwrite=True)
        files.append(rel)
        runs[variant] = (
            _variant_doc(study, variant)
            | {"scenario": cfg["scenario"]}
            | run.to_dict(outputs)
            | {"samples_file": rel}
        )
        if sc.control is not None:
            c = sc.control
            runs[variant]["speed_loop"] = {
                "kp": c.kp,
                "ki": c.ki,
                "tau": c.tau,
                "torque_min": c.torque_min,
                "torque_max": c.torque_max,
                "power_limit": c.power_limit if c.power_limit != float("inf") else None,
                "units": {"kp": "N·m·s/rad", "ki": "N·m/rad", "tau": "s", "torque": "N·m", "power": "W"},
            }
        figures[f"run {variant}"] = _png(simulation_figure(run, outputs))
        speed_rpm = run.outputs[speed] * 30.0 / np.pi
        moving = float(np.ptp(speed_rpm)) > 1e-6 * max(1.0, float(np.max(np.abs(speed_rpm))))
        eigen = [(int(i), float(f)) for i, f in enumerate(result.frequencies_hz) if not result.rigid[i]]
        decay = cfg["decay"] if cfg["decay"] is not None else cfg["scenario"] == "coast"
        want_sg = cfg["spectrogram"] if cfg["spectrogram"] is not None else moving
        per = {}
        for name in cfg["spectra"] or outputs:
            a = analyse_signal(
                run.time,
                run.outputs[name],
                name=name,
                unit=run.units[name],
                decay=decay,
                speed_rpm=speed_rpm,
                eigenfrequencies=eigen,
            )
            # the threshold the peaks passed: the report says it where no peak is listed
            threshold, largest = peak_threshold(a.spectrum)
            floor = {"amplitude": threshold, "relative": MIN_RELATIVE, "largest_hz": largest}
            per[name] = a.to_dict() | {"peak_threshold": floor}
            marks = [f for _, f in eigen if f <= 0.5 * run.rate_hz]
            unit = run.units[name]
            title = f"{name} [{unit}]"
            figures[f"spectrum {name} {variant}"] = _png(
                spectrum_figure(
                    a.spectrum,
                    title=f"{title}: {a.method}",
                    unit=unit,
                    marks=marks,
                    **listed_peaks(a, threshold),
                )
            )
            if want_sg:
                sg = spectrogram(run.outputs[name], run.rate_hz, segment=1.0, window="hann", speed=speed_rpm)
                figures[f"spectrogram {name} {variant}"] = _png(
                    spectrogram_figure(
                        sg, orders=cfg["orders"], eigenfrequencies=marks, title=title, unit=unit
                    )
                )
        spectra[variant] = _variant_doc(study, variant) | {"signals": per}
    return Output({"simulation": runs, "spectra": spectra}, figures, tuple(files))


def run_campbell(ctx, stage: Stage, folder: Path) -> Output:
    """Modes against speed with the order lines, and their crossings."""
    from ..analysis.campbell import campbell

    cfg = ctx.study.variants[0]
    result = ctx.response_modes(stage.setup, cfg)
    diagram = campbell(result, tuple(stage.config["speed_rpm"]), tuple(stage.config["orders"]))
    doc = _variant_doc(ctx.study, cfg) | diagram.to_dict()
    return Output({"campbell": doc}, {"campbell": _png(diagram.plot())})


# --- exports and calibration -----------------------------------------------------------------------


def run_export(ctx, stage: Stage, folder: Path) -> Output:
    """A part as a Craig–Bampton flexible body in every format asked, with its check; or the whole
    drivetrain as an FMU and its modes as a universal file."""
    from ..exports.bodies import write_flexible_body
    from ..model.reduce import reduce_part

    e = stage.config
    if e["part"] is None:
        return _export_drivetrain(ctx, stage, folder)
    d = ctx.drivetrain(stage.setup)
    comp = d.component(e["part"])
    modes, cutoff = e["modes"], e["cutoff_hz"]
    if modes is None and cutoff is None and getattr(comp, "reduce", None) is None:
        if ctx.max_hz(stage.setup) is not None:
            cutoff = ctx.max_hz(stage.setup)  # the part's own modes up to the range of interest
        else:
            modes = 6
    red = reduce_part(d, e["part"], modes=modes, cutoff_hz=cutoff, damping_ratio=e["damping_ratio"])
    files = []
    for fmt in e["formats"]:
        rel = f"exports/{slug(stage.setup)}/{slug(e['part'])}.{fmt}"
        folder_for(folder, rel)
        if fmt == "uff":  # the body's free-free modes, for the test lab
            from ..exports.universalfile import write_body_uff

            path = write_body_uff(red, folder / rel, overwrite=True)
        else:
            path = write_flexible_body(red.body, folder / rel, material=comp.material, overwrite=True)
        files.append(rel)
        # a format with a sidecar (op4, pch) writes it beside the matrices: the cache checks it too
        for side in sorted(Path(path).parent.glob(Path(path).name + ".*")):
            files.append(str(side.relative_to(folder)))
    # cb_check's figure: the body's free-free modes against the full part's (the reduction's accuracy)
    from ..analysis.convergence import DEFAULT_MESH_TOLERANCE
    from ..analysis.modal import part_modes
    from ..views.plots import reduction_figure

    reduced = red.body.free_hz[red.body.free_hz > 0]
    full = part_modes(red.part_model, count=min(red.part_model.n_dofs, reduced.size + 6))
    full_hz = full.frequencies_hz[~full.rigid][: reduced.size]
    doc = red.to_dict() | {
        "files": files,
        "full_part_free_hz": full_hz.tolist(),
        "free_hz_error": (np.abs(reduced[: full_hz.size] - full_hz) / full_hz).tolist(),
        # a body mode further from the part's than the mesh may be from convergence (1 %) is flagged
        "free_hz_tolerance": DEFAULT_MESH_TOLERANCE,
    }
    fig = reduction_figure(
        e["part"], reduced, full_hz, max_hz=ctx.max_hz(stage.setup), tolerance=DEFAULT_MESH_TOLERANCE
    )
    doc.pop("written", None)
    return Output({"exports": doc}, {"reduction": _png(fig)}, tuple(files))


def _export_drivetrain(ctx, stage: Stage, folder: Path) -> Output:
    """The set-up's drivetrain as ``flexshaft fmu`` and ``flexshaft modes --uff`` write it."""
    e, study = stage.config, ctx.study
    files, doc = [], {"formats": list(e["formats"])}
    base = f"exports/{slug(stage.setup)}/drivetrain"
    if "fmu" in e["formats"]:
        from ..exports.fmu import fmu_system, write_fmu

        system = fmu_system(
            ctx.drivetrain(stage.setup), e["inputs"], e["outputs"], system_ratio=study.system_damping_ratio
        )
        folder_for(folder, base + ".fmu")
        start = "system" if study.variants == ("system",) else "parts"  # the study's own damping
        built = write_fmu(system, folder / (base + ".fmu"), default_variant=start, overwrite=True)
        files.append(base + ".fmu")
        doc["fmu"] = built.to_dict() | {"path": base + ".fmu"}  # relative to the output folder
    if "uff" in e["formats"]:
        from ..exports.universalfile import write_modes_uff

        folder_for(folder, base + ".uff")
        variant = study.variants[0]  # the modes as the study lists them first
        result = ctx.modes(stage.setup, variant)
        write_modes_uff(result, folder / (base + ".uff"), overwrite=True)
        files.append(base + ".uff")
        doc["uff"] = {"path": base + ".uff", "modes": int(result.count), "damping": variant, "units": "SI"}
    return Output({"exports": doc | {"files": files}}, {}, tuple(files))


def run_calibration(ctx, stage: Stage, folder: Path) -> Output:
    """The staged calibration of the targets file; each stage's tuned model file written."""
    from datetime import date

    from ..analysis.convergence import mesh_for_range
    from ..analysis.staged import calibrate_stages
    from ..input.modelfile import load_model
    from .tunedfile import read_targets, write_tuned_model

    cfg = stage.config
    study = ctx.study

    def load(path):
        d = load_model(path, allow_code=ctx.allow_code, use_cache=ctx.use_cache)
        return mesh_for_range(d, study.max_hz).drivetrain

    targets = read_targets(cfg["targets"])
    staged = calibrate_stages(targets, load, model=cfg["model"], starts=cfg["starts"])
    doc = staged.to_dict()
    files = []
    for k, st in enumerate(staged.stages):
        values = st.tuned_values()
        rel = f"{slug(st.name or 'calibration')}-tuned.toml"
        header = (
            f"{st.drivetrain.name}, tuned by flexshaft study on {date.today().isoformat()} against "
            f"{Path(cfg['targets']).name}, stage {st.name!r}\nfrom {st.model}; tuned values (SI): "
            + ", ".join(f"{n} = {v:.9g}" for n, v in values.items())
        )
        write_tuned_model(folder / rel, st.model, st.drivetrain, values, header=header, overwrite=True)
        doc["stages"][k]["tuned_model"] = rel
        files.append(rel)
    return Output({"calibration": doc}, {}, tuple(files))


STAGES = {
    "setup": run_setup,
    "twist": run_twist,
    "modes": run_modes,
    "frf": run_frf,
    "forced": run_forced,
    "simulate": run_simulate,
    "campbell": run_campbell,
    "export": run_export,
    "views": run_views,
    "calibration": run_calibration,
    "measurement": run_measurement,
}

"""The study's ``[[measurement]]`` stage: a set-up's recordings identified, and the set-up calibrated to them.

It calls what ``flexshaft identify --model ... --parameters ...`` calls
(:func:`flexshaft.analysis.identification.identify`, then :func:`flexshaft.study.measured.tune_to_measured`)
on the set-up's model as the study meshes it, and writes into the output folder
``measurement/<set-up>-targets.toml`` (the targets calibrated to, with the parameters: ``flexshaft
calibrate --targets`` runs it again) and, with parameters, ``measurement/<set-up>-tuned.toml``, its
modes and the study's FRFs of the set-up again on it, beside the model's before. The
recordings are read inside the stage, so their digests join its key: a changed recording redoes the
identification and the calibration, an unchanged one nothing.
"""

from __future__ import annotations

from pathlib import Path

from ..system.atomic import atomic_write_text
from .folder import folder_for
from .plan import Output, Stage, slug

__all__ = ["run_measurement"]


def _identified_doc(identified) -> list[dict]:
    """Each identified mode as results.json lists it: values, spread, per-run estimates, pairing, doubts."""
    pairs = identified.pairing.pairs
    out = []
    for m, p in zip(identified.modes, pairs, strict=True):
        d = m.to_dict()
        out.append(
            {
                k: d[k]
                for k in (
                    "frequency_hz",
                    "damping_ratio",
                    "frequency_std_hz",
                    "damping_std",
                    "segment_frequency_std_hz",
                    "segment_damping_std",
                    "run_frequencies_hz",
                    "run_damping_ratios",
                    "found_in_runs",
                    "mpc",
                    "frequency_doubt",
                    "damping_doubt",
                )
            }
            | {
                "paired_mode": p.mode,
                "model_frequency_hz": p.to_dict()["model_frequency_hz"],
                "mac": p.to_dict()["mac"],
                "unpaired": p.reason,
                "frequency_target": p.frequency_target,
                "damping_target": p.damping_target,
            }
        )
    return out


def _calibration_doc(calibration) -> dict:
    """The calibration as results.json keeps it: parameters with bounds, targets with verdicts, and
    whether a damping parameter was tuned (without one, the damping targets are compared, not met)."""
    from ..analysis.parameters import is_damping

    last = calibration.last
    doc = last.result.to_dict()
    keep = ("parameters", "targets", "damping_targets", "unmet", "physics", "cost", "message")
    tuned = any(is_damping(last.drivetrain, n) for n in last.result.names)
    return {k: doc[k] for k in keep} | {"damping_tuned": tuned}


def _peak(resp, j: int) -> dict:
    """The largest resonance of output ``j``: its frequency (Hz) and magnitude (output unit per N·m)."""
    h = abs(resp.H[:, j, 0])
    k = int(h.argmax())
    return {"frequency_hz": float(resp.frequencies_hz[k]), "magnitude": float(h[k])}


def _responses(ctx, setup: str, tuned, entries) -> tuple[list, dict]:
    """The study's FRFs of the set-up again on the tuned model, each beside the model's before (the
    model files' own damping, ``"parts"``, on both): a document per entry and a figure each."""
    import numpy as np

    from ..analysis.modal import response_modes
    from ..analysis.statespace import default_frf_range, frequency_grid, frequency_response, state_space
    from ..model.assembly import assemble
    from ..views.plots import png

    before_modes, after_modes = ctx.response_modes(setup, "parts"), response_modes(assemble(tuned))
    docs, figures = [], {}
    for k, e in enumerate(entries):
        at = e["input"] or before_modes.model.stations[0].name  # None: the driving end
        before = state_space(before_modes, [at], list(e["outputs"]))
        after = state_space(after_modes, [at], list(e["outputs"]))
        f_from, f_to = default_frf_range(before, e["from_hz"], e["to_hz"] or ctx.max_hz(setup))
        # both models' resonances resolved: the union of the grids each would get
        grid = np.union1d(*(frequency_grid(ss, f_from, f_to, e["points"]) for ss in (before, after)))
        rb, ra = frequency_response(before, grid), frequency_response(after, grid)
        docs.append(
            {
                "input": at,
                "outputs": [
                    {"output": name, "before": _peak(rb, j), "after": _peak(ra, j)}
                    for j, name in enumerate(e["outputs"])
                ],
            }
        )
        figures[f"frf {k + 1}"] = png(ra.plot(damping="the model files' own (parts)", before=rb))
    return docs, figures


def run_measurement(ctx, stage: Stage, folder: Path) -> Output:
    """Identify the set-up's recordings, pair them with its modes, write the targets file, and with
    parameters calibrate the set-up to the trusted targets, write the tuned model and list its modes."""
    from ..analysis.identification import identify
    from ..analysis.modal import listing_modes
    from ..model.assembly import assemble
    from ..views.plots import png
    from .measured import tune_to_measured

    cfg, setup = stage.config, stage.setup
    drivetrain = ctx.mesh_choice(setup).drivetrain
    identified = identify(
        list(cfg["files"]),
        list(cfg["channels"]),
        model=drivetrain,
        stations=cfg["stations"],
        max_hz=cfg["max_hz"],
        min_hz=cfg["min_hz"],
        units=cfg["units"],
        time_column=cfg["time_column"],
        group=cfg["group"],
        rate=cfg["rate"],
    )
    rel_targets = f"measurement/{slug(setup)}-targets.toml"
    tuning = tune_to_measured(
        identified,
        list(cfg["parameters"]),
        model=ctx.study.setup(setup).model,
        load=lambda _: drivetrain,
        source=rel_targets,
        starts=cfg["starts"],
    )
    folder_for(folder, rel_targets)
    atomic_write_text(folder / rel_targets, tuning.targets_text, overwrite=True)
    found = identified.identification
    doc = {
        "units": {"frequency": "Hz", "damping_ratio": "fraction", "duration": "s", "rate": "Hz"},
        "runs": [
            {
                "file": r.source,
                "duration_s": r.duration_s,
                "rate_hz": r.rate_hz,
                "channels": list(found.channels),
                "segments": r.segments,
            }
            for r in found.runs
        ],
        "band": {"min_hz": found.min_hz, "max_hz": found.max_hz, "reason": found.band_reason},
        "identified": _identified_doc(identified),
        "notes": list(found.notes),
        "targets_file": rel_targets,
        "calibration": None,
        "tuned_modes": [],
    }
    files = [rel_targets]
    if tuning.calibration is not None:
        rel_tuned = f"measurement/{slug(setup)}-tuned.toml"
        tuning.write_tuned(folder / rel_tuned, overwrite=True)
        files.append(rel_tuned)
        doc["calibration"] = _calibration_doc(tuning.calibration)
        doc["tuned_model"] = rel_tuned
        tuned = listing_modes(
            assemble(tuning.calibration.last.result.drivetrain), cfg["count"], ctx.max_hz(setup)
        )
        doc["tuned_modes"] = [
            {"mode": i, "frequency_hz": float(f), "damping_ratio": float(z)}
            for i, (f, z, r) in enumerate(zip(tuned.frequencies_hz, tuned.damping_ratios, tuned.rigid))
            if not r
        ]
    figures = {"stabilisation": png(identified.plot())}
    if tuning.calibration is not None and cfg["frf"]:
        doc["responses"], more = _responses(ctx, setup, tuning.calibration.last.result.drivetrain, cfg["frf"])
        figures |= more
    return Output({"measurement": doc}, figures, tuple(files))

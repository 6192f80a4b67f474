"""``flexshaft study STUDY.toml -o DIR``: the whole study, one line per stage run (one for all those
unchanged), one report."""

from __future__ import annotations

import time

from ..console import complain, emit
from ..options import output_option
from ..registry import Command

__all__ = ["COMMANDS", "study"]


def study(args) -> int:
    """Run the study; a line per stage that runs (one for those unchanged) on stdout, a line per failed
    stage on stderr; the exit status."""
    from ...study import run_study
    from ...views.progress import ProgressBar

    t0 = time.perf_counter()
    run = run_study(
        args.study,
        args.output,
        allow_code=args.allow_code,
        use_cache=not args.no_cache,
        progress=emit,
        slicing=ProgressBar,
    )
    for s in run.failed:
        complain(f"study stage {s.title}: {s.error}")
    if run.written:  # else nothing ran, which the study's one line said
        counts = {k: sum(s.status == k for s in run.stages) for k in ("ran", "cached", "failed", "skipped")}
        told = ", ".join(f"{n} {k}" for k, n in counts.items() if n)
        t = time.perf_counter() - t0
        emit(f"study: {len(run.stages)} stages ({told}) in {t:.1f} s: {run.folder / 'index.html'}")
    return run.exit_code


def _study_options(p) -> None:
    p.add_argument("study", help="TOML study file (its [[setup]] tables name the model files)")
    output_option(
        p,
        "DIR",
        "the study's folder: index.html, results.json, exports/, *-tuned.toml (new, empty, or this "
        "study's earlier run, which is updated)",
        required=True,
    )
    p.set_defaults(force=False, json=False)  # a study's folder is updated in place: there is no --force


COMMANDS = (
    Command(
        "study",
        "the whole study in one command: set-ups, modes, responses, runs, calibration, exports, "
        "one HTML report (re-runs redo only what changed)",
        _study_options,
        study,
        source="study",
        whole=True,  # its stages say for themselves how they went; the folder is its own
    ),
)

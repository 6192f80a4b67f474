"""Run a study: its stages in dependency order, each redone only when what it reads has changed.

``run_study(path, out)`` reads the study file, claims the output folder (:mod:`.folder`: the
study's marker, one run at a time), plans its stages, and for each one either takes its stored
result (its key unchanged, every digest holding: :mod:`.store`) or runs it, saying why on its
progress line when it had a stored result. A stage that fails is told on the progress line and
in the report; the stages that depend on it are skipped, the others run. Then ``results.json``
and ``index.html`` are written - unless nothing ran and both are as the last run left them, in
which case nothing is written at all.
"""

from __future__ import annotations

import json
import math
import os
import platform
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from ..errors import ModelError
from ..system.inputs import recording, tracking
from ..system.threads import follows_policy
from ..version import __version__
from .context import Context
from .folder import claimed
from .plan import Output, Stage, plan
from .stages import STAGES
from .store import Store
from .studyfile import SetupSpec, Study

__all__ = ["run_study", "run_report", "default_study", "StudyRun", "StageRun", "SECTIONS", "REPORT_FILES"]

#: results.json's top-level keys, in order (each holds its results per set-up).
SECTIONS = (
    "provenance",
    "setups",
    "parts",
    "twist",
    "modes",
    "frf",
    "forced",
    "simulation",
    "spectra",
    "campbell",
    "calibration",
    "measurement",
    "exports",
    "views",
)
REPORT_FILES = ("index.html", "results.json")


@dataclass(frozen=True)
class StageRun:
    """How one stage went: ``status`` is ran, cached, failed or skipped; ``seconds`` its time.

    ``why``: why a stage with a stored result ran again (``"its stored result changed since it
    was written"``, ``"c1.toml changed"``); None for a stage that never ran into the folder.
    """

    id: str
    title: str
    status: str
    seconds: float = 0.0
    error: str | None = None
    why: str | None = None


@dataclass(frozen=True)
class StudyRun:
    """The outcome of :func:`run_study`.

    Attributes
    ----------
    folder : Path
        The output folder.
    stages : tuple of StageRun
    results : dict
        What ``results.json`` holds.
    written : bool
        False when nothing had changed and nothing was written.
    figures : dict
        ``stage id -> {figure name -> PNG bytes}``: the report's pictures.
    """

    folder: Path
    stages: tuple[StageRun, ...]
    results: dict = field(repr=False)
    written: bool = True
    figures: dict = field(default_factory=dict, repr=False)

    @property
    def failed(self) -> tuple[StageRun, ...]:
        """The stages that failed."""
        return tuple(s for s in self.stages if s.status == "failed")

    @property
    def exit_code(self) -> int:
        """0 when every stage ran or was current, 2 when one failed (the command line's exit status)."""
        return 2 if self.failed else 0


def _machine() -> dict:
    import numpy
    import scipy

    return {
        "host": platform.node(),
        "platform": platform.platform(),
        "processor": platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }


def _plain(value):
    """JSON's own values: a number that is not finite (a rigid-body mode's phase) becomes None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item") and hasattr(value, "dtype"):  # a numpy scalar
        return _plain(value.item())
    return value


def _place(results: dict, stage: Stage, out: Output) -> None:
    for section, value in out.results.items():
        if value is None:
            continue
        slot = results.setdefault(section, {})
        if stage.setup is None:
            results[section] = value
        elif stage.name is None:
            slot[stage.setup] = value
        else:
            slot.setdefault(stage.setup, {})[stage.name] = value


@follows_policy
def run_study(
    path, out, *, allow_code: bool = False, use_cache: bool = True, progress=None, slicing=None
) -> StudyRun:
    """Run the study file ``path`` into the folder ``out``.

    Parameters
    ----------
    path : str or Path
        The study file (TOML; see :mod:`flexshaft.study.studyfile`).
    out : str or Path
        The output folder: new, empty, or this study's earlier run (updated in place).
    allow_code : bool
        Run part code the model files name beyond flexshaft's own part library (as ``--allow-code``).
    use_cache : bool
        Read CAD parts' section tables from the disk cache (``--no-cache``: slice them anew).
    progress : callable, optional
        ``progress(line)`` for one line per stage that runs, fails or is skipped (what it is, and how
        long it took or why not), and one line for all the unchanged stages read from the store.
    slicing : callable, optional
        ``slicing(label)`` -> ``(done, total)`` callback while CAD parts are sliced.

    Returns
    -------
    StudyRun
        Failed stages are in it (``exit_code`` 2), not raised: the others still ran.

    Raises
    ------
    ModelError
        The study file itself is unusable, or the output folder is refused.
    """
    from .studyfile import read_study

    say = progress or (lambda line: None)
    folder = Path(out)
    with recording():
        study = read_study(path)
        source = Path(path).resolve()
        with claimed(folder, source):
            ctx = Context(study, allow_code=allow_code, use_cache=use_cache, progress=slicing)
            return _run(study, source, folder, say, ctx)


def default_study(model) -> Study:
    """The study of one model file with the default plan: a study file holding only its ``[[setup]]``
    (the set-up and its parts, the twist test, the modes with the mesh check, the mode views).

    Parameters
    ----------
    model : str or Path
        The model file; the set-up and the study are named after it.
    """
    model = Path(model).absolute()  # as named (a link stays one), as a study file's [[setup]] names it
    return Study(name=model.stem, source=model, setups=(SetupSpec(model.stem, model),))


@follows_policy
def run_report(
    model,
    out,
    *,
    force: bool = False,
    allow_code: bool = False,
    use_cache: bool = True,
    progress=None,
    slicing=None,
) -> StudyRun:
    """``flexshaft report MODEL``: the model's study with the default plan (:func:`default_study`)
    run into the folder ``out`` - the same ``index.html`` and ``results.json`` a study writes.

    The folder is new, empty, or a report of the same model; its report files are replaced only
    with ``force`` (a study updates its folder unasked). The model is loaded before the folder is
    touched: a model that cannot be read leaves nothing behind, and a new folder is removed again
    when the run stops with an error (a full disk), as no report is left without its page.

    Parameters
    ----------
    model : str or Path
        The model file.
    out : str or Path
        The output folder.
    force, allow_code, use_cache, progress, slicing
        As for :func:`run_study` (``force``: the command line's ``--force``).

    Returns
    -------
    StudyRun

    Raises
    ------
    ModelError
        The model cannot be loaded, or the folder is refused.
    """
    say = progress or (lambda line: None)
    folder, source = Path(out), Path(model).resolve()
    study = default_study(model)
    with recording():
        ctx = Context(study, allow_code=allow_code, use_cache=use_cache, progress=slicing)
        ctx.loaded(source)  # its errors before any folder is made (kept for the stages: loaded once)
        new = not (folder.exists() or folder.is_symlink())
        with claimed(folder, source, writer="flexshaft report", force=force, files=REPORT_FILES):
            try:
                return _run(study, source, folder, say, ctx)
            except (ModelError, OSError):
                if new:  # made by this run, which holds its lock
                    _remove_new(folder)
                raise


def _remove_new(folder: Path) -> None:
    """Remove a folder this run made (checked and locked as its own): no report without its page."""
    import contextlib
    import shutil

    with contextlib.suppress(OSError):
        shutil.rmtree(folder)


def _run(study, source: Path, folder: Path, say, ctx: Context) -> StudyRun:
    """The stages into the claimed folder, then the report (see :func:`run_study`)."""
    store = Store(folder, source)
    stages = plan(study)
    keys: dict[str, str] = {}
    outputs: dict[str, Output] = {}
    runs: list[StageRun] = []
    status: dict[str, str] = {}
    ran = False
    for n, st in enumerate(stages, 1):
        head = f"[{n}/{len(stages)}] {st.title}"
        bad = next((d for d in st.deps if status.get(d) in ("failed", "skipped")), None)
        if bad is not None:
            status[st.id] = "skipped"
            why = f"skipped: it needs {bad!r}, which did not run"
            runs.append(StageRun(st.id, st.title, "skipped", error=why))
            say(f"{head}: {why}")
            continue
        found = store.lookup(st, keys)
        if found.output is not None:
            keys[st.id], outputs[st.id], status[st.id] = store.entries[st.id]["key"], found.output, "cached"
            runs.append(StageRun(st.id, st.title, "cached"))  # told once, with the others, below
            continue
        redo = f"{found.why}: " if found.why else ""
        store.make_way(st.id)
        t0 = time.perf_counter()
        try:
            with tracking() as read:
                result = STAGES[st.kind](ctx, st, folder)
        except ModelError as err:
            error = str(err)
        except Exception as err:  # noqa: BLE001 - one stage's defect must not cost the others
            error = f"unexpected {type(err).__name__}: {err} (a flexshaft defect: please report it)"
        else:
            error = None
            result = Output(_plain(result.results), result.figures, result.files)
        seconds = time.perf_counter() - t0
        ran = True
        if error is not None:
            status[st.id] = "failed"
            store.forget(st.id)
            runs.append(StageRun(st.id, st.title, "failed", seconds, error, found.why))
            say(f"{head}: {redo}failed after {seconds:.1f} s: {error}")
            continue
        keys[st.id] = store.save(st, keys, read, result, seconds)
        outputs[st.id], status[st.id] = result, "ran"
        runs.append(StageRun(st.id, st.title, "ran", seconds, why=found.why))
        say(f"{head}: {redo + 'redone in ' if redo else ''}{seconds:.1f} s")
    planned = {st.id for st in stages}
    for old in [i for i in store.entries if i not in planned]:
        ran = True  # a stage dropped from the study: its results and files leave the folder
        store.drop(old)
    study_sha = store.digest(source)
    figures = {i: o.figures for i, o in outputs.items()}
    cached = sum(r.status == "cached" for r in runs)
    stored = f"{cached} stages read from the store ({folder}{os.sep})"
    if not ran:
        previous, why = store.unchanged_report(REPORT_FILES, study_sha)
        if previous is not None:
            say(f"study unchanged: {stored}: nothing to do")
            store.tidy()
            return StudyRun(folder, tuple(runs), previous, written=False, figures=figures)
        say(f"study unchanged: {stored}, but {why}: the report is written again")
    elif cached:
        say(f"unchanged: {stored}")
    results = _results(study, stages, outputs, runs, store, source, study_sha)
    _write(results, figures, stages, runs, store, study_sha)
    store.tidy()
    return StudyRun(folder, tuple(runs), results, figures=figures)


def _results(study, stages, outputs, runs, store, source, study_sha) -> dict:
    # what the stages in the report read (a cached stage's record was checked against these digests)
    read = [store.entries[i]["made"]["read"] for i in outputs]
    inputs = {p: sha for r in read for p, sha in r.items()}
    results: dict = {k: {} for k in SECTIONS}
    results["provenance"] = {
        "study": study.name,
        "study_file": str(source),
        "study_sha256": study_sha,
        "flexshaft": __version__,
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": _machine(),
        "inputs": {p: inputs[p] for p in sorted(inputs)},
        "damping": study.damping,
        "system_damping_ratio": study.system_damping_ratio if study.damping != "parts" else None,
        "max_hz": study.max_hz,
        "stages": [
            {
                "id": r.id,
                "title": r.title,
                "status": r.status,
                "seconds": round(r.seconds, 3),
                "error": r.error,
            }
            for r in runs
        ],
    }
    for st in stages:
        if st.id in outputs:
            _place(results, st, outputs[st.id])
    return results


def _write(results, figures, stages, runs, store, study_sha) -> None:
    """``results.json``, ``index.html``, then the record of both (until then the record names none)."""
    from .report import study_html

    folder = store.folder
    text = json.dumps(results, indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    files = {"results.json": store.put(folder / "results.json", text.encode("utf-8"))}
    html = study_html(results, figures, stages, runs)
    files["index.html"] = store.put(folder / "index.html", html.encode("utf-8"))
    store.commit({"files": files, "study_sha256": study_sha, "flexshaft": __version__})

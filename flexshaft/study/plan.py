"""A study as stages: what each does, what it depends on, and where its results go.

A study file becomes a list of stages in dependency order. A stage's ``config`` is everything of
the study file it reads (JSON-able): with its dependencies' keys and the digests of the files it
read, it makes the stage's cache key (:mod:`flexshaft.study.store`). A stage's results go into
``results.json`` under each of its ``sections`` (``results[section][setup][name]``, or
``results[section][setup]`` for a stage without a name, or ``results[section]`` for one without
a set-up).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from .studyfile import DRIVETRAIN_ENTRY, Study, slug

__all__ = ["Stage", "Output", "plan", "slug"]


@dataclass(frozen=True)
class Output:
    """What a stage produced.

    Attributes
    ----------
    results : dict
        ``section -> value`` (JSON-able, SI with units stated), for ``results.json`` and the report.
    figures : dict
        ``name -> PNG bytes``, embedded in the report.
    files : tuple of str
        Files the stage wrote into the output folder, relative to it (exports, tuned models, runs).
    """

    results: dict
    figures: dict = field(default_factory=dict)
    files: tuple[str, ...] = ()


@dataclass(frozen=True)
class Stage:
    """One stage of a study.

    Attributes
    ----------
    id : str
        Unique, e.g. ``"frf/Customer 1"``.
    kind : str
        What it does: setup, twist, modes, frf, forced, simulate, campbell, calibration, export, views,
        measurement.
    title : str
        For progress lines and the report.
    setup : str or None
    name : str or None
        The entry within its set-up (a run's name, an exported part).
    deps : tuple of str
        Ids of the stages whose results (or objects) it uses.
    config : dict
        The study file's settings it reads.
    """

    id: str
    kind: str
    title: str
    setup: str | None = None
    name: str | None = None
    deps: tuple[str, ...] = ()
    config: dict = field(default_factory=dict)


def _spec(obj) -> dict:
    """A study-file entry as JSON-able config (paths as strings)."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = str(v) if hasattr(v, "__fspath__") else v
    return out


def _setup_stages(study: Study, setup: str, model: str) -> list[Stage]:
    """The stages of one set-up: the set-up itself, then every analysis built on it."""
    damping = {"damping": study.damping, "system_damping_ratio": study.system_damping_ratio}
    base = f"setup/{setup}"
    stages: list[Stage] = []

    def add(kind: str, title: str, config: dict, name: str | None = None) -> None:
        sid = f"{kind}/{setup}" + (f"/{name}" if name else "")
        deps = () if kind == "setup" else (base,)
        stages.append(Stage(sid, kind, f"{title} {setup!r}", setup, name, deps, config))

    def here(entry) -> bool:
        return setup in study.setups_of(entry.setups)

    add("setup", "set-up", {"model": model, "max_hz": study.max_hz})
    add("twist", "twist test", {})
    add("modes", "modes", _spec(study.modes) | damping)
    if frf := [_spec(e) for e in study.frf if here(e)]:
        add("frf", "FRF", {"frf": frf} | damping)
    if forced := [_spec(e) for e in study.forced if here(e)]:
        add("forced", "forced response", {"forced": forced} | damping)
    for run in filter(here, study.simulate):
        add("simulate", f"run {run.name!r}", _spec(run) | damping, run.name)
    if study.campbell is not None and here(study.campbell):
        add("campbell", "Campbell", _spec(study.campbell) | damping)
    for e in filter(here, study.exports):
        what = f"export {e.part!r} of" if e.part else "export the drivetrain of"
        add("export", what, _spec(e), e.part or DRIVETRAIN_ENTRY)
    if here(study.views):
        add("views", "mode views", _spec(study.views) | {"count": study.modes.count})
    for m in study.measurements:
        if m.setup == setup:  # the recordings are read inside the stage: their digests join its key
            add("measurement", "recordings of", _spec(m) | {"count": study.modes.count, "frf": frf})
    return stages


def plan(study: Study) -> list[Stage]:
    """The stages of ``study`` in an order where every stage follows its dependencies."""
    stages = [st for s in study.setups for st in _setup_stages(study, s.name, str(s.model))]
    if study.calibration is not None:
        config = _spec(study.calibration) | {"max_hz": study.max_hz}
        stages.append(Stage("calibration", "calibration", "calibration", config=config))
    return stages

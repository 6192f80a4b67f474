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
import re
from dataclasses import dataclass, field

from ..io.studyfile import Study

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
        What it does: setup, twist, modes, frf, forced, simulate, campbell, calibration, export, views.
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


def slug(text: str) -> str:
    """``text`` as a file-name piece: lower case, runs of other characters as one ``-``."""
    s = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return s or "x"


def _spec(obj) -> dict:
    """A study-file entry as JSON-able config (paths as strings)."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = str(v) if hasattr(v, "__fspath__") else v
    return out


def plan(study: Study) -> list[Stage]:
    """The stages of ``study`` in an order where every stage follows its dependencies."""
    common = {"max_hz": study.max_hz}
    damping = {"damping": study.damping, "system_damping_ratio": study.system_damping_ratio}
    stages: list[Stage] = []
    for s in study.setups:
        base = f"setup/{s.name}"
        stages.append(
            Stage(base, "setup", f"set-up {s.name!r}", s.name, config={"model": str(s.model)} | common)
        )
        stages.append(Stage(f"twist/{s.name}", "twist", f"twist test {s.name!r}", s.name, deps=(base,)))
        stages.append(
            Stage(
                f"modes/{s.name}",
                "modes",
                f"modes {s.name!r}",
                s.name,
                deps=(base,),
                config=_spec(study.modes) | damping,
            )
        )
        frf = [_spec(e) for e in study.frf if s.name in study.setups_of(e.setups)]
        if frf:
            stages.append(
                Stage(
                    f"frf/{s.name}",
                    "frf",
                    f"FRF {s.name!r}",
                    s.name,
                    deps=(base,),
                    config={"frf": frf} | damping,
                )
            )
        forced = [_spec(e) for e in study.forced if s.name in study.setups_of(e.setups)]
        if forced:
            stages.append(
                Stage(
                    f"forced/{s.name}",
                    "forced",
                    f"forced response {s.name!r}",
                    s.name,
                    deps=(base,),
                    config={"forced": forced} | damping,
                )
            )
        for run in study.simulate:
            if s.name in study.setups_of(run.setups):
                stages.append(
                    Stage(
                        f"simulate/{s.name}/{run.name}",
                        "simulate",
                        f"run {run.name!r} {s.name!r}",
                        s.name,
                        run.name,
                        deps=(base,),
                        config=_spec(run) | damping,
                    )
                )
        if study.campbell is not None and s.name in study.setups_of(study.campbell.setups):
            stages.append(
                Stage(
                    f"campbell/{s.name}",
                    "campbell",
                    f"Campbell {s.name!r}",
                    s.name,
                    deps=(base,),
                    config=_spec(study.campbell) | damping,
                )
            )
        for e in study.exports:
            if s.name in study.setups_of(e.setups):
                stages.append(
                    Stage(
                        f"export/{s.name}/{e.part}",
                        "export",
                        f"export {e.part!r} of {s.name!r}",
                        s.name,
                        e.part,
                        deps=(base,),
                        config=_spec(e),
                    )
                )
        if s.name in study.setups_of(study.views.setups):
            stages.append(
                Stage(
                    f"views/{s.name}",
                    "views",
                    f"mode views {s.name!r}",
                    s.name,
                    deps=(base,),
                    config=_spec(study.views) | {"count": study.modes.count},
                )
            )
    if study.calibration is not None:
        stages.append(
            Stage("calibration", "calibration", "calibration", config=_spec(study.calibration) | common)
        )
    return stages

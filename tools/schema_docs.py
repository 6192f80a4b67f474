"""The site's file-format references, rendered from the schemas the readers read by.

``docs/reference/model-file.md``, ``study-file.md`` and ``targets-file.md`` are each generated whole:
an introduction (here) and the key tables :func:`sections` renders from
:mod:`flexshaft.input.modelschema`, :mod:`flexshaft.study.studyschema` and the targets file's tables in
:mod:`flexshaft.study.tunedfile`. They are committed; a test holds them equal to this rendering, so the
documentation never drifts from what the readers accept::

    python tools/schema_docs.py            # print the pages
    python tools/schema_docs.py --write    # write them into docs/reference/
    python tools/schema_docs.py --check    # exit 1 when one differs
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # this checkout's flexshaft, whichever one the interpreter has installed
    sys.path.insert(0, str(ROOT))
REFERENCE = ROOT / "docs" / "reference"
PAGES = {"model": "model-file.md", "study": "study-file.md", "targets": "targets-file.md"}
GENERATED = (
    "Generated from the schema by `tools/schema_docs.py` (do not edit by hand: run "
    "`python tools/schema_docs.py --write`)."
)

MODEL_INTRO = """\
# Model file

A model file (TOML) describes a drivetrain as a serial chain of components listed from the driving
end (motor first): rigid inertias, shafts (given by their stiffness and inertia, or by their
dimensions), couplings, gear stages, CAD parts whose stiffness and inertia come from their geometry,
and bearings. `flexshaft modes MODEL` and every other command read it; in Python,
`flexshaft.load_model(path)`.

A bare number is SI: stiffness N·m/rad, inertia kg·m², damping N·m·s/rad, lengths m, frequencies Hz,
damping ratios as fractions (0.0053 for 0.53 %). A number may instead carry its unit as a string,
converted to SI when the file is read: `stiffness = "307.9 kN*m/rad"`, `inertia = "58.1 t*m^2"`,
`segments = [{length = "500 mm", od = "160 mm"}]`, `E = "210 GPa"` - one number, then unit names pint
knows joined by `*`, `·`, `/` and whole exponents up to ±4, nothing evaluated; a unit of another
dimension is an error naming both (`inertia = "58.1 kg"`). Angles are radians, which pint counts as
dimensionless, so `"86 kN*m"` is read as N·m/rad too. Every key must be known: an unknown key, a
missing required key, a non-finite or out-of-range number or a duplicate name is an error that names
the file, the table, the key, the value and what would be valid.

```toml
[model]
name = "Customer 1"
inertia_model = "consistent"    # or "lumped"

[[chain]]
name = "motor"
type = "rigid"
inertia = 58.10

[[chain]]
name = "part 1"
type = "shaft"
stiffness = 307933.18
inertia = 0.44
damping_ratio = 0.0053

[[chain]]
name = "part 3"
type = "coupling"
stiffness = 55120.04
inertia = 0.06
```

Every node must carry some inertia: a massless shaft or coupling at a free end is refused (the
inertia matrix would be singular). Component boundaries are named stations: a station with a rigid
inertia takes its name (`"motor"`), one between two flexible components is `"part 1/part 2"`, free
ends are `"part 2 end"` / `"part 1 start"`; a gear stage has two, its driving and its driven wheel.
`examples/` holds complete model files (`customer1.toml`, `customer1_cad.toml`, `nrel5mw.toml`, ...).

## Tables and keys"""

STUDY_INTRO = """\
# Study file

A study file (TOML) describes a whole study - the set-ups (each a model file), and what to compute for
each: modes, frequency responses, forced responses, time runs with their spectra, the Campbell
diagram, the calibration to measured targets, flexible-body exports and 3D views.
`flexshaft study STUDY.toml -o DIR` runs it into `DIR/index.html` (one self-contained report),
`DIR/results.json`, `DIR/exports/`, the time runs as CSV and the tuned model files; run again, it
redoes only what changed. In Python, `flexshaft.read_study(path)` and `flexshaft.run_study(...)`.
Values follow the model file's rules (SI, or a string with its unit; unknown keys are errors); a
`[[simulate]]` table takes the options of `flexshaft simulate`. `examples/testbench_study.toml` is a
complete study of the test bench's three set-ups.

## Tables and keys"""

TARGETS_INTRO = """\
# Targets file

A targets file (TOML) says what to tune a model to and what may change: the target frequencies,
frequency ratios and damping ratios of numbered modes (optionally with measured mode shapes), the
parameters with their bounds, the number of starting points, and - for a staged calibration - the
stages, each with its own model file, targets and parameters. `flexshaft calibrate MODEL --targets
T.toml [-o tuned.toml]` reads it, and a study's `[calibration]` names one; `flexshaft identify
RUNS... --model MODEL -o T.toml` writes one from measured runs. In Python,
`flexshaft.read_targets(path)`. Modes are numbered as `flexshaft modes` numbers them (0: the rigid-body
mode); tolerances are relative (0.02: 2 %). `examples/calibration/` holds complete targets files.

## Tables and keys"""

INTROS = {"model": MODEL_INTRO, "study": STUDY_INTRO, "targets": TARGETS_INTRO}

# A schema's help links to the guide by paths relative to docs/reference/ ([text](../guide/x.md));
# a bare anchor ([text](#anchor)) names no page of the site, so its text stays and the link goes.
_README_LINK = re.compile(r"\[([^\]]+)\]\(#[^)]*\)")


def _table(title: str, table, *, skip: tuple[str, ...] = (), level: int = 3) -> str:
    from flexshaft.input.schema import markdown

    # A heading each (the page's contents list them), then what the table is, as a sentence.
    about = f"{table.help[:1].upper()}{table.help[1:]}.\n\n" if table.help else ""
    return f"{'#' * level} {title}\n\n{about}{markdown(table, skip=skip)}"


def model_reference() -> str:
    """The model file's tables: ``[model]``, each ``[[chain]]`` type, ``[materials.NAME]``,
    ``[[bearings]]``."""
    from flexshaft.input.modelschema import BEARING, COMPONENTS, MATERIAL, MODEL_TABLE

    parts = [_table("`[model]`", MODEL_TABLE)]
    parts.append(
        "### `[[chain]]`\n\nThe components, in order from the driving end. Every entry has a unique `name` "
        "(string) and a `type`, and the keys of its type:"
    )
    parts += [
        _table(f'`type = "{name}"`', t, skip=("name", "type"), level=4) for name, t in COMPONENTS.items()
    ]
    parts += [_table("`[materials.NAME]`", MATERIAL), _table("`[[bearings]]`", BEARING)]
    return "\n\n".join(parts)


def study_reference() -> str:
    """The study file's tables, in the order the file lists them."""
    from flexshaft.study import studyschema as s

    tables = (s.STUDY_TABLE, s.SETUP, s.MODES, s.FRF, s.FORCED, s.SIMULATE, s.CAMPBELL, s.CALIBRATION)
    return "\n\n".join(_table(f"`{t.name}`", t) for t in tables + (s.EXPORT, s.VIEWS, s.MEASUREMENT))


def targets_reference() -> str:
    """The targets file's tables."""
    from flexshaft.study.tunedfile import OPTIONS, PARAMETER, STAGE, TARGET

    return "\n\n".join(_table(f"`{t.name}`", t) for t in (OPTIONS, TARGET, PARAMETER, STAGE))


def sections() -> dict[str, str]:
    """Each reference's name and its key tables (markdown)."""
    return {"model": model_reference(), "study": study_reference(), "targets": targets_reference()}


def pages() -> dict[str, str]:
    """Each reference page's path and its whole text."""
    found = {}
    for name, body in sections().items():
        body = _README_LINK.sub(r"\1", body)
        found[REFERENCE / PAGES[name]] = f"{INTROS[name]}\n\n{body}\n\n{GENERATED}\n"
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write the pages into docs/reference/")
    parser.add_argument("--check", action="store_true", help="exit 1 when a page differs")
    args = parser.parse_args(argv)
    stale = []
    for path, text in pages().items():
        if args.write:
            path.write_text(text, encoding="utf-8")
        elif args.check:
            if not path.is_file() or path.read_text(encoding="utf-8") != text:
                stale.append(path.name)
        else:
            sys.stdout.write(f"<!-- {path.name} -->\n{text}\n")
    if stale:
        print(f"{', '.join(stale)} differ from the schemas: run python tools/schema_docs.py --write")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

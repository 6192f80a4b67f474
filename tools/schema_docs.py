"""The README's file references, rendered from the schemas the readers read by.

Each reference stands in the README between two marker lines, ``<!-- schema:NAME begin -->`` and
``<!-- schema:NAME end -->`` (NAME: ``model``, ``study``, ``targets``), and is exactly what
:func:`sections` renders from :mod:`flexshaft.input.modelschema`, :mod:`flexshaft.study.studyschema`
and the targets file's tables in :mod:`flexshaft.study.tunedfile`; a test holds them equal, so the
documentation never drifts from what the readers accept::

    python tools/schema_docs.py            # print the sections
    python tools/schema_docs.py --write    # put them into README.md
    python tools/schema_docs.py --check    # exit 1 when README.md differs
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def _table(title: str, table, *, skip: tuple[str, ...] = ()) -> str:
    from flexshaft.input.schema import markdown

    head = f"{title} ({table.help})" if table.help else title
    return f"{head}\n\n{markdown(table, skip=skip)}"


def model_reference() -> str:
    """The model file's tables: ``[model]``, each ``[[chain]]`` type, ``[materials.NAME]``,
    ``[[bearings]]``."""
    from flexshaft.input.modelschema import BEARING, COMPONENTS, MATERIAL, MODEL_TABLE

    parts = [_table("`[model]`", MODEL_TABLE)]
    parts.append(
        "`[[chain]]` entries, in order from the driving end. Every entry has a unique `name` (string) "
        "and a `type`, and the keys of its type:"
    )
    parts += [_table(f'`type = "{name}"`', t, skip=("name", "type")) for name, t in COMPONENTS.items()]
    parts += [_table("`[materials.NAME]`", MATERIAL), _table("`[[bearings]]`", BEARING)]
    return "\n\n".join(parts)


def study_reference() -> str:
    """The study file's tables, in the order the file lists them."""
    from flexshaft.study import studyschema as s

    tables = (s.STUDY_TABLE, s.SETUP, s.MODES, s.FRF, s.FORCED, s.SIMULATE, s.CAMPBELL, s.CALIBRATION)
    return "\n\n".join(_table(f"`{t.name}`", t) for t in tables + (s.EXPORT, s.VIEWS))


def targets_reference() -> str:
    """The targets file's tables."""
    from flexshaft.study.tunedfile import OPTIONS, PARAMETER, STAGE, TARGET

    return "\n\n".join(_table(f"`{t.name}`", t) for t in (OPTIONS, TARGET, PARAMETER, STAGE))


def sections() -> dict[str, str]:
    """Each reference's name and its markdown."""
    return {"model": model_reference(), "study": study_reference(), "targets": targets_reference()}


def _marked(name: str) -> re.Pattern:
    return re.compile(rf"(<!-- schema:{name} begin -->\n)(.*?)(<!-- schema:{name} end -->)", re.S)


def in_readme(text: str) -> dict[str, str]:
    """The sections as the README holds them (a missing marker pair: absent)."""
    return {n: m.group(2).strip("\n") for n in sections() if (m := _marked(n).search(text))}


def updated(text: str) -> str:
    """``text`` with every marked section replaced by its rendering."""
    for name, body in sections().items():
        text, count = _marked(name).subn(lambda m, b=body: f"{m.group(1)}\n{b}\n\n{m.group(3)}", text)
        if count != 1:
            raise SystemExit(f"README.md: no single <!-- schema:{name} begin/end --> pair")
    return text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update README.md's sections")
    parser.add_argument("--check", action="store_true", help="exit 1 when README.md's sections differ")
    args = parser.parse_args(argv)
    text = README.read_text(encoding="utf-8")
    if args.write:
        README.write_text(updated(text), encoding="utf-8")
    elif args.check:
        if updated(text) != text:
            print("README.md's file references differ from the schemas: run tools/schema_docs.py --write")
            return 1
    else:
        for name, body in sections().items():
            print(f"<!-- schema:{name} -->\n{body}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

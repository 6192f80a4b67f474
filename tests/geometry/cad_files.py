"""Part files the CAD tests and the CLI's abuse cases share: issue 33's deep STEP and a small good one.

build123d is imported only by :func:`good_step`, when a test asks for it.
"""

from __future__ import annotations

from pathlib import Path

#: Issue 33's crafted STEP: nested parentheses enough to overflow a recursive parser's stack.
DEPTH = 200_000


def deep_step(path: Path, depth: int = DEPTH) -> Path:
    """A ~400 kB STEP file whose one point's coordinate list nests ``depth`` parentheses: ISO 10303-21
    lets lists nest, and OCCT's parser descends them recursively (SIGSEGV in-process, issue 33)."""
    head = (
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
        "FILE_NAME('deep','2026-01-01T00:00:00',(''),(''),'','','');\n"
        "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n"
    )
    point = "#1=CARTESIAN_POINT(''," + "(" * depth + "0." + ")" * depth + ");\n"
    path.write_text(head + point + "ENDSEC;\nEND-ISO-10303-21;\n")
    return path


def good_step(path: Path) -> Path:
    """A hollow stepped shaft (0.3 m of 160/50 mm, 0.4 m of 120/40 mm) as a STEP file."""
    from geometry.cadio import write_step
    from geometry.parts.primitives import stepped_shaft

    part = stepped_shaft([{"length": 0.3, "od": 0.16, "id": 0.05}, {"length": 0.4, "od": 0.12, "id": 0.04}])
    return write_step(part, path)

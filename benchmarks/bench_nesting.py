"""What the nesting check costs beside the parser it guards (flexshaft/system/nesting.py, issue 33).

Every TOML file flexshaft reads is scanned for bracket depth before ``tomllib.loads``, every JSON file
before ``json.loads``. Timed in one run, best of 5: the scan alone and the parser alone, on
- a shipped model file (examples/customer1_cad.toml, a few kB),
- a model file near the 8 MB ceiling (45 000 chain entries with segments, strings and comments),
- 8 MB of flat arrays (``a = [[], [], ...]``: the most brackets a file can hold for the scan to count),
- a flexible body as JSON (`flexshaft reduce -o part.json`, a 400-DOF part: numbers in nested lists),
and prints scan/parse: the share the check adds to reading the file.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import best  # noqa: E402

from flexshaft.system.nesting import check_nesting  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def big_model() -> str:
    entry = (
        '[[chain]]\nname = "part {k} [flange]"  # a comment with [brackets]\ntype = "shaft"\n'
        'material = "steel"\n'
        "segments = [{{length = 0.06, od = 0.60}}, {{length = 1.6, od = 0.3, id = 0.2}}]\n"
    )
    return '[model]\nname = "big"\n' + "".join(entry.format(k=k) for k in range(45_000))


def body_json() -> str:
    with tempfile.TemporaryDirectory() as d:
        model = Path(d) / "m.toml"
        model.write_text(
            '[model]\nname = "b"\n[[chain]]\nname = "p"\ntype = "shaft"\nmaterial = "steel"\n'
            "segments = [{length = 4.0, od = 0.2}]\nmax_element_length = 0.01\n"
        )
        out = Path(d) / "p.json"
        subprocess.run(
            [sys.executable, "-m", "flexshaft", "reduce", str(model), "--part", "p", "--modes", "20"]
            + ["-o", str(out)],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        return out.read_text()


def main() -> None:
    cases = [
        ("customer1_cad.toml", (ROOT / "examples" / "customer1_cad.toml").read_text(), "toml"),
        ("model, 45 000 entries", big_model(), "toml"),
        ("flat arrays, 8 MB", "a = [" + "[], " * 2_000_000 + "]\n", "toml"),
        ("body JSON, 400 DOFs", body_json(), "json"),
    ]
    print(f"{'file':<24} {'MB':>6} {'scan s':>9} {'parse s':>9} {'scan/parse':>11}")
    for name, text, kind in cases:
        parse = tomllib.loads if kind == "toml" else json.loads
        scan_s, _ = best(lambda: check_nesting(text, name, kind=kind), 5)  # noqa: B023 - called at once
        parse_s, _ = best(lambda: parse(text), 5)  # noqa: B023
        print(f"{name:<24} {len(text) / 2**20:6.2f} {scan_s:9.4f} {parse_s:9.4f} {scan_s / parse_s:11.3f}")


if __name__ == "__main__":
    main()

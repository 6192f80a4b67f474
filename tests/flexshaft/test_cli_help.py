"""The commands' help says what they do, with the library's own numbers, and building it loads no numpy."""

from __future__ import annotations

import subprocess
import sys

from flexshaft.analysis.convergence import REFINEMENTS
from flexshaft.analysis.identification import MODEL_MARGIN, NYQUIST_ALONE, NYQUIST_WITH_MODEL
from flexshaft.analysis.modal import DEFAULT_LISTED
from flexshaft.analysis.scenario import KINDS
from flexshaft.cli.registry import build_parser, commands
from flexshaft.measurement.identify import LOWEST_MODE_FRACTION, MIN_HZ_FRACTION, MIN_RECORD_PERIODS


def _help(command: str, option: str) -> str:
    """The help text of one option of one command, as written (not wrapped)."""
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices[command]
    return next(a.help for a in sub._actions if option in a.option_strings)


def test_the_help_carries_the_librarys_numbers():
    assert f"else the lowest {DEFAULT_LISTED})" in _help("modes", "--modes")
    assert "cut into " + " and into ".join(map(str, REFINEMENTS)) in _help("modes", "--mesh-check")
    assert (
        f"{MODEL_MARGIN:g} x the model's highest elastic mode, at most {NYQUIST_WITH_MODEL / 2:g} x rate; "
        f"else {NYQUIST_ALONE / 2:g} x rate" in _help("identify", "--max-hz")
    )
    # the band's default low end, as measurement.identify.default_min_hz computes it
    low = _help("identify", "--min-hz")
    assert LOWEST_MODE_FRACTION == 0.5 and "half the model's first elastic mode" in low
    assert f"max-hz/{1 / MIN_HZ_FRACTION:g}; never below {MIN_RECORD_PERIODS} periods" in low


def test_every_scenario_is_explained():
    text = _help("simulate", "--scenario")
    assert all(f"{kind}: " in text for kind in KINDS), text


def test_each_commands_output_help_is_its_own():
    # -o writes something different for every command: no two share a help text
    texts = {}
    for c in commands():
        sub = next(a for a in build_parser()._actions if a.dest == "command").choices[c.name]
        found = [a.help for a in sub._actions if "-o" in a.option_strings]
        if found:
            texts.setdefault(found[0], []).append(c.name)
    assert all(len(names) == 1 for names in texts.values()), texts
    assert "-o DIR/" in _help("demo", "-o")


def test_building_the_parser_loads_no_numpy():
    # every command builds it first: numpy (and its BLAS threads) load only for the work that needs it
    code = "import sys; from flexshaft.cli.registry import build_parser; build_parser(); "
    code += "print('numpy' in sys.modules)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.stdout.strip() == "False", r.stderr

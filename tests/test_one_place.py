"""One place for each core: the MAC, damped eigenvalues, the report, result serialisation, the TOML
schema, the twist test and the Craig-Bampton front end each exist once, and a second copy fails here.

Read from the source, nothing imported. A second MAC is a second definition of one (a function named
mac or mac_matrix anywhere in flexshaft); a second damped eigen-solver is a general (non-symmetric)
eigen-solve - numpy's or scipy's eig or eigvals - outside the one solver (linalg/firstorder.py).
Symmetric problems (eigh, eigvalsh: undamped modes, Gram matrices) are other problems and not counted.
"""

from __future__ import annotations

import re

from tests.conftest import ROOT

# A general eigen-solve: np.linalg.eig(…), np.linalg.eigvals(…), scipy.linalg.eig(…), sla.eig(…) ...
GENERAL_EIG = re.compile(r"\b(?:np\.linalg|numpy\.linalg|scipy\.linalg|sla|la)\.eig(?:vals)?\(")
# The one exception: the time run diagonalises its discrete propagator once to run the recursion
# x_{k+1} = F x_k in modal blocks (analysis/discreteloop.py's ModalBlocks). It needs the eigenvectors
# and their condition of numpy's eig, and finds no poles: the loop's poles are damped_eigen's
# (_worst_pole). The nonlinear run's recursion uses a Schur form instead (linalg/recursion.py).
PROPAGATOR = "np.linalg.eig(Fk)"


def _sources():
    for path in sorted((ROOT / "flexshaft").rglob("*.py")):
        yield path.relative_to(ROOT).as_posix(), path.read_text()


def test_one_mac():
    defined = [
        path
        for path, text in _sources()
        if re.search(r"^\s*def (?:_?mac|_?mac_matrix)\(", text, re.MULTILINE)
    ]
    assert defined == ["flexshaft/linalg/mac.py"]


def test_one_damped_eigen_solver():
    found = []
    for path, text in _sources():
        for line in text.splitlines():
            if (
                GENERAL_EIG.search(line)
                and path != "flexshaft/linalg/firstorder.py"
                and PROPAGATOR not in line
            ):
                found.append(f"{path}: {line.strip()}")
    assert found == []


def _defined(pattern: str) -> list[str]:
    """The files defining a function or class whose name matches ``pattern`` (a regular expression)."""
    rx = re.compile(rf"^\s*(?:def|class) (?:{pattern})\b", re.MULTILINE)
    return [path for path, text in _sources() if rx.search(text)]


def test_one_twist_test():
    """The twist test serves 1D and solid parts: no solid twist test beside it."""
    assert _defined("twist_test") == ["flexshaft/analysis/twist.py"]
    assert _defined("_?solid_stiffness|_?solid_twist") == []


def test_one_craig_bampton_front_end_and_check():
    assert _defined("craig_bampton") == ["flexshaft/reduction/craig_bampton.py"]
    assert _defined("cb_check") == ["flexshaft/reduction/check.py"]
    # (check.py's private _solid_check is cb_check's branch for a solid body's recovery, inside the one)
    assert _defined("solid_reduction|solid_check|solid_craig_bampton|solid_modes") == []


def test_one_averaging_interface():
    """One RBE3 formulation: the held masters (averaged end faces) are written once."""
    assert _defined("_?HeldMasters|_?averaged") == ["flexshaft/parts/solidties.py"]


def test_one_report():
    """One HTML report generator (the study's; ``flexshaft report MODEL`` is a study). The only other
    page is the 3D viewer's own file (``flexshaft view -o FILE.html``), which the report embeds."""
    pages = sorted(path for path, text in _sources() if "<!DOCTYPE" in text.upper())
    assert pages == ["flexshaft/study/report.py", "flexshaft/views/webview.py"]
    assert not (ROOT / "flexshaft" / "views" / "report.py").exists()


def test_one_result_serialisation():
    """A result serialises itself (``to_dict``); no module of views writes documents of results."""
    documents = [p for p in _defined(r"\w+_document") if p.startswith("flexshaft/views/")]
    assert documents == []
    assert not (ROOT / "flexshaft" / "views" / "tables.py").exists()


def test_one_toml_schema_layer():
    """Every TOML file is parsed in one place (input/schema.py, on system/nesting's depth check), and the
    unknown-key message is written once. The tuned-model writer re-reads the model document it edits."""
    parsers = sorted(
        path
        for path, text in _sources()
        if re.search(r"\btoml_document\(|\btomllib\.loads?\(", text) and path != "flexshaft/system/nesting.py"
    )
    assert parsers == ["flexshaft/input/schema.py", "flexshaft/study/tunedfile.py"]
    # (sections/table.py: table_from_segments checks the mappings a Python caller hands it)
    unknown = [path for path, text in _sources() if '"unknown key"' in text]
    assert unknown == ["flexshaft/input/schema.py", "flexshaft/sections/table.py"]

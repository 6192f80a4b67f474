"""One place each (issue 34): one MAC (linalg/mac.py) and one damped eigen-solver (linalg/firstorder.py).

Read from the source, nothing imported: a second MAC is a second definition of one (a function named
mac or mac_matrix anywhere in flexshaft); a second damped eigen-solver is a general (non-symmetric)
eigen-solve - numpy's or scipy's eig or eigvals - outside the one solver. Symmetric problems (eigh,
eigvalsh: undamped modes, Gram matrices) are other problems and not counted.
"""

from __future__ import annotations

import re

from tests.conftest import ROOT

# A general eigen-solve: np.linalg.eig(…), np.linalg.eigvals(…), scipy.linalg.eig(…), sla.eig(…) ...
GENERAL_EIG = re.compile(r"\b(?:np\.linalg|numpy\.linalg|scipy\.linalg|sla|la)\.eig(?:vals)?\(")
# The one exception: the time run diagonalises its discrete propagator once to run the recursion
# x_{k+1} = F x_k in modal blocks (analysis/simulate.py's _Linear). It needs the eigenvectors and their
# condition of numpy's eig, and finds no poles: the loop's poles are damped_eigen's (_worst_pole).
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

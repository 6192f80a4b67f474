"""Shared fixtures and reference values for the tests."""

import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

# Compiled bytecode is cached (Python's default) even where the environment says otherwise
# (PYTHONDONTWRITEBYTECODE=1 in some sandboxes and CI images): hundreds of tests start `flexshaft` as a
# process, and each compiled the package anew - a fifth of those tests' time.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

# Section tables cached by the tests go to a folder of their own, never the user's cache (tests of
# the cache itself point FLEXSHAFT_CACHE_DIR at their own temporary folders).
os.environ.setdefault("FLEXSHAFT_CACHE_DIR", tempfile.mkdtemp(prefix="flexshaft-test-cache-"))


def _test_threads():
    """The tests' own linear algebra (dense references, peers in-process) on flexshaft's thread policy.

    flexshaft's functions pin their BLAS threads themselves; the reference computations in the tests do
    not, and on a busy machine two OpenBLAS threads made the suite several times slower. Where the user
    set OPENBLAS_NUM_THREADS / OMP_NUM_THREADS (or FLEXSHAFT_THREADS), that count stands - which is how
    the suite is checked with two threads too.
    """
    import scipy.linalg  # noqa: F401 - both BLAS libraries loaded (numpy's and scipy's), so both are limited
    from threadpoolctl import threadpool_limits

    from flexshaft.system.threads import requested_threads

    n = requested_threads()
    return None if n is None else threadpool_limits(limits=n)


_THREADS = _test_threads()  # held for the whole session

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

# The uniform shaft of the issue: steel G = 81 GPa, rho = 7850 kg/m³, D = 0.2 m, L = 4 m.
G, RHO, D, L = 81e9, 7850.0, 0.2, 4.0
IP = np.pi * D**4 / 32.0


#: The peers' interpreter (benchmarks/setup_peers.sh: ROSS, openTorsion, scikit-fem ... in their own venv).
PEER_PYTHON = ROOT / "benchmarks" / ".venv-peers" / "bin" / "python"


def run_peer(script: str, spec, *, what: str, timeout: float):
    """The JSON a peer script of benchmarks/peers prints last, given ``spec`` as JSON on its stdin, run
    by the peers' interpreter on one BLAS thread (steady on a busy machine; the peers' dense solves are
    small); the test is skipped where the peers' virtualenv (``what`` names it) is missing."""
    import json
    import subprocess

    if not PEER_PYTHON.exists():
        pytest.skip(f"{what} peer virtualenv missing: run benchmarks/setup_peers.sh")
    proc = subprocess.run(
        [str(PEER_PYTHON), str(ROOT / "benchmarks" / "peers" / script)],
        input=json.dumps(spec),
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture
def examples_dir() -> Path:
    return EXAMPLES


def gmsh_loads() -> bool:
    """Whether gmsh imports: installed (the solid extra) and its library's system dependencies there."""
    try:
        import gmsh  # noqa: F401
    except (ImportError, OSError):
        return False
    return True


def exudyn_loads() -> bool:
    """Whether Exudyn imports: installed (the multibody extra) and the system's OpenGL and X11 client
    libraries its module links there."""
    try:
        import exudyn  # noqa: F401
    except (ImportError, OSError):
        return False
    return True


def solid_shaft_model(od: str, mesh_size: str) -> str:
    """A model file's text: a 1 m steel shaft of diameter ``od`` (m) meshed as a solid at ``mesh_size``
    between two rigid 1 kg·m² inertias (the meshing tests' part: size and count from the two)."""
    return (
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 1.0\n'
        '[[chain]]\nname = "shaft"\ntype = "shaft"\nmaterial = "steel"\n'
        f'segments = [{{length = 1.0, od = {od}}}]\nfe = "solid"\nmesh_size = "{mesh_size}"\n'
        '[[chain]]\nname = "load"\ntype = "rigid"\ninertia = 1.0\n'
    )


def full_shaft_model(model_keys: str = "") -> str:
    """A 6-DOF model file's text: a motor (5 kg·m²) and a 1 m, 0.1 m steel shaft in 0.05 m elements, on
    bearings of 1e9 N/m at the motor and the shaft's end; ``model_keys`` adds lines to ``[model]``."""
    return (
        f'[model]\ndofs = "full"\n{model_keys}\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 5.0\n\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\n'
        "segments = [{length = 1.0, od = 0.1}]\nmax_element_length = 0.05\n\n"
        '[[bearings]]\nstation = "motor"\nstiffness = 1e9\n\n'
        '[[bearings]]\nstation = "s end"\nstiffness = 1e9\n'
    )


def without_progress(err: str) -> str:
    """stderr without the progress lines long work writes off a terminal (``label: state (N s)``, one
    every 5 s: :mod:`flexshaft.views.progress`) - on a busy machine a check's command may take that long."""
    import re

    return "".join(
        line
        for line in err.splitlines(True)
        if not re.fullmatch(r"(?!flexshaft: )[^\n]+: [^\n]+ \(\d+ s\)\n?", line)
    )

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


def solid_shaft_model(od: str, mesh_size: str) -> str:
    """A model file's text: a 1 m steel shaft of diameter ``od`` (m) meshed as a solid at ``mesh_size``
    between two rigid 1 kg·m² inertias (the meshing tests' part: size and count from the two)."""
    return (
        '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 1.0\n'
        '[[chain]]\nname = "shaft"\ntype = "shaft"\nmaterial = "steel"\n'
        f'segments = [{{length = 1.0, od = {od}}}]\nfe = "solid"\nmesh_size = "{mesh_size}"\n'
        '[[chain]]\nname = "load"\ntype = "rigid"\ninertia = 1.0\n'
    )

"""Shared fixtures and reference values for the tests."""

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

# Section tables cached by the tests go to a folder of their own, never the user's cache (tests of
# the cache itself point FLEXSHAFT_CACHE_DIR at their own temporary folders).
os.environ.setdefault("FLEXSHAFT_CACHE_DIR", tempfile.mkdtemp(prefix="flexshaft-test-cache-"))

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

# The uniform shaft of the issue: steel G = 81 GPa, rho = 7850 kg/m³, D = 0.2 m, L = 4 m.
G, RHO, D, L = 81e9, 7850.0, 0.2, 4.0
IP = np.pi * D**4 / 32.0


@pytest.fixture
def examples_dir() -> Path:
    return EXAMPLES

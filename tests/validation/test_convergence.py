"""A uniform free-free shaft converges to the continuum frequencies at rate 2.

Reference: the free-free uniform shaft in torsion has f_k = k/(2L)·√(G/ρ)
(e.g. Rao, Mechanical Vibrations, torsional vibration of a uniform shaft).
Linear elements give eigenvalue errors O(h²): consistent inertia from above
(Rayleigh-Ritz bound), lumped inertia from below.
"""

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import IP, RHO, G, L

K_TOTAL = G * IP / L  # N·m/rad
J_TOTAL = RHO * IP * L  # kg·m²
MODES = np.arange(1, 4)
EXACT = MODES / (2 * L) * np.sqrt(G / RHO)
SIZES = np.array([8, 16, 32, 64, 128])


def _errors(model: str) -> np.ndarray:
    errs = []
    for n in SIZES:
        dt = fs.Drivetrain("u", [fs.Shaft("shaft", K_TOTAL, J_TOTAL, elements=int(n))], inertia_model=model)
        f = fs.modal_analysis(dt, count=4).frequencies_hz[1:]
        errs.append(f / EXACT - 1.0)
    return np.array(errs)


@pytest.mark.parametrize("model, sign", [("consistent", 1.0), ("lumped", -1.0)])
def test_uniform_shaft_converges_at_rate_two(model, sign):
    err = _errors(model)
    assert np.all(sign * err > 0), "consistent inertia converges from above, lumped from below"
    for k in range(len(MODES)):
        rate = -np.polyfit(np.log(SIZES), np.log(np.abs(err[:, k])), 1)[0]
        assert rate == pytest.approx(2.0, abs=0.05), f"mode {k + 1}: fitted rate {rate:.3f}"
    assert np.max(np.abs(err[-1])) < 1e-3


def test_large_model_uses_the_sparse_path_and_matches_the_continuum():
    n = 20_000
    dt = fs.Drivetrain("u", [fs.Shaft("shaft", K_TOTAL, J_TOTAL, elements=n)])
    r = fs.modal_analysis(dt)
    assert r.count == 10 and "Lanczos" in r.method
    exact = np.arange(10) / (2 * L) * np.sqrt(G / RHO)
    # Consistent-mass error for mode k is ≈ (kπ/n)²/24 relative (O(h²) leading term): < 1e-7 here.
    assert r.frequencies_hz[1:] == pytest.approx(exact[1:], rel=1e-6)
    assert r.frequencies_hz[0] == 0.0  # set, not solved for


@pytest.mark.parametrize("n", [50, 1000, 20_000])
@pytest.mark.parametrize("model", ["consistent", "lumped"])
def test_solver_hits_the_exact_discrete_eigenvalues(n, model):
    # A uniform free-free chain of n linear elements has modes cos(κx) sampled at the
    # nodes, with κ = kπ/L and, writing c² = G/ρ and h = L/n,
    #   consistent: λ = (6c²/h²)(1 − cos κh)/(2 + cos κh)
    #   lumped:     λ = (2c²/h²)(1 − cos κh)   (the spring-mass chain, ω = 2(c/h)·sin(κh/2))
    # (dispersion of linear elements, e.g. Hughes, The Finite Element Method, ch. 9).
    # This separates solver accuracy from discretisation error: it must be round-off. Its size: the
    # eigenvalue is the Rayleigh quotient vᵀKv, whose K·v cancels element stiffnesses n·k_total down to λ,
    # ~eps·n^1.5/π² relative as a random walk (6e-11 at n = 20 000, 2e-13 measured); the dense path at
    # n = 50: eps·λ_max/λ₁ = eps·12n²/π² ≈ 7e-13. 1e-10 on f still tells the two inertia models apart:
    # they differ by (kπ/n)²/12 = 2e-9 on the first mode at n = 20 000.
    dt = fs.Drivetrain("u", [fs.Shaft("shaft", K_TOTAL, J_TOTAL, elements=n)], inertia_model=model)
    r = fs.modal_analysis(dt, count=10, damped=False)
    h, c2 = L / n, G / RHO
    kh = np.arange(1, 10) * np.pi / n
    one_minus_cos = 2.0 * np.sin(kh / 2) ** 2  # 1 − cos x without cancellation
    if model == "consistent":
        lam = 6 * c2 / h**2 * one_minus_cos / (2 + np.cos(kh))
    else:
        lam = 2 * c2 / h**2 * one_minus_cos
    assert r.frequencies_hz[1:] == pytest.approx(np.sqrt(lam) / (2 * np.pi), rel=1e-10)
    assert ("Lanczos" in r.method) == (n > 600)

"""Modes of single parts: free, and on bearing springs, against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import part_modes
from flexshaft.parts.model import part_model
from flexshaft.sections import cowper_shear_factor, table_from_segments

E, G, RHO, NU = fs.STEEL.E, fs.STEEL.G, fs.STEEL.rho, fs.STEEL.nu


def tube(L=2.0, D=0.1, n=100, dofs="full"):
    return part_model(
        table_from_segments([{"length": L, "od": D}]), fs.STEEL, dofs=dofs, max_element_length=L / n
    )


def test_free_part_has_six_zero_modes_then_the_torsion_and_bending_ones():
    L, D = 2.0, 0.1
    m = part_modes(tube(L, D), count=20)
    assert m.rigid.sum() == 6 and np.all(m.frequencies_hz[:6] == 0.0)  # rigid-body modes are set to 0
    # First free-free torsion mode of a uniform shaft: f = 1/(2L)·√(G/ρ) (any text on torsional vibration).
    f_torsion = 1 / (2 * L) * math.sqrt(G / RHO)
    assert np.min(np.abs(m.frequencies_hz[6:] / f_torsion - 1)) < 1e-3
    # First free-free bending mode, Euler–Bernoulli: (4.7300/L)² √(EI/ρA)/(2π); Timoshenko lowers it
    # slightly (L/D = 20: ~0.3 %), so it lies within 1 % below.
    I, A = math.pi * D**4 / 64, math.pi * D**2 / 4
    f_eb = (4.7300407 / L) ** 2 * math.sqrt(E * I / (RHO * A)) / (2 * math.pi)
    first = m.frequencies_hz[6]
    assert 0.99 * f_eb < first < f_eb
    assert np.sum(np.abs(m.frequencies_hz[6:8] / first - 1) < 1e-9) == 2  # the y and z planes: a pair


def test_stiff_bearings_at_the_ends_give_pinned_pinned_timoshenko():
    # Pinned-pinned Timoshenko beam (Timoshenko 1921; Han, Benaroya & Wei, J. Sound Vib. 225, 1999):
    # EI k⁴ − ρA ω² − ρI ω² k² (1 + E/(κG)) + ρ² I ω⁴/(κG) = 0, k = π/L, lower root.
    L, D = 1.0, 0.1
    part = tube(L, D, n=60)
    m = part_modes(part, count=8, bearings={0: 1e14, part.n_nodes - 1: 1e14})
    assert m.rigid.sum() == 2  # axial and spin remain free
    I, A = math.pi * D**4 / 64, math.pi * D**2 / 4
    kap = cowper_shear_factor(0.0, NU)
    k = math.pi / L
    a, b, c = RHO**2 * I / (kap * G), -(RHO * A + RHO * I * k**2 * (1 + E / (kap * G))), E * I * k**4
    w2 = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    f_exact = math.sqrt(w2) / (2 * math.pi)
    elastic = m.frequencies_hz[~m.rigid]
    assert elastic[0] == pytest.approx(f_exact, rel=2e-4) and elastic[1] == pytest.approx(f_exact, rel=2e-4)


def test_bearing_errors():
    with pytest.raises(fs.ModelError, match="bearings act on lateral DOFs"):
        part_modes(tube(dofs="torsion"), bearings={0: 1e8})
    with pytest.raises(fs.ModelError, match=r"bearings\[0\] = -1.0 N/m"):
        part_modes(tube(), bearings={0: -1.0})


def test_a_part_model_goes_through_the_one_modal_analysis():
    # modal_analysis(part) is part_modes(part) (the part as a one-component model). Reference: a free
    # uniform rod of n linear elements with consistent inertia has the sampled cos(kπx/L) as exact
    # discrete modes, so ω_k = (c/h)·√(6(1 − cos θ)/(2 + cos θ)), θ = kπh/L, to round-off.
    L, n_el = 1.0, 10
    part = tube(L, 0.1, n=n_el, dofs="torsion")
    r = fs.modal_analysis(part, 4)
    # the same assembly and the same solve in one process: bit for bit
    np.testing.assert_array_equal(r.frequencies_hz, part_modes(part, 4).frequencies_hz)
    h, theta = L / n_el, np.arange(1, 4) * np.pi / n_el
    exact = math.sqrt(G / RHO) / h * np.sqrt(6 * (1 - np.cos(theta)) / (2 + np.cos(theta))) / (2 * np.pi)
    # round-off of a dense 11-DOF solve: eps·λ_max/λ₁/2 = eps·6n²/π² ≈ 1e-14; 1e-10 is loose
    np.testing.assert_allclose(r.frequencies_hz[1:], exact, rtol=1e-10)
    assert r.model.component_names == (part.name,)
    assert r.strain_energy_fractions()[1:, 0] == pytest.approx(1.0)
    with pytest.raises(fs.ModelError, match="inertia_model = 'lumped': a part model's mass is spread"):
        fs.modal_analysis(part, 4, inertia_model="lumped")


def test_a_1d_part_takes_the_direct_strategy_only():
    # a 1D part is banded (LAPACK's banded factorisations): asking for multigrid is refused, not ignored
    from flexshaft.errors import ModelError

    part = part_model(table_from_segments([{"length": 1.0, "od": 0.1}]), fs.STEEL, dofs="torsion")
    with pytest.raises(ModelError, match="banded"):
        part_modes(part, 2, solver="amg")
    with pytest.raises(ModelError, match="solver"):
        part_modes(part, 2, solver="cholesky")

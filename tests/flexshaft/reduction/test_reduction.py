"""Craig–Bampton reduction of part models: static exactness, convergence, rigid mass, damping per mode."""

from __future__ import annotations

import io
import re
import warnings

import numpy as np
import pytest
import scipy.linalg as la

import flexshaft as fs
from flexshaft.analysis.modal import part_modes
from flexshaft.parts.model import part_model
from flexshaft.reduction import ModalDamping, cb_check, craig_bampton, select_modes
from flexshaft.sections import table_from_segments

PYYETI_MISSING = "pyyeti (the peer tool, from the test extra: pip install -e '.[test]') is not installed"

TABLE = table_from_segments([{"length": 1.0, "od": 0.2, "id": 0.1}, {"length": 0.8, "od": 0.12}], name="p")


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_static_exactness_and_rigid_mass(dofs):
    # Craig & Bampton (1968): the constraint modes make the reduced interface stiffness the exact static
    # condensation, and the rigid-body mass is carried exactly by the constraint modes.
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.02)
    fb = craig_bampton(pm, modes=6)
    check = cb_check(fb, pm)
    # Round-off only. The condensation cancels the end elements' stiffness down to the part's (340x in
    # torsion, 130x full): ~eps·340 ≈ 1e-13 (1.3e-13 seen). The rigid mass rests on Ψ carrying the rigid
    # motions, to eps·κ(K_ii) with K_ii's scaled condition number 4e3 / 4e4: 1e-11 at most.
    assert check.static_error < 1e-10
    assert check.rigid_mass_error < 1e-10
    assert check.symmetry == 0.0  # K and M are symmetrised as (A + Aᵀ)/2: exactly symmetric
    # 6 fixed-interface modes, then one residual vector per boundary DOF.
    assert fb.n_boundary == (2 if dofs == "torsion" else 12)
    assert fb.n_residual == fb.n_boundary and fb.n_modes == 6 + fb.n_residual
    # Residual vectors, like the modes, leave the boundary uncoupled from the modal coordinates in K.
    nb = fb.n_boundary
    # K_bq = (K_bi + ΨᵀK_ii)·Φ cancels to round-off: a few eps of max|K| (3e-15 seen).
    assert np.max(np.abs(fb.K[:nb, nb:])) < 1e-12 * np.abs(fb.K).max()


# Slow (CI's `pytest -m slow` step): a convergence study - 37 reductions of a 546-DOF part per case, mode by
# mode from 1 to 32. 1-3 s alone on the 2-core machine, but its many small dense solves spin OpenBLAS's two
# threads and take 12-42 s when the machine is busy (the suite's longest test in every run measured).
@pytest.mark.slow
@pytest.mark.parametrize("residual", [False, True])
def test_free_frequencies_converge_as_modes_are_added(residual):
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.02)
    full = part_modes(pm, 20).frequencies_hz
    errs = []
    for n in (4, 8, 16, 32):
        fb = craig_bampton(pm, modes=n, residual=residual)
        errs.append(np.max(np.abs(fb.free_hz[6:12] / full[6:12] - 1)))
    assert np.all(np.diff(errs) < 0)  # monotone: CB is a Rayleigh–Ritz method on nested subspaces
    assert errs[-1] < 1e-3
    # Ritz values bound the full model's from above - up to round-off: the full model's dense solve is
    # good to eps·λ_max/λ₇/2 = 5e-11 (f_max = 1.4e5 Hz against 206 Hz): 3e-10.
    fb = craig_bampton(pm, modes=8, residual=residual)
    assert np.all(fb.free_hz[6:12] >= full[6:12] * (1 - 3e-10))
    # Each mode on its own, not just the worst: the subspace for n + 1 modes contains the one for n, so by
    # the Poincaré separation theorem no Ritz frequency rises when a mode is added - up to the reduced
    # solves' round-off, eps·λ_max/λ/2 <= 2e-12 (their f_max <= 2.7e4 Hz; measured at most 2.3e-13).
    prev = None
    for n in range(1, 33):
        f = craig_bampton(pm, modes=n, residual=residual).free_hz[6:18]
        if prev is not None:
            m = min(f.size, prev.size)
            assert np.all(f[:m] <= prev[:m] * (1 + 1e-10)), n
        prev = f


def test_cutoff_keeps_every_fixed_interface_mode_below_it():
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.01)
    fb = craig_bampton(pm, cutoff_hz=5000.0)
    all_fixed = craig_bampton(pm, modes=40, residual=False).fixed_interface_hz
    kept = fb.fixed_interface_hz[: fb.n_modes - fb.n_residual]
    # The same fixed-interface problem solved twice: each to eps·λ_max/λ₁/2 ≈ 2e-12 (180 elements).
    np.testing.assert_allclose(kept, all_fixed[all_fixed < 5000.0], rtol=1e-10)
    # The residual vectors' Ritz frequencies lie above the cut-off.
    assert fb.n_residual == 2 and np.all(fb.fixed_interface_hz[kept.size :] > 5000.0)


def test_a_part_without_interior_nodes_is_its_own_reduction():
    """One element: every DOF is an interface DOF, so the reduction is the identity - the body's K and M
    are the part's (a cut-off used to index an empty list of fixed-interface modes)."""
    one = table_from_segments([{"length": 1.0, "od": 0.2}], name="one")
    pm = part_model(one, fs.STEEL, dofs="torsion", max_element_length=10.0)
    assert pm.n_dofs == 2
    for kwargs in ({"cutoff_hz": 6000.0}, {"modes": 3}):
        fb = craig_bampton(pm, residual=False, **kwargs)
        assert fb.n_modes == 0
        # Same matrices, only symmetrised: equal to a few eps of their scale.
        np.testing.assert_allclose(fb.K, pm.K.toarray(), rtol=1e-13, atol=1e-13 * abs(pm.K).max())
        np.testing.assert_allclose(fb.M, pm.M.toarray(), rtol=1e-13, atol=1e-13 * abs(pm.M).max())


def test_damped_eigenvalues_carry_the_set_ratio():
    # First-order form of the reduced part: every elastic mode has λ = −ξω ± iω√(1−ξ²).
    # (Textbook CB here: residual vectors add 10⁵ Hz modes that this unscaled 2n solve resolves to 1e-5
    # only; the next tests check the default body with a scaled solve.)
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.05)
    fb = craig_bampton(pm, modes=10, damping_ratio=0.0053, residual=False)
    n = fb.K.shape[0]
    # M = LLᵀ turns M q̈ + C q̇ + K q = 0 into a standard problem in Lᵀq. Why not QZ on the pencil
    # ([[0, I], [−K, −C]], diag(I, M)): M's condition number (6e4 here) multiplies its round-off, and a
    # newer BLAS measured 1.8e-6 on the degenerate bending pairs. In this form the matrix's norm is
    # ω_max² (2e9 (rad/s)²), so each λ is within ~n·eps·ω_max² and ξ within ~n·eps·(ω_max/ω_1)²/ξ ≈ 1e-9
    # relative (measured 1e-13): rtol 1e-6 leaves three orders for other BLAS builds.
    L = np.linalg.cholesky(fb.M)
    Kt, Ct = (
        la.solve_triangular(L, la.solve_triangular(L, X, lower=True).T, lower=True) for X in (fb.K, fb.C)
    )
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-0.5 * (Kt + Kt.T), -0.5 * (Ct + Ct.T)]])
    lam = la.eigvals(A)
    # The 6 rigid-body modes are zero eigenvalues (round-off sized); the elastic ones come in pairs.
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))][-(n - 6) :]
    zeta = -lam.real / np.abs(lam)
    np.testing.assert_allclose(zeta, 0.0053, rtol=1e-6)


def test_bad_reduction_input():
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.05)
    with pytest.raises(fs.ModelError, match="give either modes or cutoff_hz"):
        craig_bampton(pm)
    with pytest.raises(fs.ModelError, match="damping_ratio = 1.5: must be in"):
        craig_bampton(pm, modes=3, damping_ratio=1.5)


@pytest.mark.parametrize("suffix", [".npz", ".json", ".mat", ".op4"])
def test_export_round_trip_and_unit_check(tmp_path, suffix):
    import json

    from flexshaft.exports.bodies import read_flexible_body, write_flexible_body

    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.1)
    fb = craig_bampton(pm, modes=4)
    path = tmp_path / f"p{suffix}"
    write_flexible_body(fb, path, material=fs.STEEL)
    with pytest.raises(fs.ModelError, match="file exists"):
        write_flexible_body(fb, path)
    _read = read_flexible_body(path)
    back, meta = _read.body, _read.metadata
    for name in (
        "K",
        "M",
        "C",
        "T",
        "free_hz",
        "fixed_interface_hz",
        "damping_ratios",
        "boundary_x",
        "boundary_nodes",
        "free_modes",
    ):
        np.testing.assert_array_equal(getattr(back, name), getattr(fb, name))  # bit-identical
    assert back.name == "p" and back.dofs == "full" and meta["material"]["name"] == "steel"
    assert back.n_residual == fb.n_residual == 12 and meta["residual_vectors"] == 12
    assert meta["dof_order"][:7] == [
        "node 0 ux",
        "node 0 uy",
        "node 0 uz",
        "node 0 θx",
        "node 0 θy",
        "node 0 θz",
        f"node {pm.n_nodes - 1} ux",
    ]
    # A file in other units is refused, naming both.
    if suffix == ".json":
        doc = json.loads(path.read_text())
        doc["units"]["length"] = "mm"
        path.write_text(json.dumps(doc))
        with pytest.raises(fs.ModelError, match="the file's length unit is 'mm', flexshaft's is 'm'"):
            read_flexible_body(path)


def test_cli_reduce(tmp_path, capsys):
    from flexshaft.cli import main
    from flexshaft.exports.bodies import read_flexible_body

    model = tmp_path / "m.toml"
    model.write_text(
        '[model]\ndofs = "full"\n\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 5.0\n\n'
        '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\ndamping_ratio = 0.01\n'
        "segments = [{length = 1.0, od = 0.1}]\nmax_element_length = 0.05\nstations = {journal = 0.4}\n"
    )
    out = tmp_path / "s.npz"
    assert main(["reduce", str(model), "--part", "s", "--modes", "5", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "18 boundary DOFs at x = 0, 0.4, 1 m + 5 fixed-interface modes + 18 residual vectors" in text
    _read = read_flexible_body(out)
    body, meta = _read.body, _read.metadata
    assert body.n_boundary == 18 and meta["material"]["name"] == "steel"
    assert np.all(body.damping_ratios[~(body.free_hz == 0)] == 0.01)  # the part's damping_ratio
    assert main(["reduce", str(model), "--part", "s", "--modes", "5", "-o", str(out)]) == 2
    assert "file exists" in capsys.readouterr().err
    assert main(["reduce", str(model), "--part", "motor", "--modes", "5", "-o", str(out), "--force"]) == 2
    assert "--part = 'motor': has no elements to reduce" in capsys.readouterr().err


def test_pyyeti_reads_our_op4_exactly(tmp_path):
    # Peer check: pyyeti's op4 reader gives back our K and T bit for bit.
    op4 = pytest.importorskip("pyyeti.nastran.op4", reason=PYYETI_MISSING)
    from flexshaft.exports.bodies import write_flexible_body

    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.1)
    fb = craig_bampton(pm, modes=4)
    assert fb.n_residual == 12
    write_flexible_body(fb, tmp_path / "p.op4")
    d = op4.read(str(tmp_path / "p.op4"))
    assert np.array_equal(d["kaa"], fb.K) and np.array_equal(d["trec"], fb.T)


# --- damping per mode, per band, Rayleigh -------------------------------------------------------------------


def _damped_eigenvalues(K, M, C):
    """Eigenvalues of M ẍ + C ẋ + K x = 0 from its first-order form, solved densely.

    Scaled so that the stiff residual-vector modes (10⁵ Hz) do not swamp the low ones: with
    M = LLᵀ and x = L⁻ᵀ y, ÿ + L⁻¹CL⁻ᵀ ẏ + L⁻¹KL⁻ᵀ y = 0; the state [y, ẏ/s] with s the largest
    frequency keeps the first-order matrix of norm ~s. (No use of the modes under test.)
    """
    n = K.shape[0]
    L = np.linalg.cholesky(M)
    Kt = la.solve_triangular(L, la.solve_triangular(L, K, lower=True).T, lower=True)
    Ct = la.solve_triangular(L, la.solve_triangular(L, C, lower=True).T, lower=True)
    s = np.sqrt(np.abs(Kt).max())
    A = np.block([[np.zeros((n, n)), s * np.eye(n)], [-Kt / s, -Ct]])
    return la.eigvals(A)


def _assert_modes_carry(lam, omega, zeta, rtol=1e-6):
    """Every elastic mode (ω, ξ) is one computed eigenvalue −ξω + iω√(1−ξ²), each eigenvalue used once.

    ``rtol``: the non-symmetric 2n × 2n solve resolves a degenerate pair (bending in y and z) to ~1e-7 only.
    """
    from scipy.optimize import linear_sum_assignment

    expected = -zeta * omega + 1j * omega * np.sqrt(1 - zeta**2)
    upper = lam[lam.imag > 0]
    rows, cols = linear_sum_assignment(np.abs(expected[:, None] - upper[None, :]))
    assert rows.size == expected.size
    got = upper[cols]
    np.testing.assert_allclose(-got.real / np.abs(got), zeta[rows], rtol=rtol)  # the damping ratio
    np.testing.assert_allclose(np.abs(got), omega[rows], rtol=rtol)  # |λ| = ω for viscous modal damping


@pytest.mark.parametrize(
    "damping",
    [
        ModalDamping(by_mode=(0.01, 0.02, 0.03)),
        ModalDamping(ratio=0.005, bands=((0.0, 500.0, 0.02), (1000.0, 2000.0, 0.04))),
        ModalDamping(rayleigh=(5.0, 2e-6)),
    ],
    ids=["by_mode", "bands", "rayleigh"],
)
def test_damped_eigenvalues_carry_the_modal_damping(damping):
    # Modal damping C = M V diag(2ξω) Vᵀ M and Rayleigh αM + βK are both diagonal on the free-free modes
    # V, so the damped eigenvalues are exactly −ξω ± iω√(1−ξ²) with the set ξ on every elastic mode.
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.05)
    fb = craig_bampton(pm, modes=10, damping_ratio=damping)
    elastic = fb.free_hz > 0
    f, zeta = fb.free_hz[elastic], fb.damping_ratios[elastic]
    assert np.all(fb.damping_ratios[~elastic] == 0) and np.count_nonzero(~elastic) == 6
    if damping.by_mode:
        # Mode 1 (206 Hz), 2 (its twin bending in the other plane) and every higher one at the last ratio.
        np.testing.assert_array_equal(zeta, [0.01, 0.02] + [0.03] * (f.size - 2))
    elif damping.bands:
        want = np.where(f < 500, 0.02, np.where((f >= 1000) & (f < 2000), 0.04, 0.005))
        assert set(want) == {0.02, 0.04, 0.005}  # every band and the default are exercised
        np.testing.assert_array_equal(zeta, want)
    else:
        alpha, beta = damping.rayleigh
        np.testing.assert_array_equal(fb.C, alpha * fb.M + beta * fb.K)  # exactly, on the reduced matrices
        # the closed form of the mode's own f in another order: a few roundings
        np.testing.assert_allclose(zeta, alpha / (4 * np.pi * f) + beta * np.pi * f, rtol=1e-12)
        assert zeta.max() < 1  # every elastic mode underdamped, so each has a complex pair to compare
    _assert_modes_carry(_damped_eigenvalues(fb.K, fb.M, fb.C), 2 * np.pi * f, zeta)


def test_damping_ratio_as_float_sequence_or_modal_damping():
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.05)
    a = craig_bampton(pm, modes=4, damping_ratio=0.02)
    b = craig_bampton(pm, modes=4, damping_ratio=ModalDamping(ratio=0.02))
    np.testing.assert_array_equal(a.damping_ratios[1:], 0.02)
    np.testing.assert_array_equal(a.damping_ratios, b.damping_ratios)
    np.testing.assert_array_equal(a.C, b.C)
    # A sequence is one ratio per mode of the orthonormalised basis; the rigid one is ignored (set to 0).
    c = craig_bampton(pm, modes=4, damping_ratio=[0.5, 0.01, 0.02, 0.03, 0.04, 0.05], residual=False)
    np.testing.assert_array_equal(c.damping_ratios, [0.0, 0.01, 0.02, 0.03, 0.04, 0.05])
    d = craig_bampton(
        pm, modes=4, damping_ratio=ModalDamping(by_mode=[0.01, 0.02, 0.03, 0.04, 0.05]), residual=False
    )
    np.testing.assert_array_equal(c.damping_ratios, d.damping_ratios)
    # The same ratios through two inputs: C = M V diag(2ξω) Vᵀ M alike, round-off ~n·eps of max|C| at most.
    np.testing.assert_allclose(c.C, d.C, rtol=0, atol=1e-12 * np.abs(c.C).max())


def test_modal_damping_ratios_rule():
    f = np.array([0.0, 100.0, 100.0, 250.0, 400.0, 900.0])
    rigid = f == 0
    np.testing.assert_array_equal(
        ModalDamping(by_mode=(0.01, 0.02)).ratios(f, rigid), [0, 0.01, 0.02, 0.02, 0.02, 0.02]
    )
    # Bands are half-open and may touch: 250 Hz belongs to the upper one; 900 Hz is in none and gets `ratio`.
    bands = ModalDamping(ratio=0.001, bands=[(0, 250, 0.01), (250.0, 500.0, 0.02)])
    assert bands.bands == ((0.0, 250.0, 0.01), (250.0, 500.0, 0.02))  # lists become tuples of floats
    np.testing.assert_array_equal(bands.ratios(f, rigid), [0, 0.01, 0.01, 0.02, 0.02, 0.001])
    # Rayleigh: ξ = α/(2ω) + βω/2 (α = 2 1/s, β = 1e-5 s at 100 Hz: 1/(200π) + 1e-3·π).
    ray = ModalDamping(rayleigh=[2.0, 1e-5])
    assert ray.rayleigh == (2.0, 1e-5)
    # ~5 roundings apart
    np.testing.assert_allclose(ray.ratios(f, rigid)[1], 1 / (200 * np.pi) + 1e-3 * np.pi, rtol=1e-14)
    assert ray.ratios(f, rigid)[0] == 0
    assert hash(bands)  # frozen and made of tuples: usable as a key


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"ratio": 1.0}, r"damping_ratio = 1.0: must be in \[0, 1\); valid: a fraction in \[0, 1\)"),
        ({"ratio": "2 %"}, "damping_ratio = '2 %': not a number"),
        ({"by_mode": (0.01, -0.1)}, r"damping_ratio\[1\] = -0.1: must be in \[0, 1\)"),
        ({"by_mode": 0.01}, "damping_ratio = 0.01: not a sequence"),
        ({"bands": [(0, 50)]}, r"damping_bands\[0\] = \(0, 50\): must be three numbers"),
        (
            {"bands": [(-1, 50, 0.01)]},
            r"damping_bands\[0\] = \(-1.0, 50.0, 0.01\) \(Hz, Hz, -\): f_lo_hz must be",
        ),
        (
            {"bands": [(0, np.inf, 0.01)]},
            r"damping_bands\[0\] = \(0.0, inf, 0.01\) \(Hz, Hz, -\): f_hi_hz must be finite",
        ),
        ({"bands": [(100, 50, 0.01)]}, "f_hi_hz must be finite and above f_lo_hz"),
        ({"bands": [(0, 50, 1.2)]}, r"ratio must be in \[0, 1\)"),
        (
            {"bands": [(0, 100, 0.01), (50, 200, 0.02)]},
            r"damping_bands\[1\] = \(50.0, 200.0, 0.02\) \(Hz, Hz, -\): "
            r"overlaps damping_bands\[0\] = \(0.0, 100.0, 0.01\)",
        ),
        (
            {"rayleigh": (-1.0, 0.0)},
            r"rayleigh.alpha = -1.0 1/s: out of range; valid: a finite number >= 0 and <= 1e\+06 \(1/s\)",
        ),
        ({"rayleigh": (0.0, 1e300)}, r"rayleigh.beta = 1e\+300 s: out of range; valid: .* <= 1 \(s\)"),
        ({"rayleigh": (1.0, np.nan)}, "rayleigh.beta = nan s: not finite"),
        (
            {"rayleigh": (1.0,)},
            r"rayleigh = \(1.0,\): must be two numbers",
        ),
        ({"rayleigh": (1.0, 1e-6), "by_mode": (0.01,)}, "rayleigh: cannot be combined with ratios per mode"),
        (
            {"by_mode": (0.01,), "bands": [(0, 10, 0.1)]},
            "damping_bands: cannot be combined with ratios per mode",
        ),
    ],
)
def test_modal_damping_refuses_bad_input(kwargs, message):
    with pytest.raises(fs.ModelError, match=message):
        ModalDamping(**kwargs)


# --- mode selection -------------------------------------------------------------------------------------


def test_select_modes_gives_the_body_on_its_kept_free_modes():
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.05)
    fb = craig_bampton(pm, modes=8, damping_ratio=ModalDamping(by_mode=(0.01, 0.02)))
    keep = [9, 0, 1, 2, 3, 4, 5, 6, 7]  # any order; sorted into frequency order
    mb = select_modes(fb, keep)
    mask = np.zeros(fb.free_hz.size, bool)
    mask[keep] = True
    same = select_modes(fb, mask)
    np.testing.assert_array_equal(mb.shapes, same.shapes)
    np.testing.assert_array_equal(mb.modes, sorted(keep))
    omega = 2 * np.pi * fb.free_hz[mb.modes]
    np.testing.assert_array_equal(mb.frequencies_hz, fb.free_hz[mb.modes])
    np.testing.assert_array_equal(mb.damping_ratios, fb.damping_ratios[mb.modes])
    np.testing.assert_array_equal(mb.K, np.diag(omega**2))
    np.testing.assert_array_equal(mb.M, np.eye(9))
    np.testing.assert_array_equal(
        mb.C, np.diag(2 * mb.damping_ratios * omega)
    )  # rigid-body entries exactly 0
    assert mb.rigid.sum() == 6
    # The shapes are the part's own: mass-normalised on the full model, with ω² as Rayleigh quotients.
    M, K = pm.M.toarray(), pm.K.toarray()
    # The reduced M and K are Tᵀ M T and Tᵀ K T, so in exact arithmetic these are the reduced solve's
    # I and Ω². Round-off: n·eps on the mass (1.6e-15 seen); on the stiffness the Rayleigh quotients on
    # the full mesh cancel like eps·λ_max(full) = eps·8e3·ω_max² ≈ 2e-12 of ω_max² (8e-14 seen).
    np.testing.assert_allclose(mb.shapes.T @ M @ mb.shapes, np.eye(9), atol=1e-10)
    np.testing.assert_allclose(mb.shapes.T @ K @ mb.shapes, mb.K, atol=1e-8 * omega.max() ** 2)
    # At the boundary the recovery T is the identity: the boundary rows are the CB coordinates of the modes.
    np.testing.assert_array_equal(mb.boundary_shapes, fb.free_modes[: fb.n_boundary, mb.modes])
    elastic = select_modes(fb, [6, 7, 8], drop_rigid=True)
    assert not elastic.rigid.any() and elastic.shapes.shape == (pm.n_dofs, 3)


def test_select_modes_keeps_rayleigh_alpha_on_rigid_modes():
    # αM is a damper to ground: on a rigid-body mode VᵣᵀCVᵣ = α although its reported ratio is 0.
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.05)
    fb = craig_bampton(pm, modes=4, damping_ratio=ModalDamping(rayleigh=(3.0, 1e-6)))
    mb = select_modes(fb, [0, 1, 2])
    omega = 2 * np.pi * mb.frequencies_hz
    # Vᵀ(αM + βK)V = α·(1 ± n·eps) + β·(ω² ± its Rayleigh quotient's round-off): ~1e-14 relative; 1e-9.
    np.testing.assert_allclose(np.diag(mb.C), 3.0 + 1e-6 * omega**2, rtol=1e-9)
    assert mb.damping_ratios[0] == 0


@pytest.mark.parametrize(
    "keep, kwargs, message",
    [
        ([6, 7], {}, "keep: leaves out rigid-body mode.s. 0, 1, 2, 3, 4, 5; valid: every rigid-body mode"),
        ([0, 1, 2, 6], {}, "leaves out rigid-body mode.s. 3, 4, 5"),
        ([0, 6], {"drop_rigid": True}, "names rigid-body mode.s. 0 although drop_rigid is true"),
        ([0, 1, 2, 3, 4, 5, 99], {}, r"keep\[6\] = 99: no such mode; valid: indices from 0 to 19"),
        ([0, 0, 1, 2, 3, 4, 5], {}, "names a mode twice"),
        ([0.0, 1.0], {}, "not indices or a mask"),
        (np.ones(3, bool), {}, "has 3 flags for 20 modes"),
        ([], {}, "keeps no mode"),
    ],
)
def test_select_modes_refuses_bad_selection(keep, kwargs, message):
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.1)
    fb = craig_bampton(pm, modes=8, residual=False)
    with pytest.raises(fs.ModelError, match=message):
        select_modes(fb, keep, **kwargs)


# --- modal effective mass -------------------------------------------------------------------------------


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_effective_masses_of_all_modes_and_the_boundary_residual_make_the_rigid_mass(dofs):
    # With every fixed-interface mode kept, Φ Φᵀ M_ii = I, so
    #     Σ_k L_kᵀ L_k = Rbᵀ (M_bi + ΨᵀM_ii) M_ii⁻¹ (M_ib + M_ii Ψ) Rb,
    # and the rigid mass Rbᵀ M_bb^CB Rb (M_bb^CB = M_bb + M_bi Ψ + ΨᵀM_ib + ΨᵀM_ii Ψ) exceeds it by exactly
    # the boundary's residual Rbᵀ (M_bb − M_bi M_ii⁻¹ M_ib) Rb: closed form, no model-dependent tolerance.
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.1)
    b = pm.interface_dofs
    i = np.setdiff1d(np.arange(pm.n_dofs), b)
    fb = craig_bampton(pm, modes=i.size)
    check = cb_check(fb, pm)
    M = pm.M.toarray()
    Rb = pm.rigid_body_modes()[b]
    residual = (
        Rb.T @ (M[np.ix_(b, b)] - M[np.ix_(b, i)] @ np.linalg.solve(M[np.ix_(i, i)], M[np.ix_(i, b)])) @ Rb
    )
    total = check.participation.T @ check.participation + residual
    # Round-off: sums of ~100 positive terms (L_k², the residual) and the modes' M-orthonormality (M_ii's
    # scaled condition number is 3), ~n·eps = 2e-14 (3.4e-14 seen); 1e-12 leaves 30x.
    np.testing.assert_allclose(total, check.rigid_mass_full, atol=1e-12 * np.abs(check.rigid_mass_full).max())
    np.testing.assert_allclose(
        check.effective_mass.sum(axis=0) + np.diag(residual), np.diag(check.rigid_mass_full), rtol=1e-12
    )
    np.testing.assert_array_equal(check.effective_mass, check.participation**2)
    np.testing.assert_allclose(
        check.effective_mass_total_percent,
        100 * (1 - np.diag(residual) / np.diag(check.rigid_mass_reduced)),
        rtol=1e-12,
    )
    assert check.effective_mass.shape == (i.size, 1 if dofs == "torsion" else 6)


def _pyyeti_cbcheck(K, M, bset, xyz) -> dict:
    """pyyeti's cbcheck on a reduced model, and what it printed, by name."""
    from pyyeti import cb
    from pyyeti.nastran import n2p

    uset = n2p.addgrid(None, np.arange(1, len(xyz) + 1), "b", 0, xyz, 0)
    out = io.StringIO()
    with warnings.catch_warnings():
        # its printed table of (rhs - krr) / krr divides by krr's exact zeros (nan in the text, unused here)
        warnings.filterwarnings("ignore", "invalid value encountered in divide", RuntimeWarning, "pyyeti")
        chk = cb.cbcheck(out, M, K, bset, bset[:6], uset, uref=1, n_freefree_modes=12)
    text = out.getvalue()
    # Its matrix checks, e.g. "Maximum value of KBQ = 9.3e-07  (should be zero) CHECK!", by name.
    pattern = r"Maximum (?:off-diagonal )?value of (\S+)\s*=\s*(\S+)"
    return {
        "rigid_mass": chk.rbg.T @ chk.m[np.ix_(chk.bset, chk.bset)] @ chk.rbg,
        "mass_symmetric": "Mass matrix is symmetric." in text,
        "stiffness_symmetric": "Stiffness matrix is symmetric." in text,
        "mass_positive_definite": "Mass matrix is positive-definite." in text,
        "values": {k: float(v) for k, v in re.findall(pattern, text)},
        "cb_frq": chk.cb_frq,
        "effmass_percent": chk.effmass_percent.to_numpy(),
    }


@pytest.mark.parametrize("residual", [False, True])
def test_cb_check_agrees_with_pyyeti_cbcheck(residual):
    # Peer check (pyyeti, from the test extra): its cbcheck on our reduced matrices,
    # b-set = the 12 DOFs of the two end nodes, reference = grid 1 (our first boundary node), grids at
    # (x, 0, 0) with our (ux, uy, uz, θx, θy, θz) order, which is Nastran's (T1, T2, T3, R1, R2, R3).
    pytest.importorskip("pyyeti", reason=PYYETI_MISSING)
    pm = part_model(TABLE, fs.STEEL, dofs="full", max_element_length=0.05)
    fb = craig_bampton(pm, modes=10, residual=residual)
    ours = cb_check(fb, pm)
    xyz = np.column_stack([fb.boundary_x, np.zeros((fb.boundary_x.size, 2))])
    peer = _pyyeti_cbcheck(fb.K, fb.M, np.arange(fb.n_boundary), xyz)
    assert peer["mass_symmetric"] and peer["stiffness_symmetric"] and peer["mass_positive_definite"]
    # Rigid-body mass entry by entry in units of √(m_ii m_jj) (kg, kg·m, kg·m² mixed): Rᵀ M_bb R in
    # another order, its mixed-unit terms cancelling up to ~1e3x: ~1e-13 (1.8e-13 measured); 1e-9.
    mg = np.array(peer["rigid_mass"])
    s = 1 / np.sqrt(np.diag(ours.rigid_mass_full))
    assert np.max(np.abs((mg - ours.rigid_mass_full) * np.outer(s, s))) < 1e-9
    # Its fixed-base frequencies are √diag(K_qq)/2π of our matrices (Rayleigh quotients of the modes);
    # ours the eigensolver's: round-off eps·λ_max/λ/2 ~ 1e-12 (measured 3e-12); 1e-9 leaves 300x.
    np.testing.assert_allclose(peer["cb_frq"], fb.fixed_interface_hz, rtol=1e-9)
    # Same definition (L = M_qb Rb, L², % of the rigid mass's diagonal): equal to round-off (measured 0.0).
    np.testing.assert_allclose(peer["effmass_percent"], ours.effective_mass_percent, rtol=1e-9, atol=1e-9)
    # pyyeti's absolute 1e-12 tolerance on K_bq and off-diagonal K_qq flags "CHECK!" in SI units (K ~ 1e9
    # N/m; measured 9e-7 and 7e-6): relative to K's largest entry they are round-off, a few eps (3e-15).
    kmax = np.abs(fb.K).max()
    assert peer["values"]["KBQ"] / kmax < 1e-12 and peer["values"]["KQQ"] / kmax < 1e-12
    # Residual vectors are M-orthonormalised numerically, through the eigen-decomposition of their Gram
    # matrix (condition number 8e4 here): orthonormal to ~eps·8e4 ≈ 2e-11 (3.6e-12 measured); 1e-9.
    # (Not normalised at all they would be off by O(1).)
    assert peer["values"]["diag(MQQ)-1.0"] < 1e-9 and peer["values"]["MQQ"] < 1e-9


# --- convergence against the full model -----------------------------------------------------------------


@pytest.mark.parametrize("dofs", ["torsion", "full"])
def test_free_frequencies_within_a_tenth_of_a_percent_below_half_the_cutoff(dofs):
    # The claim, for the default body (fixed-interface modes + residual vectors): every free-free
    # mode below fc/2 within 0.1 %. Measured over 60 cut-offs from 1.5 to 40 × f1, on this shaft and a
    # uniform one: worst 2.5e-5.
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.02)
    r = 1 if dofs == "torsion" else 6
    w2 = la.eigh(pm.K.toarray(), pm.M.toarray(), eigvals_only=True)[r:]
    full = np.sqrt(w2) / (2 * np.pi)
    for fc in full[0] * np.geomspace(1.5, 40.0, 16):
        free = craig_bampton(pm, cutoff_hz=fc).free_hz[r:]
        below = full[full < fc / 2]
        err = free[: below.size] / below - 1
        # Ritz values bound the exact ones from above, up to the reference's dense round-off,
        # eps·λ_max/λ/2 <= 5e-11 (full: f_max = 1.4e5 Hz against 206 Hz): -3e-10
        assert np.all(err > -3e-10)
        assert np.max(err, initial=0.0) < 1e-4, fc


@pytest.mark.parametrize(
    "dofs, worst_below_half",
    # Textbook Craig–Bampton (no residual vectors) does not reach 0.1 % below fc/2: the error of a free-free
    # mode at f is up to about 0.07 (f/fc)² in torsion and 0.13 (f/fc)² in the full model. Measured over 60
    # cut-offs from 2 to 40 × f1: worst below fc/2 0.88 % (torsion) and 1.25 % (full); below fc/8 1.9e-4
    # and 8.0e-4. The test holds what does: 0.1 % below fc/8, and the measured worst below fc/2.
    [("torsion", 1.0e-2), ("full", 1.5e-2)],
)
def test_textbook_cb_frequencies_below_the_cutoff(dofs, worst_below_half):
    pm = part_model(TABLE, fs.STEEL, dofs=dofs, max_element_length=0.02)
    r = 1 if dofs == "torsion" else 6
    # Reference: the unreduced model's free-free frequencies, dense LAPACK on all of its DOFs.
    w2 = la.eigh(pm.K.toarray(), pm.M.toarray(), eigvals_only=True)[r:]
    full = np.sqrt(w2) / (2 * np.pi)
    prev = None
    for fc in full[0] * np.geomspace(2.0, 40.0, 16):
        fb = craig_bampton(pm, cutoff_hz=fc, residual=False)
        free = fb.free_hz[r:]
        below = full[full < fc / 2]
        err = free[: below.size] / below - 1
        assert np.all(err > -3e-10)  # Ritz values bound the exact ones from above (round-off as above)
        assert np.max(err, initial=0.0) < worst_below_half, fc
        assert np.max(err[below < fc / 8], initial=0.0) < 1e-3, fc  # the 0.1 %, where it holds
        # A higher cut-off keeps more modes, a larger nested subspace: no frequency's error grows (up to
        # the reduced solves' round-off, ~1e-12).
        if prev is not None:
            m = min(prev.size, free.size)
            assert np.all(free[:m] <= prev[:m] * (1 + 1e-10))
        prev = free


def test_residual_vectors_error_falls_at_least_like_the_fourth_power():
    # Residual flexibility turns the truncation error of a mode at f from ~(f/fc)² into ~(f/fc)⁴ or faster:
    # doubling the kept modes (fc ×2) divides the first elastic mode's error by >= 16 rather than ~4-8.
    # Measured on this shaft, modes 4 -> 8 -> 16: plain 2.3, 3.1 doublings; residual 5.6, 7.1.
    pm = part_model(TABLE, fs.STEEL, dofs="torsion", max_element_length=0.005)
    w2 = la.eigh(pm.K.toarray(), pm.M.toarray(), eigvals_only=True)
    f1 = np.sqrt(w2[1]) / (2 * np.pi)
    errs = {
        r: np.array([craig_bampton(pm, modes=n, residual=r).free_hz[1] / f1 - 1 for n in (4, 8, 16)])
        for r in (False, True)
    }
    plain, res = errs[False], errs[True]
    assert np.all(res > 0) and np.all(res < plain / 1000)
    assert np.all(np.log2(plain[:-1] / plain[1:]) > 2.0)
    assert np.all(np.log2(res[:-1] / res[1:]) > 4.0)

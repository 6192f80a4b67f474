"""The 12-DOF Timoshenko beam element and part models against closed forms and published equations."""

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from flexshaft import STEEL, Material, ModelError
from flexshaft.elements import (
    timoshenko_consistent_mass,
    timoshenko_lumped_mass,
    timoshenko_stiffness,
    torsion_consistent_inertia,
    torsion_lumped_inertia,
    torsion_stiffness,
)
from flexshaft.parts.beammesh import torsion_mesh
from flexshaft.parts.model import part_model
from flexshaft.sections import annulus_properties, cowper_shear_factor, table_from_segments

E, G, RHO = STEEL.E, STEEL.G, STEEL.rho
D = 0.1  # m, outer diameter of the uniform test shafts

#: Element count of the frequency checks and their tolerance (the brief: 0.5 % at 50 elements).
N_EL, FREQ_RTOL = 50, 5e-3
#: Statics is exact for this element: only round-off remains. The solve's: axial, torsion and the two
#: bending planes decouple, and elimination is blind to diagonal scaling, so what counts is each scaled
#: block's condition number - at most 1.6e4 (bending, 8 elements at L/D = 20): eps·1.6e4 ≈ 4e-12.
STATIC_RTOL = 1e-10


def _uniform(length, od=D, id=0.0, n_el=N_EL, mass="consistent"):
    table = table_from_segments([{"length": length, "od": od, "id": id}], nu=STEEL.nu)
    return table, part_model(table, STEEL, max_element_length=length / n_el * (1 + 1e-9), mass=mass)


def _plane(model, plane):
    """Node-major (u, θ) DOFs of one bending plane: x–y is (uy, θz), x–z is (uz, θy)."""
    u, th = {"xy": (1, 5), "xz": (2, 4)}[plane]
    return np.ravel([[6 * i + u, 6 * i + th] for i in range(model.n_nodes)])


def _modes_hz(K, M):
    return np.sqrt(np.abs(sla.eigh(K, M, eigvals_only=True))) / (2 * np.pi)


# ---- statics: the element is exact for end loads ------------------------------------------------


@pytest.mark.parametrize("slenderness", [20.0, 2.0])
@pytest.mark.parametrize("n_el", [1, 3, 8])
@pytest.mark.parametrize("id_ratio", [0.0, 0.6])
def test_cantilever_tip_deflection_is_exact(slenderness, n_el, id_ratio):
    # Timoshenko cantilever under a tip load P (e.g. Timoshenko & Gere, Mechanics of
    # Materials, deflections due to shear): δ = P L³/(3 E I) + P L/(κ G A), and the section
    # rotation at the tip P L²/(2 E I) (shear does not rotate the sections). The
    # interdependent element satisfies the static equations exactly (Friedman & Kosmatka
    # 1993), so any mesh gives these to round-off.
    L = slenderness * D
    table, pm = _uniform(L, id=id_ratio * D, n_el=n_el)
    props = annulus_properties(D, id_ratio * D, nu=STEEL.nu)
    free = np.arange(6, pm.n_dofs)  # node 0 clamped
    K = pm.K.toarray()[np.ix_(free, free)]
    tip = pm.node_dofs(-1) - 6
    P, T = 1.0e4, 2.0e3  # N, N·m
    bending = P * L**3 / (3 * E * props.i) + P * L / (G * props.shear_area)
    for k, force, expected in [
        (0, P, P * L / (E * props.area)),  # axial: P L/(E A)
        (1, P, bending),  # uy under Py
        (2, P, bending),  # uz under Pz
        (3, T, T * L / (G * props.j)),  # torsion: T L/(G J)
    ]:
        f = np.zeros(free.size)
        f[tip[k]] = force
        u = np.linalg.solve(K, f)
        assert u[tip[k]] == pytest.approx(expected, rel=STATIC_RTOL)
        if k in (1, 2):
            # Sign convention: θz = +duy/dx, θy = −duz/dx.
            rotation = u[tip[5]] if k == 1 else -u[tip[4]]
            assert rotation == pytest.approx(P * L**2 / (2 * E * props.i), rel=STATIC_RTOL)


def test_no_shear_locking_on_a_slender_beam():
    # A locking element (equal-order interpolation, full integration) is far too stiff
    # at L/D = 100 with 4 elements. Here the tip deflection is the Timoshenko value
    # exactly; it exceeds Euler–Bernoulli's P L³/(3 E I) only by the physical shear
    # term 3 E I/(κ G A L²) (5.5e-5 at L/D = 100, 5.5e-7 at L/D = 1000).
    for slenderness, eb_rtol in ((100.0, 6e-5), (1000.0, 1e-6)):
        L = slenderness * D
        _, pm = _uniform(L, n_el=4)
        props = annulus_properties(D, nu=STEEL.nu)
        free = np.arange(6, pm.n_dofs)
        f = np.zeros(free.size)
        f[pm.node_dofs(-1)[1] - 6] = 1.0
        tip = np.linalg.solve(pm.K.toarray()[np.ix_(free, free)], f)[pm.node_dofs(-1)[1] - 6]
        eb = L**3 / (3 * E * props.i)
        assert tip == pytest.approx(eb + L / (G * props.shear_area), rel=STATIC_RTOL)
        assert tip == pytest.approx(eb, rel=eb_rtol)


# ---- frequencies of uniform beams ------------------------------------------------------------------


def _pinned_spectrum(length, A, I, kappa, n_max=6):
    """All frequencies (Hz) of a simply supported Timoshenko beam up to wavenumber n_max.

    Timoshenko (1921) frequency equation for w = sin(kx), k = nπ/L (Han, Benaroya & Wei,
    J. Sound Vib. 225 (1999) 935-988, eq. for the simply supported Timoshenko beam):
    E I k⁴ − ρA ω² − ρI ω² k² (1 + E/(κG)) + ρ² I ω⁴/(κG) = 0, a quadratic in ω².
    Its lower roots are the flexural modes, the upper ones the second spectrum; n = 0
    adds the pure thickness-shear mode w = 0, ψ = const at ω² = κGA/(ρI).
    """
    k = np.arange(1, n_max + 1) * np.pi / length
    a = RHO**2 * I / (kappa * G)
    b = -(RHO * A + RHO * I * k**2 * (1 + E / (kappa * G)))
    c = E * I * k**4
    disc = np.sqrt(b * b - 4 * a * c)
    lower, upper = (-b - disc) / (2 * a), (-b + disc) / (2 * a)
    shear = kappa * G * A / (RHO * I)
    return np.sqrt(lower) / (2 * np.pi), np.sort(np.sqrt(np.r_[lower, upper, shear])) / (2 * np.pi)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
@pytest.mark.parametrize("slenderness", [20.0, 2.0])
def test_pinned_pinned_frequencies(slenderness, mass):
    L = slenderness * D
    table, pm = _uniform(L, mass=mass)
    A, I = table.area[0], table.iz[0]
    kappa = table.shear_area_y[0] / A
    # The same κ as the table's: Cowper's solid circle (the same formula, κ·A/A: a few roundings).
    assert kappa == pytest.approx(cowper_shear_factor(0.0, STEEL.nu), rel=1e-14)
    lower, spectrum = _pinned_spectrum(L, A, I, kappa)
    K, M = pm.K.toarray(), pm.M.toarray()
    for plane in ("xy", "xz"):
        dofs = _plane(pm, plane)
        keep = np.delete(dofs, [0, dofs.size - 2])  # u = 0 at both ends, θ free (no moment)
        fe = _modes_hz(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)])[:3]
        err = fe / spectrum[:3] - 1
        assert np.all(np.abs(err) < FREQ_RTOL), (plane, err)
    if slenderness == 20.0:
        # Slender: the lowest three are the flexural (lower-root) modes n = 1, 2, 3 (the same numbers
        # sorted, so equal to the bit; 1e-15 only says "equal").
        assert spectrum[:3] == pytest.approx(lower[:3], rel=1e-15)
    else:
        # Stubby: the third is the thickness-shear mode at √(κGA/ρI), below n = 3's lower root.
        assert spectrum[2] < lower[2]


def _free_free_determinant(omega, length, A, I, kappa):
    """Frequency determinant of a free-free Timoshenko beam (Huang 1961; Han et al. 1999).

    w(x) and ψ(x) are sums of the solutions e^{λx} of the Timoshenko equations
    E I ψ'' + κGA (w' − ψ) + ρI ω² ψ = 0,  κGA (w'' − ψ') + ρA ω² w = 0,
    with μ = λ² the two roots of E I κGA μ² + ω² (E I ρA + ρI κGA) μ + ρA ω² (ρI ω² − κGA) = 0.
    Per root the real pair w = C, ψ = (μ + c) S  and  w = μ S, ψ = (μ + c) C  (c = ρA ω²/κGA;
    C = cosh √μ x, S = sinh(√μ x)/√μ, continued to cos / sin for μ < 0) stays regular at
    μ = 0. Free ends: bending moment E I ψ' = 0 and shear force κGA (w' − ψ) = 0.
    """
    kga = kappa * G * A
    c = RHO * A * omega**2 / kga
    qa = E * I * kga
    qb = omega**2 * (E * I * RHO * A + RHO * I * kga)
    qc = RHO * A * omega**2 * (RHO * I * omega**2 - kga)
    disc = np.sqrt(qb * qb - 4 * qa * qc)
    cols = []
    for mu in ((-qb + disc) / (2 * qa), (-qb - disc) / (2 * qa)):
        r = np.sqrt(complex(mu))
        C = np.cosh(r * length).real
        S = (np.sinh(r * length) / r).real if mu != 0 else length
        # Rows: ψ'(0), w'(0) − ψ(0), ψ'(L), w'(L) − ψ(L) (moment and shear at each end, over EI and κGA).
        cols.append([mu + c, 0.0, (mu + c) * C, -c * S])
        cols.append([0.0, -c, (mu + c) * mu * S, -c * C])
    return np.linalg.det(np.array(cols).T)


def _free_free_roots(length, A, I, kappa, count=3):
    # Bracket on a fine grid up to Euler–Bernoulli's 5th free-free frequency
    # (β L ≈ (n + ½)π): the Timoshenko roots lie below their Euler–Bernoulli values.
    w_eb = np.sqrt(E * I / (RHO * A)) / length**2
    grid = np.linspace(0.05, (5.5 * np.pi) ** 2, 20001) * w_eb
    det = np.array([_free_free_determinant(w, length, A, I, kappa) for w in grid])
    brackets = np.flatnonzero(np.sign(det[:-1]) != np.sign(det[1:]))[:count]
    assert brackets.size == count
    roots = [  # bisected to ~eps (xtol in rad/s, rtol 1e-14): the determinant's own noise dominates
        brentq(
            _free_free_determinant, grid[i], grid[i + 1], args=(length, A, I, kappa), xtol=1e-12, rtol=1e-14
        )
        for i in brackets
    ]
    return np.array(roots) / (2 * np.pi)


def test_free_free_determinant_has_the_euler_bernoulli_limit():
    # Check of the reference itself: with a stiff shear (κ → ∞) and slender beam the roots
    # tend to the Euler–Bernoulli free-free values β_n L = 4.7300, 7.8532, 10.9956
    # (Blevins, Formulas for Natural Frequency and Mode Shape, 1979, single-span beams).
    L, A, I = 200 * D, np.pi * D**2 / 4, np.pi * D**4 / 64
    f = _free_free_roots(L, A, I, kappa=1e6)
    beta_l = np.array([4.730040745, 7.853204624, 10.99560784])
    f_eb = beta_l**2 * np.sqrt(E * I / (RHO * A)) / L**2 / (2 * np.pi)
    # Remaining difference: rotary inertia, (β r/L)² ~ 1e-4 at L/D = 200.
    assert f == pytest.approx(f_eb, rel=3e-4)


def _huang_free_free(omega, length, A, I, kappa):
    """Huang's closed-form free-free frequency equation, valid below ω_c = √(κGA/ρI).

    T. C. Huang, J. Appl. Mech. 28 (1961) 579-584 (also Han et al. 1999): with
    b² = ρA L⁴ ω²/(E I), r² = I/(A L²), s² = E I/(κ G A L²) and
    α, β = √(∓(r² + s²) + √((r² − s²)² + 4/b²)) / √2,
    2 − 2 cosh(bα) cos(bβ) + b [b² r² (r² − s²)² + 3 r² − s²] sinh(bα) sin(bβ) / √(1 − b² r² s²) = 0.
    """
    b = np.sqrt(RHO * A * omega**2 / (E * I)) * length**2
    r2, s2 = I / (A * length**2), E * I / (kappa * G * A * length**2)
    root = np.sqrt((r2 - s2) ** 2 + 4 / b**2)
    alpha, beta = np.sqrt((root - (r2 + s2)) / 2), np.sqrt((root + (r2 + s2)) / 2)
    return (
        2
        - 2 * np.cosh(b * alpha) * np.cos(b * beta)
        + b
        * (b**2 * r2 * (r2 - s2) ** 2 + 3 * r2 - s2)
        * np.sinh(b * alpha)
        * np.sin(b * beta)
        / np.sqrt(1 - b**2 * r2 * s2)
    )


@pytest.mark.parametrize("slenderness", [20.0, 2.0])
def test_free_free_frequencies(slenderness):
    L = slenderness * D
    table, pm = _uniform(L)
    A, I = table.area[0], table.iz[0]
    kappa = table.shear_area_y[0] / A
    ref = _free_free_roots(L, A, I, kappa)
    # The determinant's roots solve Huang's closed form too (where it holds, below ω_c).
    w_c = np.sqrt(kappa * G * A / (RHO * I))
    for w in 2 * np.pi * ref[2 * np.pi * ref < 0.98 * w_c]:
        huang_root = brentq(_huang_free_free, 0.99 * w, 1.01 * w, args=(L, A, I, kappa), xtol=1e-12)
        # The determinant cancels cosh terms ~1e4 at the third root: its roots carry ~4e-13 of round-off,
        # Huang's ~2e-16; 1e-10 leaves 200x.
        assert huang_root == pytest.approx(w, rel=1e-10)
    K, M = pm.K.toarray(), pm.M.toarray()
    dofs = _plane(pm, "xy")
    fe = _modes_hz(K[np.ix_(dofs, dofs)], M[np.ix_(dofs, dofs)])
    # Translation uy and rotation θz: eigenvalues at the dense solve's round-off, ~eps·λ_max = 7e-11 λ₁
    # at L/D = 20 (λ_max/λ₁ = 3e5), so f ~ 1e-5 f₁ at most.
    assert np.all(fe[:2] < 1e-3 * fe[2])
    err = fe[2:5] / ref - 1
    assert np.all(np.abs(err) < FREQ_RTOL), err


def _chain(length, n_el, *, shear_scale, rotary_inertia):
    """Dense K, M of the x–y plane of a uniform beam built from the element functions."""
    p = annulus_properties(D, nu=STEEL.nu)
    h = length / n_el
    kw = dict(
        L=h,
        E=E,
        G=G,
        A=p.area,
        Iy=p.i,
        Iz=p.i,
        Asy=p.shear_area * shear_scale,
        Asz=p.shear_area * shear_scale,
    )
    ke = timoshenko_stiffness(J=p.j, **kw)
    me = timoshenko_consistent_mass(rho=RHO, Ip=p.ip, rotary_inertia=rotary_inertia, **kw)
    n = 6 * (n_el + 1)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_el):
        s = slice(6 * e, 6 * e + 12)
        K[s, s] += ke
        M[s, s] += me
    xy = np.ravel([[6 * i + 1, 6 * i + 5] for i in range(n_el + 1)])
    return K[np.ix_(xy, xy)], M[np.ix_(xy, xy)], p


def test_euler_bernoulli_limit():
    # With κGA → ∞ and no rotary inertia the element is the Hermite-cubic Euler–Bernoulli
    # beam; simply supported frequencies (nπ/L)² √(EI/ρA) (Rayleigh, The Theory of Sound, 1877).
    L = 20 * D
    errors = []
    for scale in (1.0, 1e2, 1e4, np.inf):
        K, M, p = _chain(L, N_EL, shear_scale=scale, rotary_inertia=scale == 1.0)
        keep = np.delete(np.arange(K.shape[0]), [0, K.shape[0] - 2])
        fe = _modes_hz(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)])[:3]
        eb = (np.arange(1, 4) * np.pi / L) ** 2 * np.sqrt(E * p.i / (RHO * p.area)) / (2 * np.pi)
        errors.append(np.max(np.abs(fe / eb - 1)))
    assert errors == sorted(errors, reverse=True)
    # Left at κGA = ∞: the cubic element's discretisation error, O((nπ/N)⁴) with N = 50.
    assert errors[-1] < 1e-6


# ---- invariants of a free part -------------------------------------------------------------------

segment = st.fixed_dictionaries(
    {
        "length": st.floats(0.02, 1.0),
        "od": st.floats(0.02, 0.4),
        "id_ratio": st.floats(0.0, 0.9),
    }
)


@settings(max_examples=40, deadline=None)
@given(
    segs=st.lists(segment, min_size=1, max_size=4),
    pieces=st.integers(1, 12),
    mass=st.sampled_from(["consistent", "lumped"]),
)
def test_free_part_has_exactly_six_rigid_body_modes(segs, pieces, mass):
    table = table_from_segments(
        [{"length": s["length"], "od": s["od"], "id": s["id_ratio"] * s["od"]} for s in segs], nu=STEEL.nu
    )
    pm = part_model(table, STEEL, max_element_length=table.length / pieces, mass=mass)
    K, M = pm.K.toarray(), pm.M.toarray()
    assert np.array_equal(K, K.T) and np.array_equal(M, M.T)
    np.linalg.cholesky(M)  # M positive definite
    lam, vec = sla.eigh(K, M)
    R = pm.rigid_body_modes()
    # The exact rigid motions are K's null space: K·R vanishes to the round-off of K's entries and of
    # the product - at most 12 terms a row, so <= ~13·12·(eps/2) ≈ 2e-14 of max|K|·max|R| (~1e-16 seen).
    assert np.max(np.abs(K @ R)) < 1e-13 * np.max(np.abs(K)) * np.max(np.abs(R))
    # Exactly six modes at ~0, positive semi-definite, and the 7th clearly elastic. The zero eigenvalues
    # are the dense solve's round-off, ~eps·λ_max: λ_max/λ₇ reaches 4e8 over these strategies (a 2 cm
    # element of a 0.4 m disc on thin 1 m pieces), so |λ| < 1e-7 λ₇ at worst.
    assert np.all(np.abs(lam[:6]) < 1e-6 * lam[6])
    assert np.all(lam[6:] > 0)
    # The null space found is the rigid-body space: projecting it onto span(R) leaves nothing but the
    # eigenvectors' round-off, ~eps·λ_max/λ₇ <= 1e-7 too.
    Q, _ = np.linalg.qr(R)
    v0 = vec[:, :6] / np.linalg.norm(vec[:, :6], axis=0)
    assert np.linalg.norm(v0 - Q @ (Q.T @ v0)) < 1e-6


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_rigid_body_modes_sit_at_zero_frequency(mass):
    # The stepped shaft of the design notes: the rigid motions' Rayleigh frequencies are round-off of
    # Rᵀ·K·R, not a modelling error. Its size: K's entries and the products are rounded, so |rq| is a few
    # eps·λ_max at most, and λ_max/λ₇ = 1.7e4 here: √(eps·1.7e4) = 2e-6 of the first elastic frequency
    # (4e-7 seen). 1e-5 stays above that; a shape function missing a rigid motion would leave ~h/L.
    table = table_from_segments([(0.30, 0.16), (0.40, 0.12, 0.04)], nu=STEEL.nu)
    pm = part_model(table, STEEL, max_element_length=0.02, mass=mass)
    K, M, R = pm.K.toarray(), pm.M.toarray(), pm.rigid_body_modes()
    first_elastic = sla.eigh(K, M, eigvals_only=True, subset_by_index=[6, 6])[0]
    rq = np.diag(R.T @ K @ R) / np.diag(R.T @ M @ R)
    assert np.all(np.sqrt(np.abs(rq) / first_elastic) < 1e-5)


@pytest.mark.parametrize("segments", [[(0.3, 0.16), (0.4, 0.12, 0.04)], [(0.05, 0.3, 0.2)]])
def test_consistent_mass_carries_the_rigid_body_inertia(segments):
    # Rigid motions lie in the shape functions' span, so Rᵀ M R is the rigid body's mass
    # matrix about the first node (any dynamics text: m, ∫x dm, ∫x² dm + Σ ρ I L).
    table = table_from_segments(segments, nu=STEEL.nu)
    pm = part_model(table, STEEL, max_element_length=0.07)
    x0, x1, rho = table.x[:-1], table.x[1:], RHO
    m = rho * np.sum(table.area * (x1 - x0))
    s1 = rho * np.sum(table.area * (x1**2 - x0**2) / 2)
    s2 = rho * np.sum(table.area * (x1**3 - x0**3) / 3)
    iy, iz, ip = (rho * np.sum(c * (x1 - x0)) for c in (table.iy, table.iz, table.ip))
    expected = np.diag([m, m, m, ip, s2 + iy, s2 + iz])
    expected[2, 4] = expected[4, 2] = -s1  # uz = −θy x
    expected[1, 5] = expected[5, 1] = s1  # uy = +θz x
    R = pm.rigid_body_modes()
    got = R.T @ pm.M @ R
    # Sums over ~15 elements, the consistent mass's coupling terms cancelling ~10x: ~1e-14; 1e-12.
    assert got == pytest.approx(expected, rel=1e-12, abs=1e-12 * m)
    # Lumped: translations and the spin are exact too.
    lumped = part_model(table, STEEL, max_element_length=0.07, mass="lumped")
    got = R.T @ lumped.M @ R
    assert np.diag(got)[:4] == pytest.approx([m, m, m, ip], rel=1e-12)


# ---- torsion-only models ----------------------------------------------------------------------------


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_torsion_dofs_are_the_torsion_chain(mass):
    table = table_from_segments([(0.3, 0.16), (0.4, 0.12, 0.04), (0.2, 0.2)], nu=STEEL.nu)
    pm = part_model(table, STEEL, dofs="torsion", max_element_length=0.06, mass=mass)
    mesh = torsion_mesh(table, STEEL, max_element_length=0.06)
    n = mesh.x.size
    K, M = np.zeros((n, n)), np.zeros((n, n))
    inertia = torsion_consistent_inertia if mass == "consistent" else torsion_lumped_inertia
    for e, (k, j) in enumerate(zip(mesh.stiffness, mesh.inertia)):
        K[e : e + 2, e : e + 2] += torsion_stiffness(k)
        M[e : e + 2, e : e + 2] += inertia(j)
    assert np.array_equal(pm.x, mesh.x)
    # The same element formulas, at most two contributions an entry: an ulp apart (ρ·Ip·L/3 against
    # j/3 in the full model), 1e-15 ≈ 4 ulp.
    assert np.allclose(pm.K.toarray(), K, rtol=1e-15, atol=0)
    assert np.allclose(pm.M.toarray(), M, rtol=1e-15, atol=0)
    assert pm.dofs_per_node == 1 and pm.interface_nodes == (0, n - 1)
    # The full model's θx DOFs are decoupled and carry the same chain.
    full = part_model(table, STEEL, max_element_length=0.06, mass=mass)
    tx = np.arange(n) * 6 + 3
    assert np.allclose(full.K.toarray()[np.ix_(tx, tx)], K, rtol=1e-15, atol=0)
    assert np.allclose(full.M.toarray()[np.ix_(tx, tx)], M, rtol=1e-15, atol=0)


# ---- element and API details --------------------------------------------------------------------


def test_element_functions_are_vectorised():
    p = annulus_properties(D, nu=STEEL.nu)
    L = np.array([0.1, 0.2, 0.3])
    kw = dict(E=E, G=G, A=p.area, Iy=p.i, Iz=p.i, Asy=p.shear_area, Asz=p.shear_area)
    K = timoshenko_stiffness(L=L, J=p.j, **kw)
    M = timoshenko_consistent_mass(L=L, rho=RHO, Ip=p.ip, **kw)
    Ml = timoshenko_lumped_mass(L=L, rho=RHO, A=p.area, Iy=p.i, Iz=p.i, Ip=p.ip)
    assert K.shape == M.shape == Ml.shape == (3, 12, 12)
    assert np.array_equal(K[1], timoshenko_stiffness(L=0.2, J=p.j, **kw))
    assert np.array_equal(M[2], timoshenko_consistent_mass(L=0.3, rho=RHO, Ip=p.ip, **kw))
    assert np.array_equal(Ml, np.einsum("nii->ni", Ml)[:, :, None] * np.eye(12))


def test_node_dofs_and_interfaces():
    _, pm = _uniform(1.0, n_el=4)
    assert pm.n_nodes == 5 and pm.n_dofs == 30 and pm.dofs == "full"
    assert list(pm.node_dofs(1)) == [6, 7, 8, 9, 10, 11]
    assert list(pm.node_dofs(-1)) == list(range(24, 30))
    assert list(pm.interface_dofs) == list(range(6)) + list(range(24, 30))
    with pytest.raises(ModelError, match="node = 5"):
        pm.node_dofs(5)


@pytest.mark.parametrize(
    ("kwargs", "text"),
    [
        ({"dofs": "bending"}, "dofs = 'bending'"),
        ({"mass": "diagonal"}, "mass = 'diagonal'"),
        ({"max_element_length": 0.0}, "max_element_length = 0.0 m"),
        ({"max_element_length": float("nan")}, "max_element_length = nan m"),
    ],
)
def test_bad_options_are_refused(kwargs, text):
    table = table_from_segments([(0.3, 0.16)])
    with pytest.raises(ModelError, match=text):
        part_model(table, STEEL, **kwargs)
    with pytest.raises(ModelError, match="table"):
        part_model("shaft", STEEL)
    with pytest.raises(ModelError, match="material"):
        part_model(table, Material)


def test_non_positive_bending_moment_is_refused():
    from dataclasses import replace

    table = table_from_segments([(0.3, 0.16)])
    bad = replace(table, iy=np.array([0.0]))
    with pytest.raises(ModelError, match="iy = 0.0 m⁴"):
        part_model(bad, STEEL)
    assert part_model(bad, STEEL, dofs="torsion").n_dofs == 2  # torsion does not need it

"""Damping in 6-DOF models: the same kinds of damping as a torsion chain, on every mode family.

References: Rayleigh damping C = αM + βK is diagonal in the undamped modes, so every mode's ratio is
ξ = α/(2ω) + βω/2 exactly; modal damping set on a part's own free-free modes is that part's modes'
ratio when the part is the whole model; and torsion does not couple to bending or axial motion in a
straight round shaft, so the torsion modes of a 6-DOF model carry the damping of its torsion chain.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.sections import table_from_segments
from tests.conftest import full_shaft_model


def shaft(name, segs, n=30, **kw):
    t = table_from_segments(segs, name=name)
    return fs.Shaft.from_sections(name, t, fs.STEEL, max_element_length=t.length / n, **kw)


def chain(**kw):
    """Two stepped shafts and a coupling between a motor and a generator, on three bearings."""
    shafts = kw.pop("shafts", {})
    return fs.Drivetrain(
        "damped",
        [
            fs.Rigid("motor", 5.0),
            shaft("a", [{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.08, "id": 0.03}], **shafts),
            fs.Coupling("c", stiffness=2e4, inertia=0.02, damping=kw.pop("coupling_damping", 0.0)),
            shaft("b", [{"length": 0.8, "od": 0.09}], **shafts),
            fs.Rigid("gen", 2.0),
        ],
        dofs="full",
        bearings=(("motor", 2e8), ("a/c", 2e8), ("gen", 2e8)),
        **kw,
    )


@pytest.mark.parametrize("reduce", [None, fs.Reduce(modes=4, damping=0.0)])
def test_rayleigh_damping_gives_its_ratio_on_every_mode_family(reduce):
    alpha, beta = 0.5, 2e-6
    d = chain(rayleigh=fs.Rayleigh(alpha, beta), shafts={"reduce": reduce})
    r = fs.modal_analysis(d, 24)
    assert {"axial", "lateral", "torsion"} <= set(np.array(r.kinds)[~r.rigid])
    el = ~r.rigid
    expected = fs.rayleigh_ratio(alpha, beta, r.frequencies_hz[el])
    # C is diagonal in the undamped modes, so each damped pair is exact up to round-off. The damped
    # solve's ω comes from its own dense eigen-solve of (K, M), the modes' (and so `expected`, ≈ α/2ω on
    # mode 1) from another LAPACK driver: each good to eps·λ_max/λ/2, 4e-9 on the 18 Hz mode beside
    # f_max = 1.1e5 Hz (3e-10 reduced; 2.4e-9 seen, PRESCOTT kernels, two threads). The first-order
    # solve adds eps·ω_max/ω to |λ| and eps·(ω_max/ω)/ξ = 6e-10 to ξ₁ = 0.0023. 2e-8 leaves 4x on the
    # sum; a damping that were not proportional would move |λ| by ~ξ² = 5e-6.
    np.testing.assert_allclose(r.damped.damping_ratios[el], expected, rtol=2e-8)
    np.testing.assert_allclose(r.damped.natural_frequencies_hz[el], r.frequencies_hz[el], rtol=2e-8)


@pytest.mark.parametrize("reduce", [False, True])
def test_modal_damping_of_a_free_part_is_every_modes_ratio(reduce):
    # One free shaft is the whole model: its own free-free modes are the model's modes, so modal
    # damping C = M Φ diag(2ξω) Φᵀ M (or the flexible body's, on its free-free basis) puts exactly ξ
    # on each: bending pairs, axial and torsion alike. Six rigid modes stay undamped.
    s = shaft(
        "s",
        [{"length": 1.2, "od": 0.1}],
        24,
        damping_ratio=0.0 if reduce else 0.0053,
        reduce=fs.Reduce(modes=8, damping=0.0053) if reduce else None,
    )
    r = fs.modal_analysis(fs.Drivetrain("free", [s], dofs="full"), 20)
    assert r.rigid.sum() == 6
    assert {"axial", "lateral", "torsion"} <= set(np.array(r.kinds)[~r.rigid])
    # Dense first-order solve of a ~150-coordinate model: λ to ~n·eps·ω_max, ξ far inside 1e-6.
    np.testing.assert_allclose(r.damped.damping_ratios[~r.rigid], 0.0053, rtol=1e-6)


def test_torsion_modes_carry_the_torsion_chains_damping():
    d = chain(shafts={"damping_ratio": 0.0053}, coupling_damping=20.0)
    full = fs.modal_analysis(d, 30)
    tors = fs.modal_analysis(fs.assemble(d, dofs="torsion"), 4)
    is_t = (np.array(full.kinds) == "torsion") & ~full.rigid
    # Torsion decouples, so equal in exact arithmetic; the dense solves' round-off on the 18 Hz mode is
    # eps·λ_max/λ/2 = 4e-9 in the 6-DOF model (f_max = 1.1e5 Hz) and 1.5e-9 in the chain (1.8e-9 seen):
    # 2e-8 leaves 4x on their sum.
    np.testing.assert_allclose(full.frequencies_hz[is_t][:3], tors.frequencies_hz[1:4], rtol=2e-8)
    # The same torsion block of C (a part's torsion free-free modes are those of its torsion model), but
    # the full model's damped modes come from its 30 undamped modes (> 400 coordinates: projected),
    # the torsion chain's from the full first-order problem. The projection drops the damping coupling
    # to modes outside the 30, second order in it: measured 1e-7 relative; 1e-5 bounds ξ² for ξ < 3e-3.
    np.testing.assert_allclose(
        full.damped.damping_ratios[is_t][:3], tors.damped.damping_ratios[1:4], rtol=1e-5
    )


def test_cli_reports_damped_modes_of_a_full_model(tmp_path, capsys):
    model = tmp_path / "m.toml"
    model.write_text(full_shaft_model("rayleigh = {alpha = 0.0, beta = 1e-5}\n"))
    assert main(["modes", str(model), "--json", "--modes", "8"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["damped_solver"] is not None
    for m in doc["modes"]:
        if not m["rigid"]:
            w = 2 * np.pi * m["frequency_hz"]
            # JSON keeps every digit; ξ's round-off eps·(ω_max/ω)/ξ ~ 1e-10 (ξ = βω/2 ~ 3e-3)
            assert m["damping_ratio"] == pytest.approx(1e-5 * w / 2, rel=1e-8)
    assert main(["modes", str(model)]) == 0
    out = capsys.readouterr().out
    assert "damped" in out.splitlines()[0] and "undamped" not in out.splitlines()[0]


def test_bearing_energy_and_component_energy_add_up():
    # Strain energy: components and bearings share all of it; kinetic energy: the components.
    r = fs.modal_analysis(chain(), 16)
    el = ~r.rigid
    se = r.strain_energy_fractions()[el].sum(axis=1) + r.bearing_energy_fractions()[el].sum(axis=1)
    # Shares of one total, summed back: ~n_owners·eps (1e-10 is loose).
    np.testing.assert_allclose(se, 1.0, rtol=1e-10)
    np.testing.assert_allclose(r.kinetic_energy_fractions().sum(axis=1), 1.0, rtol=1e-10)
    # The total they share is each mode's strain energy φᵀKφ = ω² (mass-normalised), the eigenvalue:
    # no stiffness entry left out of the split. Element by element the quadratic forms cancel like the
    # Rayleigh quotient does, eps·λ_max/λ ≈ 8e-9 on the lowest mode (f_max/f₁ = 6000); 1e-7.
    mdl = r.model
    strain = mdl.stiffness_entries.quadratic_by_owner(r.shapes, mdl.n_owners).sum(axis=0)
    np.testing.assert_allclose(strain[el], r.omega[el] ** 2, rtol=1e-7)
    # Lateral modes bend on the bearings: some strain energy sits in them.
    lateral = (np.array(r.kinds) == "lateral") & el
    assert np.all(r.bearing_energy_fractions()[lateral].sum(axis=1) > 0)


def test_dataclasses_replace_keeps_the_model_consistent():
    # The model file's dofs and a Python replace give the same model.
    d = chain()
    t = dataclasses.replace(d, dofs="torsion", bearings=())
    a = fs.modal_analysis(t, 5)
    b = fs.modal_analysis(fs.assemble(d, dofs="torsion"), 5)
    # The same matrices, the same solve; were they assembled in another order, the solves' round-off
    # (eps·λ_max/λ/2 = 1.5e-9 on the 18 Hz mode) would still be inside 1e-8.
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-8)


def test_modal_damping_of_a_huge_part_is_refused_where_it_is_meshed():
    # A dense eigensolve of a part's own DOFs: refused past 2000 torsion elements or 3000 DOFs of a
    # 6-DOF part, with the way out named. Validating the shaft does not mesh it; assembling does.
    big = fs.Shaft("s", stiffness=1e6, inertia=1.0, elements=2001, damping_ratio=0.0053)
    d = fs.Drivetrain("big", [fs.Rigid("m", 1.0), big])
    with pytest.raises(fs.ModelError, match="at most 2000 with damping_ratio > 0") as err:
        fs.assemble(d)
    assert err.value.field == "elements"
    fine = shaft("f", [{"length": 1.0, "od": 0.1}], 600, damping_ratio=0.0053)
    with pytest.raises(fs.ModelError, match="at most 499 elements in a 6-DOF shaft") as err:
        fs.assemble(fs.Drivetrain("fine", [fine], dofs="full"))
    assert err.value.field == "max_element_length"
    # The same shafts without modal damping assemble.
    assert fs.assemble(fs.Drivetrain("fine", [dataclasses.replace(fine, damping_ratio=0.0)], dofs="full"))


def test_low_damped_modes_keep_full_precision_beside_megahertz_modes():
    # A 6-DOF line of fine elements has axial modes in the MHz beside a torsion mode of a few Hz: a dense
    # re-solve of the projected matrices would lose ε·ω_max² in every λ (1e-6 of the low mode). With
    # Rayleigh damping every mode keeps |λ| = ω exactly (λ = −ξω ± iω√(1−ξ²)), so the damped natural
    # frequencies must equal the undamped (Rayleigh-refined) ones to round-off of the balanced
    # first-order solve, ε·ω_max/ω: ~1e-11 here (f_max ~1e5 Hz, f₁ a few Hz), so 1e-9 leaves 100x.
    from flexshaft.model.components import Coupling, Drivetrain, Rigid, Shaft
    from flexshaft.sections import table_from_segments

    def shaft(name, length, od):
        t = table_from_segments([{"length": length, "od": od}], name=name)
        return Shaft.from_sections(name, t, fs.STEEL, max_element_length=0.02)

    d = Drivetrain(
        "fine",
        (
            Rigid("motor", 20.0),
            shaft("s1", 1.0, 0.1),
            Coupling("c", stiffness=2e4),
            shaft("s2", 0.6, 0.09),
            Rigid("gen", 5.0),
        ),
        dofs="full",
        bearings=(("motor", 1e8), ("s1/c", 1e8), ("gen", 1e8)),
        rayleigh=fs.Rayleigh(alpha=0.05, beta=2e-7),
    )
    m = fs.assemble(d)
    assert m.n_dof > 400  # the path for large models
    r = fs.modal_analysis(m, m.n_dof)
    el = ~r.rigid
    assert r.frequencies_hz.max() > 1e5  # the spread the test is about
    np.testing.assert_allclose(r.damped.natural_frequencies_hz[el], r.frequencies_hz[el], rtol=1e-9)
    # and the state space's poles (balanced the same way) agree with them, to the same eps·ω_max/|λ|
    from flexshaft.analysis.statespace import state_space

    p = state_space(r, ["motor"], ["speed:motor"]).poles()
    low = r.damped.eigenvalues[el][:10]
    for lam in low:
        assert np.min(np.abs(p - lam)) <= 1e-9 * abs(lam)

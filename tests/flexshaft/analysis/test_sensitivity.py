"""Analytic sensitivities against central finite differences of the eigen-solution, every parameter kind."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.parameters import (
    AFFINE_FIELDS,
    find_parameter,
    parameter_value,
    parameters,
    with_parameters,
)
from flexshaft.analysis.parametrised import ParametrisedModel
from flexshaft.analysis.sensitivity import frequency_derivatives, sensitivities
from flexshaft.cli import main
from flexshaft.model.components import Coupling, Drivetrain, Gear, Rigid, Shaft
from flexshaft.sections import table_from_segments
from tests.conftest import EXAMPLES

# Central differences of the frequencies with a relative step h = 1e-4: truncation h²·f'''/6 ~ 1e-8 of
# f/p for these smooth eigenvalues, round-off 1e-16/h = 1e-12; the 1e-6 leaves that margin.
H, RTOL = 1e-4, 1e-6


def _segments_shaft(name, segs, **kw):
    return Shaft.from_sections(name, table_from_segments(segs, name=name), fs.STEEL, **kw)


def _models():
    geared = Drivetrain(
        "geared",
        (
            Rigid("motor", 10.0),
            Shaft("a", stiffness=1e5, inertia=0.1, elements=3, damping_ratio=0.01),
            Gear("g", ratio=2.5, inertia_in=0.2, inertia_out=0.05, mesh_stiffness=3e5, mesh_damping=2.0),
            Coupling("c", stiffness=4e3, inertia=0.01, damping=1.5),
            Rigid("gen", 0.2),
        ),
    )
    sections = Drivetrain(
        "sections",
        (
            Rigid("motor", 5.0),
            _segments_shaft(
                "s1",
                [{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.08, "id": 0.03}],
                max_element_length=0.1,
                damping_ratio=0.0053,
            ),
            Coupling("c", stiffness=2e4, inertia=0.02),
            _segments_shaft("s2", [{"length": 0.8, "od": 0.09}], max_element_length=0.1),
            Rigid("gen", 2.0),
        ),
    )
    full = Drivetrain(
        "full",
        (
            Rigid("motor", 5.0),
            _segments_shaft("s1", [{"length": 1.2, "od": 0.1}], max_element_length=0.1),
            Coupling("c", stiffness=2e4, inertia=0.02),
            _segments_shaft("s2", [{"length": 0.8, "od": 0.09}], max_element_length=0.1),
            Rigid("gen", 2.0),
        ),
        dofs="full",
        bearings=(("motor", 1e8), ("s1/c", 1e8), ("gen", 1e8)),
        rayleigh=fs.Rayleigh(beta=1e-5),
    )
    return {
        "customer1": fs.load_model(EXAMPLES / "customer1.toml"),
        "nrel5mw": fs.load_model(EXAMPLES / "nrel5mw.toml"),
        "geared": geared,
        "sections": sections,
        "full": full,
    }


MODELS = _models()


def _fd(d, name, value, modes, what):
    # the central difference of the frequencies (or first-order damping ratios) by re-solving the model
    def at(v):
        m = fs.assemble(with_parameters(d, {name: v}), reduce=False)
        r = fs.modal_analysis(m, m.n_dof if m.n_dof <= 2000 else 20, damped=False)
        if what == "f":
            return r.frequencies_hz[modes]
        C = m.C if m.C is not None else 0 * m.K
        P = r.shapes[:, modes]
        return np.einsum("ij,ij->j", P, C @ P) / (2 * r.omega[modes])

    h = H * abs(value) if value else H
    if value == 0:  # a parameter at its bound 0 (no damper yet): forward difference, h² → h accuracy
        return (at(h) - at(0.0)) / h
    return (at(value + h) - at(value - h)) / (2 * h)


@pytest.mark.parametrize("model", list(MODELS))
def test_frequency_sensitivities_equal_central_differences(model):
    d = MODELS[model]
    s = sensitivities(d)
    modes = s.modes[:6]  # the lowest elastic modes (6-DOF: bending pairs, torsion, axial)
    assert {p.name for p in s.parameters} == {p.name for p in parameters(d)}
    for k, p in enumerate(s.parameters):
        v = s.values[k]
        fd = _fd(d, p.name, v, modes, "f")
        scale = s.frequencies_hz[: modes.size] / (abs(v) if v else 1.0)
        tol = RTOL if v else 1e-4  # forward difference at a bound: O(h) = 1e-4 of the scale
        np.testing.assert_allclose(
            s.dfrequency[: modes.size, k], fd, rtol=0, atol=tol * scale.max(), err_msg=p.name
        )


@pytest.mark.parametrize("model", ["customer1", "geared", "sections"])
def test_damping_sensitivities_equal_central_differences(model):
    # ξ = φᵀCφ/(2ω), first order; its derivative through ∂C, ∂ω and ∂φ (modal expansion over all modes).
    d = MODELS[model]
    s = sensitivities(d)
    assert s.ddamping is not None
    modes = s.modes[:4]
    for k, p in enumerate(s.parameters):
        v = s.values[k]
        fd = _fd(d, p.name, v, modes, "z")
        scale = np.maximum(s.damping_ratios[: modes.size], 1e-6) / (abs(v) if v else 1.0)
        tol = RTOL if v else 1e-4
        np.testing.assert_allclose(
            s.ddamping[: modes.size, k], fd, rtol=0, atol=tol * scale.max(), err_msg=p.name
        )


def test_normalised_sensitivities_of_a_two_inertia_line_are_the_closed_form():
    # f = √(k(1/J1 + 1/J2))/2π: ∂ln f/∂ln k = 1/2, ∂ln f/∂ln J1 = −½·J2/(J1 + J2),
    # ∂ln f/∂ln J2 = −½·J1/(J1 + J2).
    j1, j2 = 3.0, 1.0
    d = Drivetrain("two", (Rigid("a", j1), Shaft("s", stiffness=2e4, inertia=0.0), Rigid("b", j2)))
    s = sensitivities(d, ["s.stiffness", "a.inertia", "b.inertia"])
    np.testing.assert_allclose(
        s.normalised[0], [0.5, -0.5 * j2 / (j1 + j2), -0.5 * j1 / (j1 + j2)], rtol=1e-9
    )


def test_parameters_round_trip_and_back_to_physics():
    d = MODELS["sections"]
    s1 = d.component("s1")
    # a part's stiffness set through its own Young's modulus: k ∝ E at fixed ν, the material renamed
    tuned = with_parameters(d, {"s1.stiffness": 1.1 * s1.stiffness})
    t1 = tuned.component("s1")
    assert t1.stiffness == pytest.approx(1.1 * s1.stiffness, rel=1e-12)
    assert t1.material.E == pytest.approx(1.1 * fs.STEEL.E, rel=1e-12) and t1.material.name == "s1 (tuned)"
    assert tuned.component("s2").material == fs.STEEL  # the other part keeps steel
    # a scale s of every cross-section dimension: k and j ∝ s⁴
    scaled = with_parameters(d, {"s1.scale": 1.05})
    assert scaled.component("s1").stiffness == pytest.approx(1.05**4 * s1.stiffness, rel=1e-12)
    assert parameter_value(scaled, "s1.scale") == pytest.approx(1.05, rel=1e-15)
    # a material shared by both parts
    soft = with_parameters(d, {"steel.E": 0.5 * fs.STEEL.E})
    assert soft.component("s2").stiffness == pytest.approx(0.5 * d.component("s2").stiffness, rel=1e-12)
    for bad, field in [
        ("s1.colour", "parameter"),
        ("nothing", "parameter"),
        ("motor.stiffness", "parameter"),
    ]:
        with pytest.raises(fs.ModelError) as info:
            with_parameters(d, {bad: 1.0})
        assert info.value.field == field
    with pytest.raises(fs.ModelError, match="motor"):
        with_parameters(d, {"motor.inertia": -1.0})


def test_cli_json_and_heat_map(tmp_path, capsys):
    model = str(EXAMPLES / "customer1.toml")
    assert main(["sensitivity", model, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    names = [p["name"] for p in doc["parameters"]]
    assert "part 3.stiffness" in names and doc["units"]["normalised"].startswith("%")
    mode1 = doc["modes"][0]
    assert mode1["mode"] == 1
    # the coupling sets mode 1: its stiffness has the largest normalised sensitivity of all stiffnesses
    stiff = {n: v for n, v in mode1["normalised"].items() if n.endswith(".stiffness")}
    assert max(stiff, key=stiff.get) == "part 3.stiffness"
    png = tmp_path / "s.png"
    assert main(["sensitivity", model, "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert "part 3.stiffness" in out
    assert main(["sensitivity", model, "--param", "part 9.stiffness"]) == 2
    assert "no such parameter" in capsys.readouterr().err


def test_mode_numbers_are_the_models_elastic_modes_or_refused_before_a_solve():
    from flexshaft.analysis.sensitivity import lowest_elastic

    d = fs.load_model(EXAMPLES / "customer1.toml")  # 5 DOFs: mode 0 rigid-body, modes 1 … 4 elastic
    m = fs.assemble(d, reduce=False)
    assert lowest_elastic(m, 4, "--modes").tolist() == [1, 2, 3, 4]
    with pytest.raises(fs.ModelError) as info:
        lowest_elastic(m, 5, "--modes")
    assert info.value.field == "--modes" and info.value.value == 5 and info.value.valid == "at most 4"
    assert "5 modes, 4 of them elastic" in str(info.value)
    s = sensitivities(d, ["part 3.stiffness"], modes=[4, 1])
    assert s.modes.tolist() == [4, 1]
    for bad in ([99], [0], [-1], [2.5], [np.nan], [], [True]):
        with pytest.raises(fs.ModelError) as info:
            sensitivities(d, ["part 3.stiffness"], modes=bad)
        assert info.value.field == "mode", bad
    with pytest.raises(fs.ModelError, match="listed twice"):
        sensitivities(d, ["part 3.stiffness", "part 3.stiffness"])


def test_cli_sensitivity_modes_are_refused_beyond_the_model_as_modes_count_is(capsys):
    model = str(EXAMPLES / "customer1.toml")
    assert main(["sensitivity", model, "--param", "part 3.stiffness"]) == 0  # default: up to 6 -> 4
    assert "mode 4" in capsys.readouterr().out
    lines = {}
    for argv, option in [
        (["sensitivity", model, "--modes", "99"], "--modes"),
        (["sweep", model, "--param", "part 3.stiffness=4e4:7e4:2", "--modes", "99"], "--modes"),
        (["modes", model, "--modes", "99"], "modes --modes"),
    ]:
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and f"{option[-7:]} = 99: the model has only 5 DOFs, so 5 modes" in err, err
        lines[option] = err
    assert lines["--modes"].endswith("valid: at most 4")
    assert lines["modes --modes"].endswith("valid: at most 5")


@pytest.mark.parametrize(
    "name,text",
    [
        ("motor.inertia", "> 0 kg·m²"),
        ("part 3.inertia", ">= 0 kg·m²"),
        ("part 1.stiffness", "> 0 N·m/rad"),
        ("part 1.damping_ratio", ">= 0 and < 1"),
        ("part 1.damping", ">= 0 N·m·s/rad"),
    ],
)
def test_parameter_domains_are_what_the_components_accept(name, text):
    # The domain's edges are exactly where the component starts refusing a value.
    from flexshaft.analysis.parameters import parameter_domain

    d = fs.load_model(EXAMPLES / "customer1.toml")
    dom = parameter_domain(d, name)
    assert dom.text == text
    for x in (dom.lo, np.nextafter(dom.lo, -np.inf), np.nextafter(dom.lo, np.inf), dom.hi, 1e300, np.inf):
        if x is None:
            continue
        try:
            with_parameters(d, {name: x})
            accepted = True
        except fs.ModelError:
            accepted = False
        assert accepted == dom.contains(x), (name, x)


# The parametrised model against fresh assemblies. Entries are compared with the scale every term
# summed into entry ij has, √(K_ii·K_jj) (K and M are sums of positive semi-definite blocks): two
# sums of a few terms each rounded to eps = 2.2e-16 agree to ~1e-15 of it with any BLAS kernel, so
# 1e-12 is a wide margin; a field that is not affine misses by 5e-4 (nu) to 4e-2 (scale) at the 10 %
# moves here.
SAME = 1e-12
# Derivatives by central differences of the assembly at a relative step of 1e-6 (the module's STEP)
# carry round-off ~eps/1e-6 = 1e-10 of the entries' scale; 1e-8 leaves a hundredfold margin and is far
# below the (Δx/x) = 0.1 a derivative moves by when its field is not affine.
DERIV = 1e-8


def _rigid_gear():
    return Drivetrain(
        "rigid gear",
        (
            Rigid("motor", 10.0),
            Shaft("a", stiffness=1e5, inertia=0.1, elements=3),
            Gear("g", ratio=2.5, inertia_in=0.2, inertia_out=0.05),
            Coupling("c", stiffness=4e3, inertia=0.01),
            Rigid("gen", 0.2),
        ),
    )


KINDS = {**{k: v for k, v in MODELS.items() if k != "nrel5mw"}, "rigid gear": _rigid_gear()}


def _assembled(d, names, x):
    return fs.assemble(with_parameters(d, dict(zip(names, x))), reduce=False, damping=False)


def _worst(A, B, scale_of):
    """max |A − B|_ij / √(s_i·s_j), s = |diagonal of scale_of|."""
    D = (abs(A - B)).tocoo()
    s = np.abs(scale_of.diagonal())
    return float(np.max(D.data / np.sqrt(s[D.row] * s[D.col]), initial=0.0))


def _central(d, names, x, k, rel=1e-6):
    # a central difference; from a value 0 (no damper) a forward one, as the negative side is refused
    h = rel * abs(x[k]) if x[k] else rel
    lo, hi = np.array(x, float), np.array(x, float)
    lo[k] -= h if x[k] else 0.0
    hi[k] += h
    a, b = _assembled(d, names, lo), _assembled(d, names, hi)
    return (b.K - a.K) / (hi[k] - lo[k]), (b.M - a.M) / (hi[k] - lo[k])


@pytest.mark.parametrize("model", list(KINDS))
def test_the_parametrised_model_is_a_fresh_assembly_for_every_parameter_kind(model):
    # One parameter at a time, moved 10 % - beyond the point the check was made at (5 % or less): an
    # affine field's K and M are the affine model's, assembling nothing, and its ∂K, ∂M are a fresh
    # central difference there; scale, ratio and nu are not affine - they are found so, and assembled
    # and differenced afresh at each point.
    d = KINDS[model]
    for p in parameters(d):
        pm = ParametrisedModel(d, [p.name])
        x1 = pm.x0 * 1.1
        fresh = _assembled(d, [p.name], x1)
        assert pm.affine == (p.field in AFFINE_FIELDS), p.name
        K, M = pm.matrices(x1)
        assert _worst(K, fresh.K, fresh.K) <= SAME and _worst(M, fresh.M, fresh.M) <= SAME, p.name
        ((dK, dM),) = pm.derivatives(x1)
        cK, cM = _central(d, [p.name], x1, 0)
        scale = abs(x1[0]) if x1[0] else 1.0  # derivatives compared per unit relative change
        assert _worst(dK * scale, cK * scale, fresh.K) <= DERIV, p.name
        assert _worst(dM * scale, cM * scale, fresh.M) <= DERIV, p.name
        if p.field not in AFFINE_FIELDS:
            # the affine model from x0 would be wrong here: what the check keeps out
            K_affine, M_affine = pm.matrices(x1, force=True)
            assert max(_worst(K_affine, fresh.K, fresh.K), _worst(M_affine, fresh.M, fresh.M)) > 1e-6


def test_parameters_acting_on_each_other_are_differenced_afresh():
    # A shaft's stiffness next to its scale (k = E·s⁴·…), a coupling past a rigid gear whose ratio is
    # tuned (its DOFs are the input's over n): their derivatives move, and are found to; a rotor
    # ahead of the gear keeps its own.
    cases = [
        (MODELS["sections"], ["s1.stiffness", "s1.scale", "s2.stiffness"], [False, False, True]),
        (_rigid_gear(), ["motor.inertia", "g.ratio", "c.stiffness"], [True, False, False]),
        (MODELS["geared"], ["g.mesh_stiffness", "g.ratio", "a.stiffness"], [False, False, True]),
    ]
    for d, names, constant in cases:
        pm = ParametrisedModel(d, names)
        assert not pm.affine and list(pm.constant) == constant, names
        x1 = pm.x0 * np.array([1.1, 0.93, 1.07])
        fresh = _assembled(d, names, x1)
        K, M = pm.matrices(x1)
        assert _worst(K, fresh.K, fresh.K) == 0 and _worst(M, fresh.M, fresh.M) == 0  # assembled
        for k, (dK, dM) in enumerate(pm.derivatives(x1)):
            cK, cM = _central(d, names, x1, k)
            assert _worst(dK * x1[k], cK * x1[k], fresh.K) <= DERIV, names[k]
            assert _worst(dM * x1[k], cM * x1[k], fresh.M) <= DERIV, names[k]


def test_a_whole_affine_set_and_its_frequency_derivatives():
    # Every stiffness and inertia of Customer 1 and of the 6-DOF model at once: one affine model, its
    # modes the fresh assembly's and ∂f the analytic sensitivities' at a moved point.
    for d in (MODELS["customer1"], MODELS["full"]):
        names = [p.name for p in parameters(d) if p.field in ("stiffness", "inertia")]
        pm = ParametrisedModel(d, names)
        assert pm.affine and pm.constant.all()
        x1 = pm.x0 * (1 + 0.08 * np.cos(np.arange(len(names))))
        moved = with_parameters(d, dict(zip(names, x1)))
        count = min(12, pm.model0.n_dof)
        ours = fs.modal_analysis(pm.model(x1), count, damped=False)
        fresh = fs.modal_analysis(fs.assemble(moved, reduce=False, damping=False), count, damped=False)
        # matrices equal to ~1e-15 of their scale: eigenvalues of the pencil move by that times the
        # spread of stiffness over inertia (< 1e6 here); 1e-9 holds with any LAPACK kernel
        el = ~fresh.rigid
        np.testing.assert_allclose(ours.frequencies_hz[el], fresh.frequencies_hz[el], rtol=1e-9)
        modes = np.flatnonzero(el)[:6]
        df = frequency_derivatives(ours, pm.derivatives(x1), modes)
        s = sensitivities(moved, names, modes=modes)
        # the sensitivities' ∂K carry the 1e-10 round-off of their 1e-6 step (DERIV above)
        scale = (s.frequencies_hz[:, None] / np.abs(x1)[None, :]).max()
        np.testing.assert_allclose(df, s.dfrequency, rtol=0, atol=DERIV * scale)
    assert find_parameter(d, names[0]).field in AFFINE_FIELDS


@pytest.mark.parametrize(
    "inertia, says",
    [("1e-308", "derivatives leave double precision"), ("1e308", "stiffness over inertia spans")],
)
def test_derivatives_past_double_precision_are_one_error_not_warnings(inertia, says, recwarn):
    # A central difference of an inertia of 1e-308 divides by a step of 1e-314 (overflow); one of
    # 1e308 sums past it. Both printed a table with RuntimeWarnings (sensitivity) or warned before the
    # error line (calibrate's parametrised model): now one ModelError, raised where numpy overflows
    # (1e308 is refused by the modes' own spread check first).
    text = (EXAMPLES / "customer1.toml").read_text().replace("inertia = 58.10", f"inertia = {inertia}")
    d = fs.loads_model(text, source="m.toml")
    with pytest.raises(fs.ModelError, match=says):
        sensitivities(d, ["motor.inertia", "part 1.stiffness"])
    with pytest.raises(fs.ModelError, match="derivatives leave double precision"):
        ParametrisedModel(d, ["motor.inertia"])
    assert not [str(w.message) for w in recwarn]

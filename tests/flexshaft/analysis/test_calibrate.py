"""Calibration: synthetic truth recovered, modes followed by shape across a crossing, findings where a
target cannot be met, targets files, tuned model files and staged calibration."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis import calibrate as cal
from flexshaft.analysis.calibrate import Bound, Target, calibrate, frequencysolve
from flexshaft.analysis.parameters import parameter_value, with_parameters
from flexshaft.analysis.parametrised import ParametrisedModel
from flexshaft.cli import main
from flexshaft.linalg.mac import mac
from flexshaft.model.components import Coupling, Drivetrain, Rigid, Shaft
from flexshaft.sections import table_from_segments
from tests.conftest import EXAMPLES

# Synthetic truth: the targets are the truth model's own frequencies, so the least-squares optimum is
# the truth exactly, with zero residual, where Gauss-Newton with the exact (analytic) Jacobian
# converges quadratically: the step that meets the stopping test (misses settled to SOLVER_FRACTION =
# 1e-4 of the 1 % tolerances, 1e-6) leaves the point ~its square away, and the parameters follow to
# the conditioning of the Jacobian (~1e-7 on Customer 1, 1e-11 on the 6-DOF model). 1e-6 is the
# issue's requirement.
RECOVER = 1e-6


def _targets_by_shape(start, truth, modes, tolerance=0.01):
    """The truth's frequency for each named mode of the start model, paired by shape (MAC), as a
    measured mode shape would pair them."""
    out = []
    for m in modes:
        macs = mac(start.shapes[:, m], truth.shapes)  # unweighted, as a measured shape is compared
        j = int(np.argmax(macs))
        assert macs[j] > 0.9
        out.append((m, j, Target(m, frequency_hz=truth.frequencies_hz[j], tolerance=tolerance)))
    return out


def test_synthetic_truth_is_recovered_on_customer1():
    d = fs.load_model(EXAMPLES / "customer1.toml")
    scale = {
        "part 1.stiffness": 1.15,
        "part 3.stiffness": 0.85,
        "part 2.inertia": 1.2,
        "generator.inertia": 0.9,
    }
    truth = {n: parameter_value(d, n) * f for n, f in scale.items()}
    rt = fs.modal_analysis(with_parameters(d, truth))
    targets = [Target(m, frequency_hz=rt.frequencies_hz[m], tolerance=0.01) for m in (1, 2, 3, 4)]
    res = calibrate(d, targets, [Bound(n, percent=30) for n in truth])
    np.testing.assert_allclose(res.tuned, list(truth.values()), rtol=RECOVER)
    # the truth is an exact optimum (zero residual): past the last Gauss-Newton step the misses are
    # ~1e-9 over 1 % tolerances, residuals ~1e-7 and a cost ½Σr² ~1e-14; 1e-12 asks for residuals of
    # 1.4e-6 - a millionth of a tolerance, the truth and nothing else
    assert np.all(res.met) and res.cost < 1e-12
    np.testing.assert_allclose(res.change_percent, [100 * (f - 1) for f in scale.values()], atol=1e-4)


def _section(name, segs):
    return Shaft.from_sections(name, table_from_segments(segs, name=name), fs.STEEL, max_element_length=0.1)


def _full(kc=2.5e5, jm=0.5, jg=0.3):
    # 6 DOFs per node: the first torsion mode (~131 Hz) sits just below the lowest bending pair (138 Hz)
    return Drivetrain(
        "crossing",
        (
            Rigid("motor", jm),
            _section("s1", [{"length": 1.2, "od": 0.1}]),
            Coupling("c", stiffness=kc, inertia=0.02),
            _section("s2", [{"length": 0.8, "od": 0.09}]),
            Rigid("gen", jg),
        ),
        dofs="full",
        bearings=(("motor", 1e8), ("s1/c", 1e8), ("gen", 1e8)),
    )


def test_a_gear_ratio_is_tuned_through_fresh_assemblies():
    # A gear ratio enters the mesh block k·[1, −n; −n, n²], K is not affine in it: the model is
    # assembled at each point and its ∂K differenced afresh there, the other parameters keeping their
    # derivatives. Synthetic truth again.
    d = Drivetrain(
        "geared",
        (
            Rigid("motor", 10.0),
            Shaft("a", stiffness=1e5, inertia=0.1, elements=3),
            fs.Gear("g", ratio=2.5, inertia_in=0.2, inertia_out=0.05, mesh_stiffness=3e5),
            Coupling("c", stiffness=4e3, inertia=0.01),
            Rigid("gen", 0.2),
        ),
    )
    scale = {"g.ratio": 1.06, "c.stiffness": 0.9, "a.stiffness": 1.1}
    truth = {n: parameter_value(d, n) * f for n, f in scale.items()}
    rt = fs.modal_analysis(with_parameters(d, truth))
    targets = [Target(m, frequency_hz=rt.frequencies_hz[m], tolerance=0.01) for m in (1, 2, 3)]
    pm = ParametrisedModel(d, list(truth))
    assert not pm.affine and list(pm.constant) == [False, True, True]
    res = calibrate(d, targets, [Bound(n, percent=20) for n in truth])
    np.testing.assert_allclose(res.tuned, list(truth.values()), rtol=RECOVER)
    assert np.all(res.met) and res.cost < 1e-12


# How far the calibration's end point may put the targets' values from a 1e-12 solve's, in units of
# each target's tolerance: ten times the resolution asked of the solver (SOLVER_FRACTION), since its
# stopping tests bound the last step and not the distance left, a few steps along a direction the cost
# barely sees - and still a thousandth of the tolerance the targets are judged by.
SAME_OPTIMUM = 10 * cal.SOLVER_FRACTION


def test_the_targets_resolution_reaches_the_same_optimum_as_a_1e_12_solve(monkeypatch):
    # The study's Customer 1 problem (on its own model): three parameters end on bounds, one inside,
    # along a flat valley (part 4's stiffness, which the ratios barely see). The solver stops at the
    # targets' resolution and puts the pushed parameters onto their bounds: the same bounds are active
    # as in a 1e-12 solve, exactly on them, and the targets' values agree within SAME_OPTIMUM.
    d = fs.load_model(EXAMPLES / "customer1.toml")
    targets = [
        Target(2, ratio_to=1, ratio=8.22, tolerance=0.02),
        Target(3, ratio_to=1, ratio=20.28, tolerance=0.02),
    ]
    params = [
        Bound("part 3.stiffness", percent=10),
        Bound("part 3.inertia", percent=10),
        Bound("part 4.stiffness", percent=5),
        Bound("generator.inertia", percent=5),
    ]
    ours = calibrate(d, targets, params)
    monkeypatch.setattr(frequencysolve, "SOLVER_FRACTION", 1e-12 / 0.02)  # 1e-12, as it was
    tight = calibrate(d, targets, params)
    assert ours.active == tight.active and sum(a is not None for a in ours.active) == 3
    on = [k for k, a in enumerate(ours.active) if a is not None]
    bound = [ours.lower[k] if ours.active[k] == "lower" else ours.upper[k] for k in on]
    np.testing.assert_array_equal(ours.tuned[on], bound)
    apart = np.abs(ours.values - tight.values) / np.array([t.value * t.tolerance for t in targets])
    assert np.all(apart <= SAME_OPTIMUM)
    assert ours.cost <= tight.cost * (1 + SAME_OPTIMUM)


def test_synthetic_truth_with_a_mode_crossing_is_recovered_by_shape():
    # Perturbing the coupling stiffness +20 % and the rotor inertias lifts the first torsion mode across
    # the lowest bending pair: by number it is mode 2 in the start model and mode 4 in the truth. Targets
    # name the start's modes; the calibration follows them by shape and still recovers the truth.
    d = _full()
    scale = {"c.stiffness": 1.2, "motor.inertia": 0.85, "gen.inertia": 0.9, "s1.stiffness": 1.1}
    truth_values = {n: parameter_value(d, n) * f for n, f in scale.items()}
    start = fs.modal_analysis(fs.assemble(d, reduce=False), 40, damped=False)
    truth = fs.modal_analysis(fs.assemble(with_parameters(d, truth_values), reduce=False), 40, damped=False)
    torsion = [i for i in range(start.count) if start.kinds[i] == "torsion" and not start.rigid[i]][:4]
    pairs = _targets_by_shape(start, truth, torsion)
    first_start, first_truth = pairs[0][0], pairs[0][1]
    assert first_start < first_truth  # the crossing: the torsion mode changed its number
    assert start.kinds[first_start + 1] == "lateral" and truth.kinds[first_truth - 1] == "lateral"
    res = calibrate(d, [t for *_, t in pairs], [Bound(n, percent=30) for n in scale])
    np.testing.assert_allclose(res.tuned, list(truth_values.values()), rtol=RECOVER)
    assert res.modes[0] == first_truth  # the target followed its mode's shape to its new number


def test_a_target_out_of_reach_is_a_finding_with_what_it_would_take():
    # Without DUT: f2/f1 = 2.59 with the shared parts held to ±5 % (known) / ±10 % (less known) bounds.
    # It is missed; every parameter ends on a bound that helps, and the report says what one parameter
    # alone would have to do - which, applied to the tuned model, meets the target (checked here).
    d = fs.load_model(EXAMPLES / "without_dut.toml")
    params = [
        Bound("part 1.stiffness", percent=5),
        Bound("part 2.stiffness", percent=5),
        Bound("part 1.inertia", percent=10),
        Bound("part 2.inertia", percent=10),
    ]
    target = Target(2, ratio_to=1, ratio=2.59, tolerance=0.02)
    res = calibrate(d, [target], params)
    assert not res.met[0]
    assert all(a is not None for a in res.active) and all(w > 0 for w in res.widen)
    (unmet,) = res.unmet
    best = unmet["alone_would_need"][0]
    k = res.names.index(best["parameter"]) if best["parameter"] in res.names else None
    name = best["parameter"]
    value = (res.tuned[k] if k is not None else parameter_value(res.drivetrain, name)) * (
        1 + best["change_percent"] / 100
    )
    r = fs.modal_analysis(with_parameters(res.drivetrain, {name: value}))
    assert r.frequencies_hz[2] / r.frequencies_hz[1] == pytest.approx(2.59, rel=1e-6)


def test_fixed_values_multistart_and_physics():
    d = fs.load_model(EXAMPLES / "customer1_cad.toml")
    r0 = fs.modal_analysis(d)
    target = Target(1, frequency_hz=1.02 * r0.frequencies_hz[1], tolerance=0.001)
    motor = parameter_value(d, "motor.inertia")  # held at the file's own (real-size) value
    res = calibrate(
        d,
        [target],
        [
            Bound("part 4.stiffness", percent=20),
            Bound("part 3.stiffness", percent=20),
            Bound("motor.inertia", fixed=motor),
        ],
        starts=3,
        seed=1,
    )
    assert res.starts == 3 and res.met[0]
    assert res.fixed == {"motor.inertia": motor}
    # part 4 is made from sections: its tuned stiffness is a Young's modulus (k ∝ E), flagged beyond ±10 %
    (phys,) = [p for p in res.physics if p["parameter"] == "part 4.stiffness"]
    ratio = res.tuned[res.names.index("part 4.stiffness")] / res.initial[res.names.index("part 4.stiffness")]
    assert phys["E"] == pytest.approx(fs.STEEL.E * ratio, rel=1e-12)
    assert phys["scale_equivalent"] == pytest.approx(ratio**0.25, rel=1e-12)
    assert phys["plausible"] == (abs(ratio - 1) <= 0.10)


def test_bad_targets_and_bounds():
    for make, field in [
        (lambda: Target(1), "target"),
        (lambda: Target(1, frequency_hz=10.0, ratio=2.0, ratio_to=2), "target"),
        (lambda: Target(2, ratio=2.0), "target.ratio_to"),
        (lambda: Target(1, frequency_hz=-1.0), "target.frequency_hz"),
        (lambda: Target(1, frequency_hz=1.0, tolerance=0.0), "target.tolerance"),
        # values whose residual (a relative miss over a tolerance) or bound width double precision loses
        (lambda: Target(1, frequency_hz=1e-300), "target.frequency_hz"),
        (lambda: Target(1, frequency_hz=1.0, tolerance=1e-300), "target.tolerance"),
        (lambda: Bound("a.b", percent=1e-300), "a.b.percent"),
        (lambda: Bound("a.b"), "parameter"),
        (lambda: Bound("a.b", percent=5, fixed=1.0), "parameter"),
        (lambda: Bound("a.b", lower=2.0, upper=1.0), "a.b.bounds"),
    ]:
        with pytest.raises(fs.ModelError) as info:
            make()
        assert info.value.field == field
    d = fs.load_model(EXAMPLES / "customer1.toml")
    with pytest.raises(fs.ModelError, match="do not contain the model's value"):
        calibrate(d, [Target(1, frequency_hz=11.0)], [Bound("part 3.stiffness", lower=1.0, upper=2.0)])
    with pytest.raises(fs.ModelError, match="no such parameter"):
        calibrate(d, [Target(1, frequency_hz=11.0)], [Bound("part 9.stiffness", percent=5)])


def _no_optimiser(monkeypatch):
    def refuse(*args, **kw):
        raise AssertionError("the optimiser started")

    monkeypatch.setattr(frequencysolve, "_solve_start", refuse)


C1_BOUND = [Bound("part 3.stiffness", percent=10)]


@pytest.mark.parametrize(
    "targets,field,says",
    [
        ([Target(99, frequency_hz=100.0)], "target.mode", "valid: an elastic mode of the model, 1 … 4"),
        ([Target(2, ratio_to=99, ratio=8.0)], "target.ratio_to", "no such mode: the model has 5 modes"),
        ([Target(0, frequency_hz=1.0)], "target.mode", "mode 0 is rigid-body"),
        ([Target(-1, frequency_hz=1.0)], "target.mode", "no such mode"),
        ([Target(2, ratio_to=0, ratio=8.0)], "target.ratio_to", "rigid-body"),  # a ratio to 0 Hz
        ([Target(10**30, frequency_hz=1.0)], "target.mode", "1 … 4"),  # never reaches numpy's int64
        (
            [Target(1, frequency_hz=11.0), Target(1, frequency_hz=12.0)],
            "target",
            "[[target]] #2: target = 'f1 = 12 Hz': targets what [[target]] #1 targets already",
        ),
        ([Target(2, ratio_to=1, ratio=8.0), Target(1, ratio_to=2, ratio=0.12)], "target", "already"),
        ([Target(2, frequency_hz=91.0, shape=(1.0, 0.5))], "target.shape", "2 values for the model's 5"),
    ],
)
def test_targets_are_checked_against_the_model_before_the_optimiser(monkeypatch, targets, field, says):
    # Found: mode = 99 or ratio_to = 99 ended as an IndexError deep in the tracker ("a flexshaft defect").
    _no_optimiser(monkeypatch)
    d = fs.load_model(EXAMPLES / "customer1.toml")  # 5 DOFs: mode 0 rigid-body, 1 … 4 elastic
    with pytest.raises(fs.ModelError) as info:
        calibrate(d, targets, C1_BOUND)
    assert info.value.field == field and says in str(info.value), str(info.value)
    assert str(info.value).startswith("[[target]] #")


def test_mode_numbers_are_whole_numbers_and_not_a_ratio_to_themselves():
    for make, field in [
        (lambda: Target(2.5, frequency_hz=1.0), "target.mode"),
        (lambda: Target(True, frequency_hz=1.0), "target.mode"),
        (lambda: Target("2", frequency_hz=1.0), "target.mode"),
        (lambda: Target(2, ratio_to=1.0, ratio=2.0), "target.ratio_to"),
        (lambda: Target(2, ratio_to=2, ratio=2.0), "target.ratio_to"),
    ]:
        with pytest.raises(fs.ModelError) as info:
            make()
        assert info.value.field == field


def test_a_full_models_rigid_body_modes_are_not_targets(monkeypatch):
    # Three bearings hold the line laterally: axial motion and spin are its rigid-body modes 0 and 1.
    _no_optimiser(monkeypatch)
    with pytest.raises(fs.ModelError, match="modes 0 … 1 are rigid-body") as info:
        calibrate(_full(), [Target(1, frequency_hz=100.0)], [Bound("c.stiffness", percent=10)])
    assert info.value.valid.startswith("an elastic mode of the model, 2 … ")


@pytest.mark.parametrize(
    "params,field,says",
    [
        # Found: bounds = [-1, 70000] on a stiffness was accepted (and the optimiser could reach k = -1).
        ([Bound("part 3.stiffness", lower=-1, upper=70000)], "part 3.stiffness.bounds", "> 0 N·m/rad"),
        ([Bound("part 3.stiffness", lower=0, upper=70000)], "part 3.stiffness.bounds", "lower bound"),
        ([Bound("motor.inertia", lower=0.0, upper=70.0)], "motor.inertia.bounds", "> 0 kg·m²"),
        ([Bound("part 1.damping_ratio", lower=0.001, upper=1.0)], "part 1.damping_ratio.bounds", "< 1"),
        ([Bound("part 3.stiffness", lower=6e4, upper=7e4)], "part 3.stiffness.bounds", "55120.04"),
        ([Bound("part 1.damping", percent=10)], "part 1.damping", "is 0"),
        (
            [Bound("part 3.stiffness", percent=10), Bound("part 3.stiffness", fixed=5e4)],
            "parameter",
            "[[parameter]] #2: parameter = 'part 3.stiffness': is listed twice",
        ),
        (
            [Bound("part 3.stiffness", percent=10), Bound("motor.inertia", fixed=-58.1)],
            "motor.inertia.fixed",
            "> 0 kg·m²",
        ),
        ([Bound("part 9.stiffness", percent=10)], "parameter", "[[parameter]] #1: parameter = 'part 9"),
    ],
)
def test_bounds_lie_in_the_parameters_domain_around_its_value(monkeypatch, params, field, says):
    _no_optimiser(monkeypatch)
    d = fs.load_model(EXAMPLES / "customer1.toml")
    with pytest.raises(fs.ModelError) as info:
        calibrate(d, [Target(1, frequency_hz=11.0)], params)
    assert info.value.field == field and says in str(info.value), str(info.value)


def test_percent_bounds_that_leave_the_domain_are_refused(monkeypatch):
    # ± 90 % around a damping ratio of 0.6 reaches 1.14: not a damping ratio.
    _no_optimiser(monkeypatch)
    d = Drivetrain(
        "z",
        (Rigid("m", 1.0), Shaft("s", stiffness=1e4, inertia=0.1, damping_ratio=0.6), Rigid("g", 1.0)),
    )
    with pytest.raises(fs.ModelError, match="upper bound") as info:
        calibrate(d, [Target(1, frequency_hz=20.0)], [Bound("s.damping_ratio", percent=90)])
    assert info.value.field == "s.damping_ratio.percent" and ">= 0 and < 1" in info.value.valid


def test_cli_names_the_targets_file_the_entry_and_the_stage(tmp_path, capsys, monkeypatch):
    _no_optimiser(monkeypatch)  # the second stage's mode 99 is refused before the first stage is solved
    for name in ("without_dut.toml", "customer1.toml"):
        (tmp_path / name).write_text((EXAMPLES / name).read_text())
    targets = tmp_path / "t.toml"
    second = "mode = 2\nratio_to = 1\nratio = 8.22"
    targets.write_text(STAGED.format(ratio=2.9).replace(second, second.replace("2", "99", 1)))
    assert main(["calibrate", str(tmp_path / "customer1.toml"), "--targets", str(targets), "--json"]) == 2
    out = capsys.readouterr()
    assert out.out == ""
    assert out.err.strip() == (
        f"flexshaft: error: {targets}: [[stage]] #2 [[target]] #1: target.mode = 99: no such mode: "
        "the model has 5 modes, 0 … 4; valid: an elastic mode of the model, 1 … 4"
    )


STAGED = """
[options]
starts = 1

[[stage]]
name = "shared parts"
model = "without_dut.toml"
[[stage.target]]
mode = 2
ratio_to = 1
ratio = {ratio}
tolerance = 0.02
[[stage.parameter]]
name = "part 1.stiffness"
percent = 10
[[stage.parameter]]
name = "part 2.stiffness"
percent = 10

[[stage]]
name = "Customer 1"
model = "customer1.toml"
[[stage.target]]
mode = 2
ratio_to = 1
ratio = 8.22
tolerance = 0.02
[[stage.parameter]]
name = "part 3.stiffness"
percent = 30
[[stage.parameter]]
name = "generator.inertia"
percent = 30
"""


def test_cli_staged_calibration_writes_a_tuned_model(tmp_path, capsys):
    for name in ("without_dut.toml", "customer1.toml"):
        (tmp_path / name).write_text((EXAMPLES / name).read_text())
    r0 = fs.modal_analysis(fs.load_model(EXAMPLES / "without_dut.toml"))
    reachable = 0.97 * r0.frequencies_hz[2] / r0.frequencies_hz[1]  # within reach of ±10 % stiffness
    targets = tmp_path / "targets.toml"
    targets.write_text(STAGED.format(ratio=reachable))
    out = tmp_path / "tuned.toml"
    args = [
        "calibrate",
        str(tmp_path / "customer1.toml"),
        "--targets",
        str(targets),
        "-o",
        str(out),
        "--json",
    ]
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    first, second = doc["stages"]
    assert all(t["met"] for t in first["targets"]) and all(t["met"] for t in second["targets"])
    # the shared parts' tuned values are carried into Customer 1, fixed
    tuned1 = {p["name"]: p["tuned"] for p in first["parameters"]}
    assert second["carried"] == pytest.approx(tuned1, rel=1e-15)
    # the written model is the tuned one: it loads and has the tuned frequencies and values
    tuned = fs.load_model(out)
    assert parameter_value(tuned, "part 1.stiffness") == pytest.approx(tuned1["part 1.stiffness"], rel=1e-12)
    r = fs.modal_analysis(tuned)
    assert r.frequencies_hz[2] / r.frequencies_hz[1] == pytest.approx(second["targets"][0]["tuned"], rel=1e-9)
    assert "tuned by flexshaft calibrate" in out.read_text().splitlines()[0]
    assert main(args) == 2  # no overwrite without --force
    assert "exists" in capsys.readouterr().err
    # a parameter tuned earlier cannot be tuned again later
    targets.write_text(STAGED.format(ratio=reachable).replace('"generator.inertia"', '"part 1.stiffness"'))
    assert main(["calibrate", str(tmp_path / "customer1.toml"), "--targets", str(targets)]) == 2
    assert "earlier stage" in capsys.readouterr().err


@pytest.mark.parametrize(
    "text,field",
    [
        ("[[target]]\nmode = 1\nfrequency_hz = 10.0\n", "parameter"),
        ("[[parameter]]\nname = 'part 3.stiffness'\npercent = 5\n", "target"),
        (
            "[[target]]\nmode = 1\nfrequency_hz = 10.0\ncolour = 1\n"
            "[[parameter]]\nname = 'x.y'\npercent = 5\n",
            "colour",
        ),
        ("[options]\nstarts = 0\n[[target]]\nmode = 1\nfrequency_hz = 1.0\n", "starts"),
        ("[[target]]\nmode = 1\nfrequency_hz = 10.0\n[[parameter]]\nname = 'x.y'\nbounds = [1]\n", "bounds"),
        ("not toml [", None),
    ],
)
def test_bad_targets_files(tmp_path, capsys, text, field):
    path = tmp_path / "t.toml"
    path.write_text(text)
    assert main(["calibrate", str(EXAMPLES / "customer1.toml"), "--targets", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "t.toml" in err
    if field:
        assert field in err


def test_the_study_calibration_example(capsys):
    # The study's staged problem (examples/calibration/study.toml): Customer 1's measured ratios are met
    # within the study's tolerances on top of the shared parts; Without DUT's f2/f1 = 2.59 and Customer 2's
    # ratios are not, inside physical bounds - and the report says what it would take (a finding: the
    # study's tuned models missed them too, 2.67 against 2.59 and 21.8 against 28.6).
    args = [
        "calibrate",
        str(EXAMPLES / "customer1.toml"),
        "--targets",
        str(EXAMPLES / "calibration" / "study.toml"),
    ]
    assert main([*args, "--json"]) == 0
    shared, c1, c2 = json.loads(capsys.readouterr().out)["stages"]
    assert [s["name"] for s in (shared, c1, c2)] == ["shared parts", "Customer 1", "Customer 2"]
    assert all(t["met"] for t in c1["targets"])
    assert not shared["targets"][0]["met"] and shared["unmet"][0]["alone_would_need"]
    assert not all(t["met"] for t in c2["targets"]) and c2["unmet"]
    # both DUT set-ups start from the shared parts as tuned, and nothing of Customer 1 reaches Customer 2
    tuned_shared = {p["name"]: p["tuned"] for p in shared["parameters"]}
    assert c1["carried"] == pytest.approx(tuned_shared) and c2["carried"] == pytest.approx(tuned_shared)


def test_multistart_on_an_executor_equals_it_in_turn():
    # The starts are independent least-squares runs; on worker processes they give the same end points.
    from concurrent.futures import ProcessPoolExecutor

    d = fs.load_model(EXAMPLES / "customer1.toml")
    r0 = fs.modal_analysis(d)
    targets = [
        Target(1, frequency_hz=1.03 * r0.frequencies_hz[1]),
        Target(3, frequency_hz=0.99 * r0.frequencies_hz[3]),
    ]
    params = [Bound("part 3.stiffness", percent=20), Bound("part 2.stiffness", percent=20)]
    serial = calibrate(d, targets, params, starts=3, seed=2)
    with ProcessPoolExecutor(max_workers=2) as pool:
        parallel = calibrate(d, targets, params, starts=3, seed=2, executor=pool)
    np.testing.assert_array_equal(parallel.tuned, serial.tuned)
    assert parallel.starts == serial.starts == 3 and np.all(serial.met)


def test_a_measured_shape_names_its_mode():
    # A target may carry the measured shape (θx at the stations): it must be the named mode's (MAC).
    d = fs.load_model(EXAMPLES / "customer1.toml")
    r = fs.modal_analysis(d)
    shape2 = tuple(r.station_shapes()[:, 2])
    ok = Target(2, frequency_hz=r.frequencies_hz[2], shape=shape2)
    res = calibrate(d, [ok], [Bound("part 2.stiffness", percent=10)])
    assert res.met[0]
    with pytest.raises(fs.ModelError, match="is mode 2 of the model"):
        calibrate(d, [Target(3, frequency_hz=240.0, shape=shape2)], [Bound("part 2.stiffness", percent=10)])
    with pytest.raises(fs.ModelError, match="5 stations"):
        calibrate(
            d, [Target(2, frequency_hz=90.0, shape=(1.0, 0.5))], [Bound("part 2.stiffness", percent=10)]
        )


def test_what_one_parameter_alone_needs_survives_a_path_dependent_miss():
    # "alone would need" follows a mode by shape, so a point's miss can depend on the path taken to it
    # and brentq's own evaluation of the bracket's ends may disagree with the signs seen; the fallback
    # bisects on the signs seen. Reference: the root of x² − 2 (√2), to the bisection's tolerance.
    from flexshaft.analysis.calibrate.frequencysolve import _bisect

    root = _bisect(lambda x: x * x - 2.0, 1.0, -1.0, 2.0)
    assert root == pytest.approx(2.0**0.5, rel=1e-8)
    assert _bisect(lambda x: float("nan"), 1.0, -1.0, 2.0) is None  # a point that cannot be solved


def test_modes_are_told_apart_by_their_inertia_weighted_shape():
    # The tracker's MAC is weighted by the inertia matrix the modes are orthogonal in: a model's own
    # modes then have MAC exactly the identity (to round-off), however alike their unweighted shapes -
    # on Customer 2 from geometry two distinct modes had an unweighted MAC of 0.90, and the tracker's
    # 0.1 margin was decided by the CPU's round-off.
    import dataclasses

    d = fs.load_model(EXAMPLES / "customer2.toml")
    d = dataclasses.replace(
        d,
        components=tuple(
            dataclasses.replace(c, elements=30) if c.type == "shaft" else c for c in d.components
        ),
    )
    r = fs.modal_analysis(d, 12, damped=False)
    phi = r.shapes[:, ~r.rigid]
    weighted = mac(phi, phi, r.model.M)
    assert np.allclose(weighted, np.eye(phi.shape[1]), atol=1e-9)  # M-orthogonality, to round-off

"""flexshaft's flexible bodies in Exudyn (the multibody extra): each body alone has its own free-free
modes there, the Customer 1 bench built from them has flexshaft's modes and damping, and its
motor-torque step response is flexshaft's; what the bridge cannot carry is refused in one line."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.errors import ModelError
from flexshaft.exports.exudynbody import (
    ExudynBody,
    chain_to_exudyn,
    coupling_body,
    simulate_exudyn,
    to_exudyn,
)
from tests.conftest import EXAMPLES

# Both sides hold the same matrices (Exudyn's body is the FlexibleBody's K, M, C and the mass its
# inertia terms integrate reproduces M exactly), so the frequencies differ by the eigen-solvers'
# round-off only: 4.5e-10 measured on the 11 Hz mode (the 0 Hz spin's round-off leaks into it), 1e-12
# and below on every other. The issue asks 1e-3.
FREQ_RTOL = 1e-8
# Each body alone: its free-free frequencies, which flexshaft solves from the same K and M: 1e-12 measured.
BODY_RTOL = 1e-9
# Exudyn's damped modes against flexshaft's: the same damping matrices, so round-off again; an absolute
# bound as the coupling mode's ratio is itself 3e-7 (it differs by 2e-13).
RATIO_ATOL = 1e-9
# The step response: Exudyn's trapezoidal rule at STEP s lengthens each mode's period by (ωh)²/12, which
# over DURATION s shifts the 170 Hz mode's phase by ~0.01 rad; 4.2e-4 of the coupling torque's range
# measured, 3.8e-4 of the motor speed's, 9e-6 of the generator's. The issue asks 1e-3 of the range.
STEP_TOL = 1e-3
DURATION, STEP, RATE, TORQUE = 0.2, 1e-4, 1000.0, 1000.0
OUTPUTS = ("speed:motor", "speed:generator", "torque:part 3")
INSTALL = "pip install 'flexshaft[multibody]' (Exudyn >= 1.13)"


@pytest.fixture(scope="module")
def exu():
    return pytest.importorskip("exudyn", reason="exudyn is not installed (the multibody extra)")


@pytest.fixture(scope="module")
def bench():
    drivetrain = fs.load_model(EXAMPLES / "customer1_flex.toml")
    return drivetrain, fs.modal_analysis(drivetrain)


def _system(exu):
    return exu.SystemContainer().AddSystem()


def _held(exu, mbs, marker):
    """A revolute joint about x from ground to ``marker`` (the one way a torsion body may be held)."""
    import exudyn.itemInterface as items

    ground = mbs.AddObject(items.ObjectGround())
    at = mbs.AddMarker(items.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(items.ObjectJointGeneric(markerNumbers=[at, marker], constrainedAxes=[1, 1, 1, 0, 1, 1]))


def _hz(eigenvalues):
    return np.sqrt(np.abs(eigenvalues)) / (2 * np.pi)


# --- without Exudyn ---------------------------------------------------------------------------------------


def test_flexshaft_never_imports_exudyn():
    code = "import sys, flexshaft, flexshaft.exports.exudynbody; print('exudyn' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_missing_exudyn_is_one_line(monkeypatch, bench):
    monkeypatch.setitem(sys.modules, "exudyn", None)  # `import exudyn` raises ImportError
    body = fs.reduce_part(bench[0], "part 1").body
    for call in (lambda: to_exudyn(body, None), lambda: chain_to_exudyn(bench[0], None)):
        with pytest.raises(ModelError) as err:
            call()
        assert (
            str(err.value)
            == "to_exudyn: needs exudyn; valid: pip install 'flexshaft[multibody]' (Exudyn >= 1.13)"
        )


def test_coupling_body_is_the_chains_coupling(bench):
    # the chain's entries of a coupling: its spring and damper between the hubs, its inertia spread by
    # the model's rule (consistent: J/3 on each hub, J/6 between them; lumped or "halves": J/2 each)
    drivetrain, _ = bench
    comp = dataclasses.replace(drivetrain.component("part 3"), damping=12.5)
    j, k, c = comp.inertia, comp.stiffness, comp.damping
    twist = np.array([[1.0, -1.0], [-1.0, 1.0]])
    body = coupling_body(comp, "consistent")
    np.testing.assert_allclose(body.M, j * np.array([[1 / 3, 1 / 6], [1 / 6, 1 / 3]]), rtol=1e-15)
    np.testing.assert_allclose(body.K, k * twist, rtol=1e-15)
    np.testing.assert_allclose(body.C, c * twist, rtol=1e-15)
    assert body.dofs == "torsion" and body.n_modes == 0
    for lumped in (
        coupling_body(comp, "lumped"),
        coupling_body(dataclasses.replace(comp, inertia_split="halves")),
    ):
        np.testing.assert_allclose(lumped.M, np.diag([j / 2, j / 2]), rtol=1e-15)


# --- with Exudyn ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("given", ["reduction", "body"])
@pytest.mark.parametrize("part", ["part 1", "part 2", "part 4"])
def test_torsion_body_alone_has_its_free_modes(exu, bench, part, given):
    # a PartReduction brings its mesh's positions; a body alone spreads them between its boundary nodes,
    # which moves the rings along the axis and changes nothing the torsion body does
    reduction = fs.reduce_part(bench[0], part)
    mbs = _system(exu)
    placed = to_exudyn(reduction if given == "reduction" else reduction.body, mbs)
    _held(exu, mbs, placed.interfaces[0])
    mbs.Assemble()
    f = _hz(mbs.ComputeODE2Eigenvalues()[0])
    body = reduction.body
    assert f.size == body.free_hz.size
    np.testing.assert_allclose(f[1:], body.free_hz[1:], rtol=BODY_RTOL)


def test_full_body_alone_has_its_free_modes(exu, bench):
    # a 6-DOF body, free in space: six rigid-body modes, then bending, torsion and axial modes
    drivetrain = dataclasses.replace(bench[0], dofs="full")
    body = fs.reduce_part(drivetrain, "part 4").body
    mbs = _system(exu)
    to_exudyn(body, mbs, radius=0.13)  # mesh positions from the body's own recovery T
    mbs.Assemble()
    f = _hz(mbs.ComputeODE2Eigenvalues()[0])
    assert f.size == body.free_hz.size
    assert np.all(f[:6] < 1e-6 * f[6])
    np.testing.assert_allclose(f[6:], body.free_hz[6:], rtol=BODY_RTOL)


def test_body_result_and_interfaces(exu, bench):
    reduction = fs.reduce_part(bench[0], "part 2")
    mbs = _system(exu)
    placed = to_exudyn(reduction, mbs, position=(1.0, 0.5, 0.0))
    mbs.Assemble()
    assert isinstance(placed, ExudynBody)
    with pytest.raises(dataclasses.FrozenInstanceError):
        placed.radius = 1.0
    # a marker at each boundary node (the torque flange's too), where the node is
    assert len(placed.interfaces) == reduction.body.boundary_nodes.size == 3
    reference = exu.ConfigurationType.Reference
    at = [
        mbs.GetMarkerOutput(m, exu.OutputVariableType.Position, configuration=reference)
        for m in placed.interfaces
    ]
    expected = np.column_stack([1.0 + reduction.body.boundary_x, np.full(3, 0.5), np.zeros(3)])
    np.testing.assert_allclose(at, expected, atol=1e-12)
    np.testing.assert_allclose(placed.interface_positions, expected, atol=1e-12)
    # the first boundary node is the frame: c = E·w + P·ζ puts w on it and ζ on the rest
    c = placed.coordinates(0.1, np.arange(reduction.body.K.shape[0] - 1.0))
    assert c[0] == 0.1 and c[1] == 0.1 + 0.0 and c[2] == 0.1 + 1.0


def test_bench_has_flexshafts_modes(exu, bench):
    drivetrain, reference = bench
    mbs = _system(exu)
    chain_to_exudyn(drivetrain, mbs)
    mbs.Assemble()
    f = _hz(mbs.ComputeODE2Eigenvalues()[0])
    elastic = ~reference.rigid
    assert f.size == reference.frequencies_hz.size  # every mode the bodies carry, and only those
    np.testing.assert_allclose(f[elastic], reference.frequencies_hz[elastic], rtol=FREQ_RTOL)
    # damped: Exudyn's complex eigenvalues carry each body's modal damping as flexshaft does
    lam = mbs.ComputeODE2Eigenvalues(computeComplexEigenvalues=True, useAbsoluteValues=False)[0]
    lam = lam[lam.imag > 1e-3 * 2 * np.pi * reference.frequencies_hz[elastic][0]]
    lam = lam[np.argsort(np.abs(lam))]
    np.testing.assert_allclose(
        np.abs(lam) / (2 * np.pi), reference.damped.natural_frequencies_hz[elastic], rtol=FREQ_RTOL
    )  # the same matrices: round-off, as the undamped frequencies
    np.testing.assert_allclose(
        -lam.real / np.abs(lam), reference.damping_ratios[elastic], rtol=0, atol=RATIO_ATOL
    )


def test_bench_step_response_is_flexshafts(exu, bench):
    import exudyn.itemInterface as items

    drivetrain, reference = bench
    mbs = _system(exu)
    chain = chain_to_exudyn(drivetrain, mbs)
    motor, generator, coupling = (chain.component(n) for n in ("motor", "generator", "part 3"))
    mbs.AddLoad(items.LoadTorqueVector(markerNumber=motor.marker, loadVector=[TORQUE, 0.0, 0.0]))
    ov = exu.OutputVariableType
    sensors = [
        mbs.AddSensor(items.SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=kind))
        for node, kind in (
            (motor.node, ov.AngularVelocity),
            (generator.node, ov.AngularVelocity),
            (coupling.modal_node, ov.Coordinates),
        )
    ]
    mbs.Assemble()
    simulate_exudyn(mbs, DURATION, STEP, sample_period=1.0 / RATE)
    motor_speed, generator_speed, twist = (mbs.GetSensorStoredData(s) for s in sensors)
    got = [motor_speed[:, 1], generator_speed[:, 1], chain.coupling_torque("part 3", twist[:, 1])]
    run = fs.simulate(
        reference, fs.Scenario.step(TORQUE), OUTPUTS, rate=RATE, duration=DURATION, max_hz=np.inf
    )
    np.testing.assert_allclose(motor_speed[:, 0], run.time, atol=1e-9)
    for name, y in zip(OUTPUTS, got):
        expected = run.outputs[name]
        assert np.max(np.abs(y - expected)) <= STEP_TOL * np.ptp(expected), name


def test_what_the_chain_cannot_carry_is_refused(exu, bench):
    drivetrain, _ = bench
    by_numbers = fs.load_model(EXAMPLES / "customer1.toml")  # shafts without reduce
    full = dataclasses.replace(drivetrain, dofs="full")
    for model, field in ((by_numbers, "reduce"), (full, "dofs")):
        with pytest.raises(ModelError) as err:
            chain_to_exudyn(model, _system(exu))
        assert err.value.field == field and "\n" not in str(err.value)
    with pytest.raises(ModelError, match="radius"):
        to_exudyn(fs.reduce_part(drivetrain, "part 4"), _system(exu), radius=0.0)

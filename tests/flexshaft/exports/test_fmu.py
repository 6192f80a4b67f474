"""The drivetrain FMU as FMPy loads it (not as flexshaft reads it): FMPy's validator, and FMPy's own
co-simulation and model-exchange runs against flexshaft's ``simulate`` of the same scenario."""

import shutil
import subprocess
import zipfile

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import response_modes
from flexshaft.analysis.systemdamping import system_damped
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.exports.fmu import _compiler, fmu_system, write_fmu
from flexshaft.model.assembly import assemble
from tests.conftest import EXAMPLES

fmpy = pytest.importorskip("fmpy", reason="FMPy is not installed (the test extra)")
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

needs_cc = pytest.mark.skipif(_compiler() is None, reason="no C compiler (cc, gcc or clang) to build the FMU")

OUTPUTS = ["speed:motor", "speed:generator", "torque:part 3"]
RATE = 1000.0  # Hz: the co-simulation's communication step and flexshaft's sample step
# Co-simulation and flexshaft's simulate take the same exact zero-order-hold steps, each from its own
# matrix exponential (the FMU's C Pade-13 against scipy's): they differ by round-off, ~1e-15 of the
# state per step, carried over 2000 steps of a lightly damped system: 1e-10 measured, 1e-6 asked.
CS_TOL = 1e-6
# Model exchange is integrated by FMPy's CVode: the FMU gives the exact derivative, and what is left is
# CVode's global error at its tolerance (2e-7 of the range at rtol 1e-12; it shrinks with rtol, see
# test_model_exchange_converges_to_flexshaft).
ME_RTOL = 1e-12


@pytest.fixture(scope="module")
def customer1():
    return fs.load_model(EXAMPLES / "customer1.toml")


@pytest.fixture(scope="module")
def built(customer1, tmp_path_factory):
    """Customer 1 as an FMU, FMI 2 and FMI 3, built once."""
    if _compiler() is None:
        pytest.skip("no C compiler (cc, gcc or clang) to build the FMU")
    folder = tmp_path_factory.mktemp("fmu")
    system = fmu_system(customer1, None, OUTPUTS)
    return {v: write_fmu(system, folder / f"customer1_fmi{v}.fmu", fmi=v) for v in (2, 3)}


def _flexshaft(drivetrain, scenario, duration):
    result = response_modes(assemble(drivetrain))
    return fs.simulate(result, scenario, OUTPUTS, rate=RATE, duration=duration, max_hz=float("inf"))


def _inputs(t, motor, *, held: bool):
    """FMPy's input table: the motor torque at the samples; ``held``: as a staircase (each value
    repeated at the next sample's time, which FMPy takes as an event), the zero-order hold flexshaft's
    samples mean, for a continuous-time integrator."""
    kinds = [("time", float), ("motor", float), ("generator", float)]
    if not held:
        return np.array([(a, b, 0.0) for a, b in zip(t, motor)], dtype=kinds)
    rows = [(t[0], motor[0], 0.0)]
    for k in range(1, t.size):
        rows += [(t[k], motor[k - 1], 0.0), (t[k], motor[k], 0.0)]
    return np.array(rows, dtype=kinds)


def _error(ref, out) -> float:
    """The largest difference of any output over the run, relative to that output's range."""
    return max(np.max(np.abs(np.asarray(ref.outputs[n]) - out[n])) / np.ptp(ref.outputs[n]) for n in OUTPUTS)


def _run(path, kind, t, motor, *, rtol=None, start_values=None):
    return simulate_fmu(
        str(path),
        fmi_type=kind,
        stop_time=float(t[-1]),
        step_size=1 / RATE,
        output_interval=1 / RATE,
        input=_inputs(t, motor, held=kind == "ModelExchange"),
        output=OUTPUTS,
        relative_tolerance=rtol,
        record_events=False,
        start_values=start_values or {},
    )


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_finds_no_problem(built, version):
    assert validate_fmu(str(built[version].path)) == []
    names = set(zipfile.ZipFile(built[version].path).namelist())
    assert {"sources/model_data.c", "sources/drivetrain.c", f"sources/fmi{version}.c"} <= names
    assert "documentation/licenses/FMI-LICENSE.txt" in names
    assert any(n.startswith("binaries/") for n in names)


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
def test_units_in_the_model_description(built, version):
    md = read_model_description(str(built[version].path))
    by_name = {v.name: v for v in md.modelVariables}
    assert [by_name[n].causality for n in ("motor", "generator")] == ["input", "input"]
    assert by_name["motor"].unit == "N.m" and by_name["speed:motor"].unit == "rad/s"
    assert by_name["torque:part 3"].unit == "N.m"
    units = {u.name: u for u in md.unitDefinitions}
    assert (units["N.m"].baseUnit.kg, units["N.m"].baseUnit.m, units["N.m"].baseUnit.s) == (1, 2, -2)
    rpm = {d.name: d for d in units["rad/s"].displayUnits}["rpm"]
    assert rpm.factor == pytest.approx(60 / (2 * np.pi), rel=1e-15)
    assert by_name["initial_speed"].causality == "parameter" and by_name["initial_speed"].unit == "rad/s"
    assert by_name["damping_variant"].type == "Enumeration"


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["CoSimulation", "ModelExchange"])
def test_a_step_of_motor_torque_as_flexshaft_simulates_it(customer1, built, version, kind):
    ref = _flexshaft(customer1, fs.Scenario.step(100.0), 2.0)
    out = _run(built[version].path, kind, ref.time, np.full(ref.time.size, 100.0), rtol=ME_RTOL)
    assert _error(ref, out) < CS_TOL


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["CoSimulation", "ModelExchange"])
def test_a_sine_of_motor_torque_as_flexshaft_simulates_it(customer1, built, version, kind):
    # 12 Hz: between the first two modes, the response carries both
    ref = _flexshaft(customer1, fs.Scenario.sine(50.0, 12.0), 1.0)
    motor = 50.0 * np.sin(2 * np.pi * 12.0 * ref.time)  # sampled at each step's start and held
    out = _run(built[version].path, kind, ref.time, motor, rtol=ME_RTOL)
    assert _error(ref, out) < CS_TOL


@needs_cc
def test_model_exchange_converges_to_flexshaft(customer1, built):
    """What separates model exchange from flexshaft is CVode's error alone: it falls with CVode's
    tolerance (the FMU's derivatives are exact)."""
    ref = _flexshaft(customer1, fs.Scenario.step(100.0), 2.0)
    motor = np.full(ref.time.size, 100.0)
    errors = [
        _error(ref, _run(built[2].path, "ModelExchange", ref.time, motor, rtol=r)) for r in (1e-8, 1e-12)
    ]
    assert errors[1] < errors[0] / 10


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
def test_the_parameters(customer1, built, version):
    path = built[version].path
    t = np.arange(int(0.5 * RATE) + 1) / RATE
    # Spinning at 100 rad/s with no torque: the whole line turns rigidly, nothing twists.
    out = _run(path, "CoSimulation", t, np.zeros(t.size), start_values={"initial_speed": 100.0})
    np.testing.assert_allclose(out["speed:motor"], 100.0, rtol=1e-12)  # round-off of the modal sum
    np.testing.assert_allclose(out["speed:generator"], 100.0, rtol=1e-12)  # no gear: one speed
    # the coupling's torque is k times a difference of two angles as large as the line turned (50 rad):
    # round-off leaves ~1e-15 of k·50 rad; 1e-9 of it asked
    k = customer1.component("part 3").stiffness
    assert np.max(np.abs(out["torque:part 3"])) < 1e-9 * k * 100.0 * t[-1]
    # The system damping variant is flexshaft's system-damped model.
    ref = _flexshaft(system_damped(customer1), fs.Scenario.step(100.0), 2.0)
    out = _run(
        path, "CoSimulation", ref.time, np.full(ref.time.size, 100.0), start_values={"damping_variant": 2}
    )
    assert _error(ref, out) < CS_TOL


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
def test_each_damping_variant_reads_its_own_torques(customer1, tmp_path, version):
    """A coupling with a damper: per-part damping counts its damper in the coupling's torque, system
    damping removes it (and fits Rayleigh damping instead) - the FMU's torque output follows the variant."""
    import dataclasses

    comps = [dataclasses.replace(c, damping=200.0) if c.name == "part 3" else c for c in customer1.components]
    damped = dataclasses.replace(customer1, components=tuple(comps))
    path = write_fmu(fmu_system(damped, None, OUTPUTS), tmp_path / f"d{version}.fmu", fmi=version).path
    for variant, model in ((1, damped), (2, system_damped(damped))):
        ref = _flexshaft(model, fs.Scenario.step(100.0), 1.0)
        out = _run(
            path,
            "CoSimulation",
            ref.time,
            np.full(ref.time.size, 100.0),
            start_values={"damping_variant": variant},
        )
        assert _error(ref, out) < CS_TOL, variant


def test_without_a_compiler_the_fmu_carries_its_sources(customer1, tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    built = write_fmu(fmu_system(customer1, None, OUTPUTS), tmp_path / "c1.fmu")
    assert built.platform is None and "no C compiler" in built.note
    names = zipfile.ZipFile(built.path).namelist()
    assert not any(n.startswith("binaries/") for n in names)
    assert {"modelDescription.xml", "sources/model_data.c", "sources/fmi2Functions.h"} <= set(names)


@needs_cc
def test_the_sources_alone_build_the_fmu(customer1, built, tmp_path, monkeypatch):
    """A user on another platform builds the binary from the FMU's sources with one plain command."""
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    src = write_fmu(fmu_system(customer1, None, OUTPUTS), tmp_path / "c1.fmu")
    folder = tmp_path / "unpacked"
    zipfile.ZipFile(src.path).extractall(folder)
    (folder / "binaries" / "linux64").mkdir(parents=True)
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    sources = sorted(str(p) for p in (folder / "sources").glob("*.c"))
    cmd = [cc, "-shared", "-fPIC", "-I", str(folder / "sources"), *sources, "-o"]
    subprocess.run([*cmd, str(folder / "binaries" / "linux64" / "c1.so"), "-lm"], check=True)
    ref = _flexshaft(customer1, fs.Scenario.step(100.0), 1.0)
    out = _run(folder, "CoSimulation", ref.time, np.full(ref.time.size, 100.0))
    assert _error(ref, out) < CS_TOL


@needs_cc
@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_builds_the_binary_from_the_sources(customer1, tmp_path, monkeypatch, version):
    """FMPy's own builder (CMake and the compiler) makes the binary of a sources-only FMU, FMI 2 and 3."""
    pytest.importorskip("cmake", reason="CMake is not installed (FMPy's builder needs it)")
    from fmpy.build import build_platform_binary

    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    src = write_fmu(fmu_system(customer1, None, OUTPUTS), tmp_path / "c1.fmu", fmi=version)
    monkeypatch.delenv("CC")
    folder = tmp_path / "unpacked"
    zipfile.ZipFile(src.path).extractall(folder)
    build_platform_binary(folder)  # in a temporary build folder of its own
    ref = _flexshaft(customer1, fs.Scenario.step(100.0), 1.0)
    out = _run(folder, "CoSimulation", ref.time, np.full(ref.time.size, 100.0))
    assert _error(ref, out) < CS_TOL


def test_bad_arguments(customer1, tmp_path):
    system = fmu_system(customer1)
    with pytest.raises(ModelError, match="unknown file type"):
        write_fmu(system, tmp_path / "x.zip")
    with pytest.raises(ModelError, match="unknown FMI version"):
        write_fmu(system, tmp_path / "x.fmu", fmi=4)
    with pytest.raises(ModelError, match="unknown damping variant"):
        write_fmu(system, tmp_path / "x.fmu", default_variant="rayleigh")
    with pytest.raises(ModelError, match="out of range"):
        fmu_system(customer1, system_ratio=1.5)
    with pytest.raises(ModelError, match="no such signal"):
        fmu_system(customer1, None, ["speed:nowhere"])


def test_the_command(tmp_path, capsys):
    model = str(EXAMPLES / "customer1.toml")
    out = tmp_path / "bench.fmu"
    assert main(["fmu", model, "--measure", "torque:part 3", "--sources-only", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "FMI 2.0" in text and "10 states, 2 inputs, 1 output;" in text and "sources only" in text
    assert main(["fmu", model, "-o", str(out), "--sources-only"]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["fmu", model, "-o", str(tmp_path / "bench.zip")]) == 2
    assert main(["fmu", model, "-o", str(out), "--system-damping", "2", "--force"]) == 2
    assert "--system-damping" in capsys.readouterr().err

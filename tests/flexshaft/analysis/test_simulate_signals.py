"""Simulated runs through the signal analysis, as measured bench data goes: damping back from a free
decay, eigenfrequencies and order lines from a ramp's spectrogram, and the CLI round trip."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.simulate import RPM, Scenario, SpeedControl, simulate
from flexshaft.cli import main
from flexshaft.measurement.decay import decay_damping, log_decrement
from flexshaft.measurement.signalfile import write_signals
from flexshaft.measurement.spectrogram import ridge, spectrogram
from flexshaft.model.components import Drivetrain, Rigid, Shaft
from tests.conftest import EXAMPLES

ZETA = 0.0053  # the study's 0.53 %
# The acceptance band: both estimates give the modal damping back within 5 %.
BAND = (0.0050, 0.0056)


def _customer1_mode1_damped():
    """Customer 1 with only mass-proportional damping tuned to 0.53 % on mode 1 (modes stay uncoupled)."""
    d = fs.load_model(EXAMPLES / "customer1.toml")
    w1 = fs.modal_analysis(d).omega[1]
    comps = [dataclasses.replace(c, damping_ratio=0.0) if c.type == "shaft" else c for c in d.components]
    return fs.modal_analysis(Drivetrain("c1", comps, rayleigh=fs.Rayleigh(alpha=2 * ZETA * w1)))


def _two_inertia():
    j1, j2, k = 3.0, 1.5, 2e4
    je = j1 * j2 / (j1 + j2)
    c = 2 * ZETA * math.sqrt(k * je)  # the dashpot that makes the relative motion 0.53 % damped
    return fs.modal_analysis(
        Drivetrain("1-DOF", (Rigid("a", j1), Shaft("s", stiffness=k, inertia=0.0, damping=c), Rigid("b", j2)))
    )


@pytest.mark.parametrize("case", ["1-DOF", "Customer 1 mode 1"])
def test_free_decay_gives_the_modal_damping_back(case):
    # Coast: the line carries 1000 N·m, then the torques vanish and the twist rings down. Log decrement on
    # the band-passed shaft torque and the half-power width of the transient's spectrum (rectangular and
    # exponential windows: fit for a decay) both return 0.53 % within the 5 %.
    r = _two_inertia() if case == "1-DOF" else _customer1_mode1_damped()
    f1 = r.frequencies_hz[1]
    # The model is what the test says: ξ₁ is ZETA up to the damped solve's round-off, eps·(ω_max/ω₁)/ξ ≈
    # 2e-12 (Customer 1: ω_max/ω₁ = 48), a few eps/ξ for the 1-DOF line.
    assert r.damping_ratios[1] == pytest.approx(ZETA, rel=1e-9)
    torque = "torque:s" if case == "1-DOF" else "torque:part 3"
    run = simulate(r, Scenario.coast(1000.0), [torque], rate=1000.0, duration=120.0)
    t, x = run.time, run.outputs[torque]
    band = (0.5 * f1, 1.5 * f1)
    ld = log_decrement(t, x, band=band)
    assert BAND[0] <= ld.damping_ratio <= BAND[1]
    assert ld.frequency_hz == pytest.approx(f1 * math.sqrt(1 - ZETA**2), rel=1e-3)
    for window in ("rect", "exponential"):
        hp = decay_damping(t, x, band=band, window=window)
        assert BAND[0] <= hp.damping_ratio <= BAND[1], window
        assert hp.window == window


def test_a_hann_window_on_the_decay_would_misread_it():
    # Why the decay estimate does not use Hann: on the same record a Hann-windowed spectrum's half-power
    # width reads roughly half the damping (its closed form √(2^(1/3) − 1) ≈ 0.51), far outside the band.
    from flexshaft.measurement.spectrum import spectrum

    r = _two_inertia()
    run = simulate(r, Scenario.coast(1000.0), ["torque:s"], rate=1000.0, duration=120.0)
    (peak,) = spectrum(run.outputs["torque:s"], 1000.0, window="hann").peaks(count=1)
    assert peak.damping_ratio < 0.7 * ZETA


@pytest.fixture(scope="module")
def ramp_run():
    # The study's run-up: 0 -> 1800 rpm in 900 s with the PI loop closed, a 6th-order torque ripple from
    # the drive and broadband noise; the coupling torque and the motor speed at 1 kHz.
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ctl = SpeedControl.tuned(r, tau=0.002)
    sc = Scenario.ramp(1800.0, 900.0, ctl, ripple=100.0, noise=50.0, seed=1)
    run = simulate(r, sc, ["torque:part 3", "speed:motor"], rate=1000.0, duration=900.0)
    return r, run


def test_ramp_spectrogram_shows_eigenfrequencies_and_the_sixth_order(ramp_run):
    # The ridges read off the array: (1) in a band around modes 1 and 2, away from the order line, a
    # constant line at the eigenfrequency - the median over ~400 segments within 0.1 bin (a noise-driven,
    # lightly damped line; the log-parabola's bias is 0.016 bin for a steady tone, and closing the loop
    # moves f1 by < 0.1 %, well inside); (2) in a band that follows 6 × speed, a line through the origin
    # with slope 6 Hz per rev/s: fitted slope within 0.1 %, intercept and every point within 0.2 bin (the
    # order sweeps 0.4 Hz within a 2 s segment, symmetrically about the segment's mean speed).
    r, run = ramp_run
    sg = spectrogram(
        run.outputs["torque:part 3"], run.rate_hz, segment=2.0, speed=run.outputs["speed:motor"] / RPM
    )
    res = sg.resolution_hz
    order6 = 6 * sg.speed_rpm / 60
    for f in r.frequencies_hz[1:3]:
        far = np.abs(order6 - f) > 10
        assert np.median(ridge(sg, f - 3, f + 3)[far]) == pytest.approx(f, abs=0.1 * res)
    sel = (order6 > 20) & (order6 < 170) & (np.abs(order6 - r.frequencies_hz[2]) > 10)
    idx = np.flatnonzero(sel)
    line = np.array([ridge(sg, order6[i] - 3, order6[i] + 3)[i] for i in idx])
    speed = sg.speed_rpm[idx]
    slope, intercept = np.polyfit(speed / 60, line, 1)  # Hz per rev/s
    assert slope == pytest.approx(6.0, rel=1e-3)
    assert abs(intercept) < 0.2 * res
    assert np.max(np.abs(line - 6 * speed / 60)) < 0.2 * res


def test_cli_simulate_then_spectrum_round_trip(tmp_path, capsys):
    # simulate writes a CSV (time [s], NAME [unit]); spectrum reads it, finds the coupling torque's peaks,
    # gives each its order at the mean speed and the model's mode it sits on.
    model = str(EXAMPLES / "customer1.toml")
    csv = tmp_path / "run.csv"
    args = [
        "simulate",
        model,
        "--scenario",
        "ramp",
        "--end-speed",
        "600",
        "--ramp-time",
        "2",
        "--duration",
        "20",
    ]
    args += ["--measure", "torque:part 3", "--measure", "speed:motor", "--rate", "1000", "-o", str(csv)]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "ramp run" in out and str(csv) in out
    head = csv.read_text().splitlines()[0]
    assert head == "time [s],torque:part 3 [N·m],speed:motor [rad/s]"
    assert main(args) == 2  # no overwrite without --force
    assert "exists" in capsys.readouterr().err
    assert (
        main(
            ["spectrum", str(csv), "--column", "torque:part 3", "--speed-column", "speed:motor", "--json"]
            + ["--model", model, "--segment", "4"]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc["unit"] == "N·m" and doc["method"].startswith("stationary: hann")
    assert doc["mean_speed_rpm"] > 0
    # The ramp's start and stop ring mode 1 (the PI loop's own slow swing is the largest, lowest peak).
    (ring,) = [p for p in doc["peaks"] if p.get("mode") == 1]
    assert ring["frequency_hz"] == pytest.approx(ring["mode_frequency_hz"], abs=2 * doc["resolution_hz"])
    # JSON keeps every digit: f/(n/60) in another order, a few roundings
    assert ring["order"] == pytest.approx(ring["frequency_hz"] / (doc["mean_speed_rpm"] / 60), rel=1e-12)


def test_cli_spectrum_of_a_known_sine_and_bad_input(tmp_path, capsys):
    # A 3 N·m sine at 12.5 Hz (on a bin of a 4 s segment at 1 kHz): the amplitude-correct spectrum reads 3.
    t = np.arange(40000) / 1000.0
    path = tmp_path / "sine.csv"
    write_signals(path, t, {"torque": (3.0 * np.sin(2 * np.pi * 12.5 * t), "N·m")})
    assert main(["spectrum", str(path), "--column", "torque [N·m]", "--segment", "4", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["averages"] == 19  # 40 s in 4 s segments, 50 % overlap
    # The CSV keeps every float (shortest round-trip digits); on a bin only the FFTs' rounding is left,
    # ~eps·log2(4000) ≈ 3e-15 of the amplitude, and the vertex ~eps of a bin off: 1e-9 is loose.
    assert doc["peaks"][0]["frequency_hz"] == pytest.approx(12.5, abs=1e-9)
    assert doc["peaks"][0]["amplitude"] == pytest.approx(3.0, rel=1e-9)
    for bad, field in [
        (["--column", "nothing"], "nothing"),
        (["--column", "torque", "--decay", "--window", "hann"], "--window"),
        (["--column", "torque", "--window", "exponential"], "--window"),
        (["--column", "torque", "--segment", "100"], "segment"),
    ]:
        assert main(["spectrum", str(path), *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and field in err


def test_cli_spectrogram_plots(tmp_path, capsys):
    # A swept sine with a speed column: the spectrogram against speed, and against time.
    t = np.arange(20000) / 1000.0
    rpm = 300.0 + 60.0 * t
    angle = np.cumsum(rpm * RPM) / 1000.0
    path = tmp_path / "sweep.csv"
    write_signals(path, t, {"torque": (np.sin(2 * angle), "N·m"), "speed": (rpm * RPM, "rad/s")})
    for extra in (["--speed-column", "speed"], ["--spectrogram"]):
        png = tmp_path / f"s{len(extra)}.png"
        assert main(["spectrum", str(path), "--column", "torque", "--plot", str(png), *extra]) == 0
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()


def test_cli_csv_scenario_and_units_named_on_the_command_line(tmp_path, capsys):
    # A drive-torque history in kN·m without a unit in its header: --unit names it, and the run equals the
    # same history given in Python in N·m (the file's values are converted once, on reading).
    t = np.arange(0, 2.0, 0.001)
    history = 0.05 * (t > 0.1)  # 50 N·m from 0.1 s, written in kN·m
    path = tmp_path / "torque.csv"
    path.write_text("time,drive\n" + "\n".join(f"{a:.17g},{b:.17g}" for a, b in zip(t, history)) + "\n")
    out = tmp_path / "run.csv"
    model = str(EXAMPLES / "customer1.toml")
    args = ["simulate", model, "--scenario", "csv", "--series", str(path), "--column", "drive"]
    args += ["--measure", "torque:part 3", "--duration", "1.5", "-o", str(out)]
    assert main(args) == 2
    assert "--unit drive=UNIT" in capsys.readouterr().err
    assert main([*args, "--unit", "drive=kNm"]) == 0
    capsys.readouterr()
    got = fs.read_signals(out).columns["torque:part 3"]
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    ref = simulate(r, Scenario.from_series(t, 1e3 * history), ["torque:part 3"], duration=1.5)
    # The same run in one process; were the unit's factor an ulp off 1e3, this linear, damped response
    # would move by ~eps of its range: 1e-12 of it.
    np.testing.assert_allclose(got, ref.outputs["torque:part 3"], rtol=0, atol=1e-12 * np.ptp(got))
    assert main([*args, "--force", "--unit", "drive"]) == 2
    assert "COLUMN=UNIT" in capsys.readouterr().err

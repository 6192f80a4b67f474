"""analyse_signal, the one signal analysis of ``flexshaft spectrum`` and the study: against a closed-form
1-DOF free decay x = A·e^(−ξωt)·sin(ω_d t) (ξ = 0.0053) and a sine of known amplitude, and against
the command's own --json document."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.measurement.analyse import analyse_signal

XI, FN, RATE = 0.0053, 20.0, 1000.0
WN = 2 * math.pi * FN
FD = FN * math.sqrt(1 - XI**2)


def decay(seconds, *, amplitude=2.0):
    t = np.arange(int(round(seconds * RATE))) / RATE
    return t, amplitude * np.exp(-XI * WN * t) * np.sin(2 * math.pi * FD * t)


def test_a_free_decay_gives_its_damping_both_ways():
    t, x = decay(3.0)  # cut short (envelope e^(-2) at the end): the exponential window's case
    a = analyse_signal(t, x, name="torque", unit="N·m", decay=True, peaks=1)
    (p,) = a.peaks
    assert a.window == "exponential" and a.decay and a.rate_hz == pytest.approx(RATE)
    # The window fit: σ read to ~1e-3 from the windowed decay, 1/τ subtracted exactly, so ξ carries
    # ~4x that relative error (tests/flexshaft/measurement/test_decay.py); 1e-2 with margin.
    assert p["damping_ratio"] == pytest.approx(XI, rel=1e-2)
    # Log decrement: interpolated peaks of a sampled sine (50 samples a period), ratio fitted over the
    # record - read to 1e-3 as in tests/flexshaft/measurement/test_decay.py (the band leaves one mode).
    assert p["log_decrement_damping_ratio"] == pytest.approx(XI, rel=1e-3)
    # the window fit reads the damped frequency to a fraction of its 1/T = 0.33 Hz bin
    assert p["frequency_hz"] == pytest.approx(FD, abs=0.05)


def test_a_sine_s_amplitude_order_and_mode():
    t = np.arange(int(10 * RATE)) / RATE
    x = 3.0 * np.sin(2 * math.pi * 60.0 * t)  # 60 Hz: order 6 at 600 rpm
    speed = np.full(t.size, 600.0)
    a = analyse_signal(
        t,
        x,
        name="torque",
        unit="N·m",
        window="flattop",
        peaks=1,
        speed_rpm=speed,
        eigenfrequencies=[(1, 20.0), (2, 60.2)],
    )
    (p,) = a.peaks
    # the flat-top window's scalloping loss is below 0.01 dB (1.2e-3) anywhere in a bin
    assert p["amplitude"] == pytest.approx(3.0, rel=2e-3)
    assert p["frequency_hz"] == pytest.approx(60.0, abs=a.spectrum.resolution_hz)
    assert p["order"] == pytest.approx(6.0, abs=6.0 * a.spectrum.resolution_hz / 60.0)
    assert p["mode"] == 2 and p["mode_frequency_hz"] == 60.2  # within two bins (0.1 Hz each) or 1 %
    assert a.to_dict()["mean_speed_rpm"] == 600.0


@pytest.mark.parametrize(
    "options, field",
    [
        ({"decay": True, "window": "hann"}, "window"),
        ({"decay": True, "segment": 0.5}, "segment"),
        ({"window": "exponential"}, "window"),
        ({"speed_rpm": [600.0, 600.0]}, "speed_rpm"),
        ({"eigenfrequencies": [3.0]}, "eigenfrequencies"),
    ],
)
def test_options_that_do_not_go_together_name_the_argument(options, field):
    t, x = decay(1.0)
    with pytest.raises(ModelError) as err:
        analyse_signal(t, x, name="torque", unit="N·m", **options)
    assert err.value.field == field


def test_the_document_is_the_command_s(tmp_path, capsys):
    from flexshaft.measurement.signalfile import read_signals, write_signals

    t, x = decay(4.0)
    path = write_signals(tmp_path / "decay.csv", t, {"torque": (x, "N·m")})
    assert main(["spectrum", str(path), "--column", "torque", "--decay", "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    table = read_signals(path, columns=["torque"])
    a = analyse_signal(
        table.time, table.columns["torque"], name="torque", unit="N·m", source=table.source, decay=True
    )
    assert json.loads(json.dumps(a.to_dict())) == cli

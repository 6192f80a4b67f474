"""The band ``identify`` searches when none is given: it never drops a mode the model says is there.

The record is a Customer 1 coast stop simulated from ``examples/customer1.toml`` (``flexshaft simulate
--scenario coast``), so the model's modes are the independent reference: the identification, which
never sees the model's matrices, must find the two below 100 Hz (11.6 and 91.05 Hz) at them. Before the
band's low end came from the model it sat at max_hz/50 = 16 Hz (max_hz: 0.8 x Nyquist at 2 kHz) and
the bench's dominant first mode was silently left out.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.measurement.identify import (
    LOWEST_MODE_FRACTION,
    MIN_HZ_FRACTION,
    MIN_RECORD_PERIODS,
    default_min_hz,
    identify_modes,
)
from tests.conftest import EXAMPLES

MODEL = EXAMPLES / "customer1.toml"
CHANNEL = "torque:part 3"  # the coupling: the softest part, strained by both low modes


@pytest.fixture(scope="module")
def coast(tmp_path_factory):
    """A 30 s coast stop of Customer 1 at 2 kHz, the coupling's torque, as the simulate command writes it."""
    out = tmp_path_factory.mktemp("coast") / "coast.csv"
    args = ["simulate", str(MODEL), "--scenario", "coast", "--torque", "1000", "--speed", "600"]
    args += ["--measure", CHANNEL, "--duration", "30", "--rate", "2000", "-o", str(out)]
    assert main(args) == 0
    return out


@pytest.fixture(scope="module")
def model_modes():
    result = fs.modal_analysis(fs.load_model(MODEL))
    return [(i, f) for i, (f, r) in enumerate(zip(result.frequencies_hz, result.rigid)) if not r and f < 100]


def test_a_coast_stop_gives_both_modes_below_100_hz_with_default_options(coast, model_modes, capsys):
    assert main(["identify", str(coast), "--channel", CHANNEL, "--model", str(MODEL), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    (first_hz,) = [f for i, f in model_modes if i == 1]
    # the low end: half the model's first elastic mode, and it says so
    assert doc["min_hz"] == pytest.approx(LOWEST_MODE_FRACTION * first_hz, rel=1e-12)
    assert doc["band_reason"] == f"from the model's first mode, {first_hz:.4g} Hz"
    pairs = {p["mode"]: p for p in doc["pairing"]["pairs"] if p["mode"] is not None}
    assert len(model_modes) == 2
    for index, f_model in model_modes:
        p = pairs[index]
        # within the identification's own stated accuracy: the targets' tolerance (three times the
        # relative scatter, at least 0.1 %)
        assert abs(p["frequency_hz"] / f_model - 1) <= p["tolerance"]
    # the library's default is the command's: the CLI passes None
    lib = fs.identify([coast], [CHANNEL], model=MODEL)
    assert lib.identification.min_hz == doc["min_hz"] and lib.identification.max_hz == doc["max_hz"]


def test_the_table_says_the_band_in_one_line_and_the_method_only_when_verbose(coast, model_modes, capsys):
    args = ["identify", str(coast), "--channel", CHANNEL, "--model", str(MODEL)]
    assert main(args) == 0
    out = capsys.readouterr().out
    (first_hz,) = [f for i, f in model_modes if i == 1]
    low = LOWEST_MODE_FRACTION * first_hz
    assert out.splitlines()[0] == f"band {low:.3g} … 800 Hz (from the model's first mode, {first_hz:.4g} Hz)"
    assert "SSI-COV" not in out
    # a mode the model has is not suggested to be a harmonic, however lightly damped (the model's first
    # mode: 0.0069 %)
    assert "harmonic" not in out and "the model has mode 1 there" in out
    assert main([*args, "--verbose"]) == 0
    verbose = capsys.readouterr().out
    assert verbose.startswith("covariance-driven stochastic subspace identification (SSI-COV")
    assert f"band {low:.3g} … 800 Hz" in verbose


def _noise(seconds: float, rate: float):
    t = np.arange(int(seconds * rate)) / rate
    return t, {"a": np.random.default_rng(0).standard_normal(t.size)}, {"a": "N·m"}


def test_without_a_model_the_low_end_is_what_the_record_resolves():
    # 3 s: 20 periods must fit in the record, 20/3 = 6.67 Hz, above max_hz / 50 = 2 Hz (which the record
    # could not identify: before, it was refused)
    run = _noise(3.0, 1000.0)
    assert default_min_hz([run], 100.0) == (
        pytest.approx(MIN_RECORD_PERIODS / 3.0),
        f"from the record's length, {MIN_RECORD_PERIODS} periods in 3 s",
    )
    # 100 s: the record resolves 0.2 Hz; max_hz / 50 as ever, and the reason says why so high
    low, why = default_min_hz([_noise(100.0, 1000.0)], 100.0)
    assert low == pytest.approx(MIN_HZ_FRACTION * 100.0)
    assert why == "max_hz / 50: no model to say where the first mode is"
    # a model's first mode below what the record holds: the record's limit, and the reason says the mode
    # is out of reach
    low, why = default_min_hz([_noise(3.0, 1000.0)], 100.0, lowest_mode_hz=5.0)
    assert low == pytest.approx(MIN_RECORD_PERIODS / 3.0)
    assert "the model's first mode, 5 Hz, below it" in why


def test_the_default_band_is_used_and_stated():
    found = identify_modes([_noise(3.0, 1000.0)], max_hz=100.0)
    assert math.isclose(found.min_hz, MIN_RECORD_PERIODS / 3.0)
    assert found.band == "band 6.67 … 100 Hz (from the record's length, 20 periods in 3 s)"
    given = identify_modes([_noise(3.0, 1000.0)], max_hz=100.0, min_hz=10.0)
    assert given.band == "band 10 … 100 Hz (given)"

"""Operational modal identification (SSI-COV): exact poles of noise-free free decays, the statistical
accuracy on an exactly simulated operational run of a free three-inertia line, the spread over runs and
segments, and the errors on bad input.

References: the poles and shapes of the systems below are exact (``scipy.linalg.eigh`` on (K, M), or
given); the operational run is simulated from first principles by ``examples/operational_run.py``
(modal decomposition, zero-order-hold discretisation: exact at the samples), not by flexshaft. The
estimator's random error on a damping ratio ζ of a mode at f from a record of T seconds is about
std(ζ)/ζ ≈ 1/√(π·ζ·f·T) (Brincker & Ventura 2015); 30 simulated 300 s runs of the example line gave
5.0 % (mode 1, 35.5 Hz; the formula 7.5 %) and 5.2 % (mode 2, 138.2 Hz; the formula 3.8 %), and 40 runs
of 60 s gave 14.6 % and 9.4 % (16.8 % and 8.5 %): the formula holds within a factor 1.4.
"""

from __future__ import annotations

import json
import math
import runpy

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from flexshaft.errors import ModelError
from flexshaft.linalg.mac import mac
from flexshaft.measurement.fdd import spectral_matrix
from flexshaft.measurement.identify import Run, identify_modes
from flexshaft.measurement.ssi import correlations, mpc, ssi_poles
from tests.conftest import EXAMPLES

EXAMPLE = runpy.run_path(str(EXAMPLES / "operational_run.py"))
TORQUES, SPEEDS = EXAMPLE["TORQUES"], EXAMPLE["SPEEDS"]
TRUTH = EXAMPLE["true_modes"]()
F_TRUE, ZETA_TRUE = TRUTH["frequencies_hz"], EXAMPLE["DAMPING_RATIO"]


def relative_damping_std(f_hz: float, seconds: float) -> float:
    """The estimator's relative standard deviation of ζ, 1/√(π·ζ·f·T), times 1.4: the most the
    simulations above exceeded the formula by."""
    return 1.4 / math.sqrt(math.pi * ZETA_TRUE * f_hz * seconds)


# --- the algorithm's parts, exactly ------------------------------------------------------------------


def test_correlations_are_the_direct_sums():
    rng = np.random.default_rng(5)
    y = rng.standard_normal((3, 20011))
    lags = 57
    got = correlations(y, lags, references=[0, 2])
    n = y.shape[1]
    direct = np.array([y[:, k:] @ y[[0, 2], : n - k].T for k in range(lags + 1)]) / n
    # the same products summed in another order (FFT blocks): round-off, ~eps·√N relative to the sums
    assert got.shape == (lags + 1, 3, 2)
    np.testing.assert_allclose(got, direct, rtol=0, atol=1e-12)


def test_ssi_poles_of_exact_correlations_are_the_systems_poles():
    # R_k = C·A^(k-1)·G exactly (a system of order 4: two modes), so the Toeplitz matrix is of rank 4
    # and its SVD and shift give a matrix similar to A: its poles to round-off (eigenvalues of a
    # well-separated pair; relative error ~1e-13 observed, 1e-9 asserted).
    fs = 200.0
    poles = np.array(
        [-0.02 * 2 * np.pi * 7.0 + 2j * np.pi * 7.0 * math.sqrt(1 - 0.02**2), -1.5 + 2j * np.pi * 31.0]
    )
    mu = np.exp(np.concatenate([poles, poles.conj()]) / fs)
    rng = np.random.default_rng(1)
    v = rng.standard_normal((4, 4)) + 1j * rng.standard_normal((4, 4))
    v[:, 2:] = v[:, :2].conj()  # a real system: conjugate eigenvectors for conjugate poles
    a = (v @ np.diag(mu) @ np.linalg.inv(v)).real
    c = rng.standard_normal((3, 4))
    g = rng.standard_normal((4, 3))
    i = 12
    corr = np.array([c @ np.linalg.matrix_power(a, max(k - 1, 0)) @ g for k in range(2 * i + 1)])
    (order4,) = ssi_poles(corr, fs, [4], i)
    want_f = np.abs(poles) / (2 * np.pi)
    want_z = -poles.real / np.abs(poles)
    k = np.argsort(order4.frequency_hz)
    np.testing.assert_allclose(order4.frequency_hz[k], want_f, rtol=1e-9)
    np.testing.assert_allclose(order4.damping_ratio[k], want_z, rtol=1e-9)
    # the shapes: C times A's eigenvectors
    for j, kk in enumerate(k):
        assert mac(order4.shapes[:, kk], c @ v[:, j]) == pytest.approx(1.0, abs=1e-9)


def test_the_spectral_matrix_is_welchs_cross_spectrum():
    # scipy.signal.csd (Hann, half overlap, mean removed per segment) is the mean over segments of
    # conj(X_a)·X_b, scaled by 2/(fs·Σw²) off DC and Nyquist: ours is Σ X_a·conj(X_b), so the ratio is
    # one constant (segments·fs·Σw²/2) - to round-off
    rng = np.random.default_rng(2)
    y = rng.standard_normal((2, 5000))
    f, g = spectral_matrix(y, 100.0, 256)
    fs, pxy = scipy.signal.csd(y[0], y[1], fs=100.0, window="hann", nperseg=256, noverlap=128)
    np.testing.assert_allclose(f, fs)
    ratio = g[1:-1, 0, 1] / np.conj(pxy[1:-1])
    np.testing.assert_allclose(ratio, ratio[0].real, rtol=1e-9)
    np.testing.assert_allclose(g, np.conj(g.transpose(0, 2, 1)))  # Hermitian per frequency


def test_mac_and_mpc():
    assert mac([1.0, 2.0], [-2.0, -4.0]) == pytest.approx(1.0)
    assert mac([1.0, 0.0], [0.0, 1.0]) == 0.0
    assert mpc(np.array([1.0, -0.5, 0.2]) * np.exp(0.7j)) == pytest.approx(1.0)  # one phase: a normal mode
    assert mpc([1.0, 1j]) == pytest.approx(0.0)  # components in quadrature, equal: no common phase


# --- noise-free free decays: exact poles through the whole pipeline ------------------------------------
#
# A free decay is a sum of decaying exponentials e^(λt), and every step before SSI keeps it one: the
# detrend subtracts a line (a double pole at z = 1), the decimation's FIR filter adds a transient of
# finite length (poles at z = 0), the zero-phase high-pass its own exponentials (below min_hz). So the
# correlations are exactly C·A^(k-1)·G of a finite state once the decay has died out (e^(-ζωT) < 1e-16
# here), and every model order above the state's finds the true λ: no statistical error, only round-off
# (observed 1e-13 relative; the damping ratio, -Re λ/|λ|, is the pole's small real part, so it may lose
# a further factor 1/(ζ·ω·dt) ~ 100 to cancellation). Asserted: 1e-8 on frequency, 1e-6 on damping.


def decay_time(seconds: float, rate: float) -> np.ndarray:
    return np.arange(int(round(seconds * rate))) / rate


def test_a_single_mode_free_decay_gives_its_pole():
    t = decay_time(60.0, 1000.0)
    fn, zeta = 10.0, 0.02
    wn = 2 * np.pi * fn
    x = 5.0 + np.exp(-zeta * wn * t) * np.cos(wn * math.sqrt(1 - zeta**2) * t + 0.3)  # on a static torque
    # not cut into segments: a decay is not stationary (its halves' RMS differ 1e5-fold), which a note says
    found = identify_modes([(t, {"torque": x}, {"torque": "N·m"})], max_hz=50.0)
    assert found.runs[0].segments == 1 and "not stationary" in found.notes[0]
    (mode,) = found.modes
    assert mode.frequency_hz == pytest.approx(fn, rel=1e-8)
    assert mode.damping_ratio == pytest.approx(zeta, rel=1e-6)
    # one channel: its shape is its largest component, 1 up to the round-off of scaling the channel to
    # unit standard deviation and back (1 ulp under one BLAS kernel)
    assert mode.shape == {"torque": pytest.approx(1.0, abs=1e-12)}
    assert mode.found_in_runs == 1 and math.isnan(mode.frequency_std_hz)  # one run: no spread across runs


def line_decay(seconds: float, rate: float, zeta: float, v0: float = 10.0):
    """The example line's free decay after a blow to inertia 1 (initial speed v0 rad/s), exactly:
    θ = Σ φ_r q_r with q_r = φ_r[0]·J1·v0 · e^(-ζωt)·sin(ω_d t)/ω_d, the rigid mode q_0 = φ_0[0]·J1·v0·t."""
    m, k = EXAMPLE["line_matrices"]()
    w2, phi = scipy.linalg.eigh(k, m)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    t = decay_time(seconds, rate)
    q0 = phi[0] * m[0, 0] * v0  # initial modal rates
    q = np.empty((3, t.size))
    qd = np.empty((3, t.size))
    q[0], qd[0] = q0[0] * t, q0[0]
    for r in (1, 2):
        wd = omega[r] * math.sqrt(1 - zeta**2)
        env = np.exp(-zeta * omega[r] * t)
        q[r] = q0[r] * env * np.sin(wd * t) / wd
        qd[r] = q0[r] * env * (np.cos(wd * t) - zeta * omega[r] / wd * np.sin(wd * t))
    theta, speed = phi @ q, phi @ qd
    k1, k2 = EXAMPLE["STIFFNESSES"]
    columns = {"torque s1": k1 * (theta[0] - theta[1]), "torque s2": k2 * (theta[1] - theta[2])}
    columns |= {f"speed {j + 1}": speed[j] for j in range(3)}
    units = {n: ("N·m" if n.startswith("torque") else "rad/s") for n in columns}
    return t, columns, units, omega[1:] / (2 * np.pi), phi[:, 1:]


def test_a_two_mode_free_decay_gives_its_poles_and_real_shapes():
    zeta = 0.02
    t, columns, units, f, phi = line_decay(10.0, 2000.0, zeta)  # e^(-ζω₁T) = 4e-20 at the end
    found = identify_modes(Run(t, columns, units), max_hz=200.0, segments=1)
    assert len(found.modes) == 2
    np.testing.assert_allclose(found.frequencies_hz, f, rtol=1e-8)
    np.testing.assert_allclose(found.damping_ratios, zeta, rtol=1e-6)
    k1, k2 = EXAMPLE["STIFFNESSES"]
    for mode, f_r, shape in zip(found.modes, f, phi.T, strict=True):
        # every channel shares one phase: the speeds turned back by λ's (they lead their angles by
        # ~90°, the torques follow the angles); the real shape is then exact, speeds at ω times the
        # angles' scale, with the rigid spin (a constant speed) taken out by the detrend
        want = np.concatenate(
            [[k1 * (shape[0] - shape[1]), k2 * (shape[1] - shape[2])], 2 * np.pi * f_r * shape]
        )
        want = want / want[np.argmax(np.abs(want))]
        got = np.array([mode.shape[n] for n in found.channels])
        np.testing.assert_allclose(got, want, atol=1e-8)
        assert mode.mpc == pytest.approx(1.0, abs=1e-9)


# --- the operational run: statistics --------------------------------------------------------------------


@pytest.fixture(scope="module")
def long_run():
    """The example's run: 300 s at 2 kHz, 2 % sensor noise, seed 1."""
    time, columns, units, _ = EXAMPLE["operational_run"](seed=1, duration=300.0)
    return time, columns, units


@pytest.mark.parametrize("names", [TORQUES, SPEEDS], ids=["torques", "speeds"])
def test_an_operational_run_gives_both_elastic_modes(long_run, names):
    found = identify_modes([long_run], channels=names, max_hz=200.0)
    # exactly the two elastic modes: the rigid spin (the speeds' drift) is high-passed and below min_hz,
    # and what the high model orders fit to noise is not reproduced by the segments
    assert len(found.modes) == 2
    for mode, f in zip(found.modes, F_TRUE, strict=True):
        # frequency: the relative std, about √(ζ/(π·f·T)) (ζ times the damping's relative std), is 4e-4
        # and 2e-4 (3e-4 and 2e-4 observed over 30 runs): 0.3 % is > 7σ
        assert mode.frequency_hz == pytest.approx(f, rel=3e-3)
        # damping: σ is 7.5 % for mode 1 (the formula; 5.0 % observed) and 5.2 % for mode 2 (observed;
        # the formula 3.8 %): 30 % is 4.0σ and 5.8σ
        assert mode.damping_ratio == pytest.approx(ZETA_TRUE, rel=0.30)
        assert mode.found_in_runs == 1 and mode.found_in_segments > mode.segments / 2
        # the FDD cross-check: s₁'s peak in a Welch estimate of ~55 averages, bins a quarter of the
        # half-power band 2ζf wide, moves by a fraction of a bin with the estimate's scatter (±14 % per
        # bin): within ζ·f (two bins) of the mode, its singular vector the mode's shape
        assert abs(mode.fdd_frequency_hz - f) <= ZETA_TRUE * f
        assert mode.fdd_mac > 0.99
    assert found.runs[0].decimated_rate_hz == 1000.0 and found.runs[0].segments == 5  # 60 s ≥ 10/(ζ·f₁)
    if names == SPEEDS:
        for mode, shape in zip(found.modes, TRUTH["speed_shapes"].T, strict=True):
            got = np.array([mode.shape[n] for n in SPEEDS])
            # the shape's error is the noise's share at the mode (2 % noise, a resonant peak far above):
            # 1 − MAC of order 1e-4 at worst; 0.99 leaves a wide margin
            assert mac(got, shape) > 0.99
            assert mode.mpc > 0.99


def test_the_result_is_json_with_its_diagrams(long_run):
    found = identify_modes([long_run], channels=TORQUES, max_hz=200.0, orders=40, segments=2)
    doc = json.loads(json.dumps(found.to_dict(), allow_nan=False))
    assert doc["units"]["damping_ratio"] == "fraction" and doc["units"]["frequency"] == "Hz"
    assert doc["method"].startswith("covariance-driven stochastic subspace identification (SSI-COV")
    assert doc["orders"] == list(range(2, 41, 2))
    assert len(doc["modes"]) == 2 and doc["modes"][0]["frequency_std_hz"] is None  # one run
    assert doc["modes"][0]["segments"] == 2
    (diagram,) = found.diagrams
    # each mode's poles in the diagram: stable and physical, at the mode's frequency within 1 %
    for m, mode in enumerate(found.modes):
        at = diagram.mode == m
        assert at.sum() == mode.stable_poles
        assert np.all(diagram.stable[at] & diagram.physical[at])
        np.testing.assert_allclose(diagram.frequency_hz[at], mode.frequency_hz, rtol=0.01)


# --- several runs: the spread ---------------------------------------------------------------------------


def test_several_runs_give_the_spread_that_holds_the_truth():
    seconds = 60.0
    runs = []
    for seed in (21, 22, 23, 24):
        time, columns, units, _ = EXAMPLE["operational_run"](seed=seed, duration=seconds)
        runs.append(
            Run(time, {n: columns[n] for n in TORQUES}, {n: units[n] for n in TORQUES}, f"seed {seed}")
        )
    found = identify_modes(runs, max_hz=200.0, segments=4)  # 16 segments of 15 s
    assert len(found.modes) == 2 and [r.source for r in found.runs] == [
        "seed 21",
        "seed 22",
        "seed 23",
        "seed 24",
    ]
    for mode, f in zip(found.modes, F_TRUE, strict=True):
        assert mode.found_in_runs == 4 and mode.segments == 16 and mode.found_in_segments > 8
        assert mode.frequency_hz == pytest.approx(np.mean(mode.run_frequencies_hz))
        assert mode.damping_ratio == pytest.approx(np.mean(mode.run_damping_ratios))
        # the truth within the range of 16 segments' and 4 runs' estimates: were they unbiased and
        # independent, it would lie outside with probability 2·2^-16 ≈ 3e-5 (the biased correlation adds
        # ζ·1/(ζ·ω·T) ≈ 6 % of ζ to a 15 s segment, against a scatter of 1.4/√(π·ζ·f·T) ≈ 48 %)
        lo, hi = mode.frequency_range_hz
        assert lo <= f <= hi
        lo, hi = mode.damping_range
        assert lo <= ZETA_TRUE <= hi
        # the spread across runs is the estimator's: the sample std of 4 runs lies within
        # [0.07, 2.43]·σ with probability 99.9 % (χ² with 3 degrees of freedom); σ from the formula,
        # between 1/1.4 and 1 times the relative_damping_std
        sigma = relative_damping_std(f, seconds) * ZETA_TRUE
        assert 0.07 * sigma / 1.4 <= mode.damping_std <= 2.43 * sigma
        # the mean of 4 runs within 4 of its standard deviations, σ/√4
        assert abs(mode.damping_ratio - ZETA_TRUE) <= 4 * sigma / 2
        assert mode.segment_damping_std > 0 and mode.segment_frequency_std_hz > 0


def test_a_harmonic_is_noted(long_run):
    # an 80 Hz order of the shaft speed on both torques: a pole of (almost) no damping, which the
    # identification reports with a note
    time, columns, units = long_run
    n = 120_000  # 60 s
    tone = 20.0 * np.sin(2 * np.pi * 80.0 * time[:n])
    cols = {name: columns[name][:n] + tone for name in TORQUES}
    found = identify_modes([(time[:n], cols, units)], max_hz=200.0)
    harmonic = [m for m in found.modes if abs(m.frequency_hz - 80.0) < 0.01]
    assert len(harmonic) == 1 and harmonic[0].damping_ratio < 1e-4
    assert any(f"{harmonic[0].frequency_hz:.6g} Hz" in note and "harmonic" in note for note in found.notes)


def test_a_signal_table_is_a_run(long_run):
    from flexshaft.measurement.signalfile import SignalTable

    time, columns, units = long_run
    n = 120_000  # 60 s
    table = SignalTable(
        time=time[:n],
        columns={k: v[:n] for k, v in columns.items()},
        units=units,
        rate_hz=2000.0,
        source="x.csv",
    )
    found = identify_modes(table, channels=["speed 1", "speed 3"], references=["speed 1"], max_hz=200.0)
    assert found.references == ("speed 1",) and found.runs[0].source == "x.csv"
    # 60 s make two segments: a noise pole the whole record's high orders fit recurs in one of them
    # (1 of 2: the vote is undecided) - it may be listed, but only as doubtful, never as a target
    trusted = [m.frequency_hz for m in found.modes if not m.frequency_doubt]
    np.testing.assert_allclose(trusted, F_TRUE, rtol=3e-3)
    for m in found.modes:
        if m.frequency_doubt:
            assert m.found_in_segments == 1 and m.segments == 2 and "too few to confirm" in m.frequency_doubt


# --- bad input ------------------------------------------------------------------------------------------


def short_run(seconds=10.0, rate=1000.0):
    t = np.arange(int(seconds * rate)) / rate
    rng = np.random.default_rng(0)
    return t, {"a": rng.standard_normal(t.size), "b": rng.standard_normal(t.size)}, {"a": "N·m", "b": "rad/s"}


def test_bad_runs_are_one_error_naming_the_argument():
    t, cols, units = short_run()
    cases = [
        (lambda: identify_modes([], max_hz=100.0), "runs", "at least one run"),
        (lambda: identify_modes([(t, {}, {})], max_hz=100.0), "runs[0].columns", "non-empty"),
        (
            lambda: identify_modes([(t, cols, units), (t, {"a": cols["a"]}, units)], max_hz=100.0),
            "runs[1].columns",
            "same channels",
        ),
        (
            lambda: identify_modes([(t, cols, units)], channels=["c"], max_hz=100.0),
            "channels",
            "channels of every run",
        ),
        (lambda: identify_modes([(t, cols, {"a": "N·m"})], max_hz=100.0), "runs[0].units['b']", "SI unit"),
        (
            lambda: identify_modes([(t, cols, units), (t, cols, {"a": "N·m", "b": "rpm"})], max_hz=100.0),
            "runs[1].units['b']",
            "same unit",
        ),
        (
            lambda: identify_modes([(t, cols | {"a": np.where(t > 5, np.nan, 1.0)}, units)], max_hz=100.0),
            "runs[0].columns['a']",
            "finite",
        ),
        (lambda: identify_modes([(t, cols, units)], max_hz=600.0), "max_hz", "below 500 Hz"),
        (lambda: identify_modes([(t, cols, units)], max_hz=100.0, min_hz=1.0), "runs[0]", "at least 20 s"),
        (lambda: identify_modes([(t, cols, units)], max_hz=100.0, min_hz=200.0), "min_hz", "below 100 Hz"),
        (lambda: identify_modes([(t[::-1], cols, units)], max_hz=100.0), "runs[0].time", "increasing"),
        (lambda: identify_modes([(t, cols, units)], max_hz=100.0, orders=7), "orders", "even"),
        (lambda: identify_modes([(t, cols, units)], max_hz=100.0, references=["c"]), "references", "one of"),
        (lambda: identify_modes([(t, cols, units)], max_hz=100.0, segments=50), "segments", "at most"),
        (lambda: identify_modes([(t, cols, units)], max_hz=-1.0), "max_hz", "> 0"),
        (lambda: identify_modes([(t, cols)], max_hz=100.0), "runs[0]", "a Run"),
        (
            lambda: identify_modes([(t, cols | {"b": cols["b"][:-1]}, units)], max_hz=100.0),
            "runs[0].columns['b']",
            "one sample per time",
        ),
        (
            lambda: identify_modes([(t, cols | {"b": np.zeros(t.size)}, units)], max_hz=100.0),
            "runs[0].columns['b']",
            "vibrates",
        ),
    ]
    for call, field, valid in cases:
        with pytest.raises(ModelError) as err:
            call()
        assert err.value.field == field, (field, str(err.value))
        assert valid in str(err.value), (valid, str(err.value))


def test_too_short_a_record_names_its_length_and_what_is_needed():
    t, cols, units = short_run(seconds=3.0)
    with pytest.raises(
        ModelError,
        match=r"runs\[0\] = 3\.0 s: is too short for min_hz = 2 Hz; valid: a record of at least 10 s",
    ):
        identify_modes([(t, cols, units)], max_hz=100.0, min_hz=2.0)


def test_a_toeplitz_matrix_beyond_the_ceiling_is_refused_before_it_is_built(monkeypatch):
    # lags over half a period of min_hz: i = 0.5·rate/min_hz block rows at the decimated rate, the
    # matrix i·channels rows (its SVD the cube of that). 50 s at 2 kHz with max_hz = 400 Hz stays at
    # 2 kHz (5·max_hz); min_hz = 0.4 Hz (the record holds its 20 periods) asks for 2500 block rows of
    # 2 channels: 5000 rows, past the ceiling's 4000
    t, cols, units = short_run(seconds=50.0, rate=2000.0)
    with pytest.raises(ModelError, match="FLEXSHAFT_MAX_SSI_ROWS") as e:
        identify_modes([(t, cols, units)], max_hz=400.0, min_hz=0.4)
    assert e.value.field == "min_hz" and "5000 rows" in str(e.value)
    # the ceiling is the environment's for one run: 10 s at 1 kHz, max_hz 100 Hz (decimated to 500 Hz)
    # and its default min_hz 2 Hz need 125 block rows, 250 rows - past a ceiling of 100
    t, cols, units = short_run()
    monkeypatch.setenv("FLEXSHAFT_MAX_SSI_ROWS", "100")
    with pytest.raises(ModelError, match="250 rows"):
        identify_modes([(t, cols, units)], max_hz=100.0)

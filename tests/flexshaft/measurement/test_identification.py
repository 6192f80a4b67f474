"""From the bench's files to the calibrated model: ``flexshaft identify`` and :func:`flexshaft.identify`
on a synthetic operational run written as TDMS, MDF 4 and CSV, its targets file, and ``calibrate`` on it.

The run is ``examples/operational_run.py``'s: a free three-inertia line (0.53 % damping on both elastic
modes) driven by random torque, 300 s at 2 kHz with 2 % sensor noise, simulated from first principles
(numpy and scipy, not flexshaft's models). The truth the tests compare with is that script's:
the elastic frequencies from ``scipy.linalg.eigh`` on its own (K, M), the speeds' shapes its
eigenvectors, the stiffnesses it was simulated with. The model the identified modes are paired with,
and calibrated, starts 10 % off in both stiffnesses.
"""

from __future__ import annotations

import json
import math
import runpy
import tomllib

import numpy as np
import pytest
import scipy.linalg

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.linalg.mac import mac
from flexshaft.measurement.pairing import MIN_DAMPING_TOLERANCE, MIN_MAC, PAIR_WINDOW, pair_modes
from tests.conftest import EXAMPLES

EXAMPLE = runpy.run_path(str(EXAMPLES / "operational_run.py"))
TRUTH = EXAMPLE["true_modes"]()
F_TRUE = TRUTH["frequencies_hz"]
ZETA_TRUE = EXAMPLE["DAMPING_RATIO"]
K_TRUE = EXAMPLE["STIFFNESSES"]
TORQUES, SPEEDS = EXAMPLE["TORQUES"], EXAMPLE["SPEEDS"]
#: The model before calibration: k1 10 % low, k2 10 % high (its modes 0.4 % and 0.9 % off the truth).
K_START = (0.9 * K_TRUE[0], 1.1 * K_TRUE[1])
STATIONS = ("inertia 1", "inertia 2", "inertia 3")
FORMATS = (".tdms", ".mf4", ".csv")


def _model_text(k1: float, k2: float) -> str:
    text = EXAMPLE["model_text"]()
    for true, start in zip(K_TRUE, (k1, k2), strict=True):
        assert f"stiffness = {true!r}" in text
        text = text.replace(f"stiffness = {true!r}", f"stiffness = {start!r}")
    return text


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """The run as a data logger writes it (TDMS, MDF 4) and as CSV, with the model 10 % off."""
    out = tmp_path_factory.mktemp("bench")
    time, columns, units, _ = EXAMPLE["operational_run"](seed=1, duration=300.0)
    data = {name: (x, units[name]) for name, x in columns.items()}
    fs.write_signals(out / "run.csv", time, data)
    fs.write_measured(out / "run.tdms", time, data)
    fs.write_measured(out / "run.mf4", time, data)
    (out / "start.toml").write_text(_model_text(*K_START), encoding="utf-8")
    return out


def _identify(capsys, *argv) -> tuple[int, str, str]:
    code = main(["identify", *map(str, argv)])
    got = capsys.readouterr()
    return code, got.out, got.err


def _channel_args(names, stations=False) -> list[str]:
    args = [a for n in names for a in ("--channel", n)]
    if stations:
        args += [a for n, s in zip(names, STATIONS, strict=True) for a in ("--station", f"{n}={s}")]
    return args


@pytest.mark.parametrize(
    "suffix,names",
    # the torques from every format; the speeds (with the rigid-body drift, mapped to the stations) from
    # one: the readers give the same floats (tests/flexshaft/measurement/test_measured.py), the library test
    # below identifies the speeds of the MDF 4 file
    [*((s, TORQUES) for s in FORMATS), (".csv", SPEEDS)],
    ids=[*(f"torques{s}" for s in FORMATS), "speeds.csv"],
)
def test_identify_writes_the_targets_calibrate_recovers_the_true_stiffnesses_from(
    bench, tmp_path, capsys, suffix, names
):
    speeds = names == SPEEDS
    targets = tmp_path / "targets.toml"
    run = bench / f"run{suffix}"
    args = [run, *_channel_args(names, stations=speeds), "--model", bench / "start.toml", "-o", targets]
    code, out, err = _identify(capsys, *args)
    assert code == 0, err
    assert f"targets written to {targets}" in out
    # the band in one line first, its low end half the model's first mode (35.62 Hz: 10 % off the
    # truth's 35.48); the method paragraph only with --verbose
    assert out.splitlines()[0].startswith("band 17.8 … ") and "from the model's first mode" in out
    assert "SSI-COV" not in out
    doc = tomllib.loads(targets.read_text(encoding="utf-8"))
    found = doc["target"]
    # both elastic modes, numbered as `flexshaft modes` numbers them (mode 0 is the free line's spin)
    assert [t["mode"] for t in found] == [1, 2]
    for t, f in zip(found, F_TRUE, strict=True):
        # the tolerances of tests/flexshaft/measurement/test_identify.py: frequency within 0.3 % (> 7σ of
        # the estimator's scatter at 300 s), damping within 30 % (> 4σ); the file's values are the
        # identification's, written with repr (no rounding)
        assert t["frequency_hz"] == pytest.approx(f, rel=3e-3)
        assert t["damping_ratio"] == pytest.approx(ZETA_TRUE, rel=0.30)
        # the target tolerance is three times the segments' relative scatter, at least 0.1 %: the
        # truth lies inside it (the scatter of a 60 s segment is √5 that of the whole run)
        assert abs(t["frequency_hz"] / f - 1) <= t["tolerance"]
        # twice the damping's relative scatter, never below the floor nor above 0.9 (the pairing's rule)
        assert MIN_DAMPING_TOLERANCE <= t["damping_tolerance"] <= 0.9
        if speeds:
            # every station measured: the shape at the model's stations; the speeds' shapes are the
            # angles' (a speed is iω times its angle), 2 % noise leaves 1 − MAC ~1e-4
            assert len(t["shape"]) == 3
        else:
            assert "shape" not in t
    if speeds:
        for t, shape in zip(found, TRUTH["speed_shapes"].T, strict=True):
            assert mac(np.array(t["shape"]), shape) > 0.99

    # the user adds two stiffness parameters; the damping ratios are compared, not tuned
    targets.write_text(
        targets.read_text(encoding="utf-8")
        + '\n[[parameter]]\nname = "s1.stiffness"\npercent = 30\n'
        + '\n[[parameter]]\nname = "s2.stiffness"\npercent = 30\n',
        encoding="utf-8",
    )
    assert main(["calibrate", str(bench / "start.toml"), "--targets", str(targets), "--json"]) == 0
    (result,) = json.loads(capsys.readouterr().out)["stages"]  # one stage: the file's problem
    tuned = {p["name"]: p["tuned"] for p in result["parameters"]}
    # the demand, 1 %: the frequencies are met to round-off (cost ~1e-25), so the stiffnesses
    # carry the identified frequencies' errors (≤ 0.1 % observed, k ∝ f² locally) times the 2x2 map's
    # conditioning (the line's modes are each dominated by one shaft: about 2)
    assert tuned["s1.stiffness"] == pytest.approx(K_TRUE[0], rel=0.01)
    assert tuned["s2.stiffness"] == pytest.approx(K_TRUE[1], rel=0.01)
    assert all(t["met"] for t in result["targets"])
    assert [t["mode"] for t in result["damping_targets"]] == [1, 2]
    assert "damping ratios compared, not tuned" in result["message"]


def test_the_library_call_reads_pairs_and_writes_the_targets(bench, tmp_path):
    res = fs.identify(
        bench / "run.mf4", SPEEDS, model=bench / "start.toml", stations=dict(zip(SPEEDS, STATIONS))
    )
    assert isinstance(res, fs.ModelIdentification)
    assert [p.mode for p in res.pairing.pairs] == [1, 2]
    # the default band: the model's highest elastic mode and half as much again (below 80 % of Nyquist)
    start = fs.modal_analysis(fs.load_model(bench / "start.toml"))
    assert res.identification.max_hz == pytest.approx(1.5 * start.frequencies_hz[2])
    for p in res.pairing.pairs:
        assert p.model_frequency_hz == pytest.approx(start.frequencies_hz[p.mode])
        # the model 10 % off still has the measured shapes (0.995 and 1.000 observed)
        assert p.mac >= MIN_MAC
    doc = json.loads(res.to_json())  # what `identify --json` prints
    assert [p["mode"] for p in doc["pairing"]["pairs"]] == [1, 2]
    assert [m["frequency_hz"] for m in doc["modes"]] == [m.frequency_hz for m in res.modes]
    written = tomllib.loads(res.write_targets(tmp_path / "t.toml").read_text(encoding="utf-8"))["target"]
    assert [t["frequency_hz"] for t in written] == [m.frequency_hz for m in res.modes]  # repr: exact
    with pytest.raises(ModelError, match="file exists"):
        res.write_targets(tmp_path / "t.toml")  # not replaced without overwrite
    with pytest.raises(ModelError, match="numbers modes as the model does"):
        fs.ModelIdentification(res.identification).targets_toml()  # no model: no mode numbers


# --- the pairing's rules, on a model with known modes ---------------------------------------------


class _Found:
    """What pair_modes reads of an identification: modes with frequency, shape and spread."""

    def __init__(self, freqs, shapes=None, units=None):
        self.channels = tuple(units or ("torque s1",))
        self.units = dict(units or {"torque s1": "N·m"})
        shapes = shapes or [dict.fromkeys(self.channels, 1.0)] * len(freqs)
        self.modes = tuple(_Mode(f, s) for f, s in zip(freqs, shapes, strict=True))


class _Mode:
    def __init__(self, f, shape):
        self.frequency_hz, self.damping_ratio, self.shape = f, 0.005, shape
        self.frequency_std_hz = self.damping_std = math.nan
        self.segment_frequency_std_hz, self.segment_damping_std = 1e-4 * f, 1e-4


@pytest.fixture(scope="module")
def line_modes():
    return fs.modal_analysis(fs.loads_model(EXAMPLE["model_text"]()))


def test_a_mode_far_from_every_model_mode_stays_unpaired(line_modes):
    far = 1.05 * F_TRUE[1] / (1 - PAIR_WINDOW)  # model mode 2 is 29 % below it (the window: 25 %)
    pairing = pair_modes(_Found([F_TRUE[0], far]), line_modes)
    assert [p.mode for p in pairing.pairs] == [1, None]
    assert "no model mode within" in pairing.pairs[1].reason


def test_two_modes_near_one_model_mode_the_nearer_keeps_it(line_modes):
    pairing = pair_modes(_Found([F_TRUE[0] * 0.99, F_TRUE[0] * 1.05]), line_modes)
    assert [p.mode for p in pairing.pairs] == [1, None]
    assert "nearer" in pairing.pairs[1].reason


def test_a_shape_that_is_no_model_modes_stays_unpaired(line_modes):
    units = dict.fromkeys(SPEEDS, "rad/s")
    # the first mode's frequency, the second mode's shape: MAC with mode 1's shape far below MIN_MAC
    shape = dict(zip(SPEEDS, TRUTH["speed_shapes"][:, 1], strict=True))
    pairing = pair_modes(_Found([F_TRUE[0]], [shape], units), line_modes, dict(zip(SPEEDS, STATIONS)))
    assert pairing.pairs[0].mode is None and "MAC" in pairing.pairs[0].reason
    right = dict(zip(SPEEDS, TRUTH["speed_shapes"][:, 0], strict=True))
    pairing = pair_modes(_Found([F_TRUE[0]], [right], units), line_modes, dict(zip(SPEEDS, STATIONS)))
    assert pairing.pairs[0].mode == 1 and pairing.pairs[0].mac == pytest.approx(1.0, abs=1e-9)
    assert pairing.shape_stations == STATIONS


@pytest.mark.parametrize(
    "stations,field,says",
    [
        ({"speed 9": "inertia 1"}, "stations", "is not an identified channel"),
        ({"speed 1": "nowhere"}, "speed 1", "is not a station of the model"),
    ],
)
def test_bad_stations_are_one_error_naming_them(line_modes, stations, field, says):
    units = dict.fromkeys(SPEEDS, "rad/s")
    with pytest.raises(ModelError, match=says) as e:
        pair_modes(_Found([F_TRUE[0]], None, units), line_modes, stations)
    assert e.value.field == field


def test_a_torque_channel_cannot_stand_for_a_station(line_modes):
    with pytest.raises(ModelError, match="does not measure a rotation"):
        pair_modes(_Found([F_TRUE[0]]), line_modes, {"torque s1": "inertia 1"})


# --- the command line's refusals: one line, exit 2, nothing written ---------------------------------


@pytest.mark.parametrize(
    "extra,says",
    [
        (["-o", "{tmp}/t.toml"], "-o with --model"),
        (["--station", "torque s1=inertia 1"], "--station with --model"),
        (["--model", "{bench}/start.toml", "-o", "{tmp}/t.txt"], "unknown file type"),
    ],
)
def test_refusals_before_any_work(bench, tmp_path, capsys, extra, says):
    extra = [a.format(tmp=tmp_path, bench=bench) for a in extra]
    code, out, err = _identify(capsys, bench / "run.tdms", *_channel_args(TORQUES), *extra)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and says in err
    assert list(tmp_path.iterdir()) == []


def test_an_existing_targets_file_is_kept_without_force(bench, tmp_path, capsys):
    targets = tmp_path / "targets.toml"
    targets.write_text("# mine\n", encoding="utf-8")
    args = [bench / "run.tdms", *_channel_args(TORQUES), "--model", bench / "start.toml", "-o", targets]
    code, out, err = _identify(capsys, *args)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--force" in err
    assert targets.read_text(encoding="utf-8") == "# mine\n"


def test_a_channel_the_file_does_not_have_is_one_error(bench, capsys):
    code, out, err = _identify(capsys, bench / "run.tdms", "--channel", "torque s9")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "torque s9" in err


# --- two frequencies, two stiffnesses: the second solution, and the shape that tells ----------------


def _other_root() -> tuple[float, float]:
    # The free chain's elastic ω² are the roots of ω⁴ − b·ω² + c with b = k1·(1/J1 + 1/J2) + k2·(1/J2 + 1/J3)
    # and c = k1·k2·(J1 + J2 + J3)/(J1·J2·J3): the same two frequencies for every (k1, k2) with the
    # same k1·k2 = P and the same b, i.e. the roots of a·k1² − b·k1 + e·P = 0 (a = 1/J1 + 1/J2,
    # e = 1/J2 + 1/J3). One root is the truth; the other is k1' = e·P/(a·k1).
    j1, j2, j3 = EXAMPLE["INERTIAS"]
    p = K_TRUE[0] * K_TRUE[1]
    k1 = (1 / j2 + 1 / j3) * p / ((1 / j1 + 1 / j2) * K_TRUE[0])
    return k1, p / k1


def _angle_shapes(k1: float, k2: float) -> np.ndarray:
    m = np.diag(EXAMPLE["INERTIAS"])
    k = np.array([[k1, -k1, 0.0], [-k1, k1 + k2, -k2], [0.0, -k2, k2]])
    return scipy.linalg.eigh(k, m)[1][:, 1:]


@pytest.mark.parametrize("start,wrong", [(K_START, False), ((0.8 * K_TRUE[0], 1.2 * K_TRUE[1]), True)])
def test_a_measured_shape_tells_the_second_solution_from_the_truth(start, wrong):
    # The exact targets (frequencies and θ shapes of the truth), two stiffnesses free within ±50 %: from
    # 10 % off the fit ends at the truth; from 20 % off the other way, at the other root - it meets the
    # frequencies as well, and its mode 1 looks less like the measured shape than the start's did.
    d = fs.loads_model(_model_text(*start))
    targets = [
        fs.Target(i + 1, frequency_hz=F_TRUE[i], shape=tuple(TRUTH["angle_shapes"][:, i])) for i in range(2)
    ]
    res = fs.calibrate(
        d, targets, [fs.Bound("s1.stiffness", percent=50), fs.Bound("s2.stiffness", percent=50)]
    )
    assert res.met.all()
    end = _other_root() if wrong else K_TRUE
    # the frequencies are met to the solver's tolerance (~1e-9 relative here); the stiffnesses follow
    # within the 2x2 map's conditioning of that
    np.testing.assert_allclose(res.tuned, end, rtol=1e-6)
    # the MACs at the start and the end, against scipy's eigenvectors of the same chains
    for values, macs in [(start, res.initial_shape_mac), (res.tuned, res.shape_mac)]:
        model_shapes = _angle_shapes(*values)
        for i in range(2):
            assert macs[i] == pytest.approx(mac(model_shapes[:, i], TRUTH["angle_shapes"][:, i]), abs=1e-9)
    assert ("mode 1's shape matches the measured one less" in res.message) == wrong
    if wrong:
        assert res.shape_mac[0] < 0.96  # 0.951: far below the truth's 1


def test_one_estimate_has_no_spread_a_dash_in_the_table_null_in_json(tmp_path, capsys):
    # a single-mode free decay, not cut into segments (not stationary): one run, one estimate, so no
    # standard deviation exists - the table shows "-" (never "nan") and --json null, as its to_dict does
    t = np.arange(60_000) / 1000.0
    wn, zeta = 2 * np.pi * 10.0, 0.02
    x = 5.0 + np.exp(-zeta * wn * t) * np.cos(wn * math.sqrt(1 - zeta**2) * t + 0.3)
    run = fs.write_signals(tmp_path / "decay.csv", t, {"torque": (x, "N·m")})
    code, out, err = _identify(capsys, run, "--channel", "torque", "--max-hz", "50")
    assert code == 0, err
    row = next(line for line in out.splitlines() if line.strip().startswith("10.0000"))
    cells = row.split()
    assert "nan" not in out.lower() and cells[1] == "-" and cells[3] == "-"  # ± Hz and ± %
    assert "- : one estimate" in out
    code, out, err = _identify(capsys, run, "--channel", "torque", "--max-hz", "50", "--json")
    (mode,) = json.loads(out)["modes"]
    assert mode["frequency_std_hz"] is None and mode["segment_frequency_std_hz"] is None
    assert mode["damping_std"] is None and mode["segment_damping_std"] is None

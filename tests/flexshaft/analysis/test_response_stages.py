"""The response stages the commands and the study share: the modes and state space of a drivetrain
(response_system), the default FRF range, a study's scenario from its options, and the state-space
file."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.modal import response_modes
from flexshaft.analysis.scenario import Scenario, SpeedControl
from flexshaft.analysis.simulate import simulate
from flexshaft.analysis.statespace import default_frf_range, response_system
from flexshaft.errors import ModelError
from flexshaft.exports.statespacefile import write_state_space
from flexshaft.model.assembly import assemble
from tests.conftest import EXAMPLES


@pytest.fixture(scope="module")
def system():
    return response_system(fs.load_model(EXAMPLES / "customer1.toml"), ["motor"], ["speed:motor"])


def test_every_mode_of_a_small_model(system):
    result, ss = system
    assert result.model.n_dof == 5 and len(result.frequencies_hz) == 5  # no truncation up to 2000 DOFs
    np.testing.assert_array_equal(ss.frequencies_hz, result.frequencies_hz)
    again = response_modes(assemble(fs.load_model(EXAMPLES / "customer1.toml")))
    np.testing.assert_array_equal(again.frequencies_hz, result.frequencies_hz)


def test_the_default_range_is_one_and_a_half_times_the_highest_mode(system):
    _, ss = system
    assert default_frf_range(ss) == (0.0, 1.5 * ss.frequencies_hz.max())
    assert default_frf_range(ss, 1.0, 50.0) == (1.0, 50.0)
    with pytest.raises(ModelError) as err:
        default_frf_range(ss, 60.0, 50.0)
    assert err.value.field == "f_from" and "f_from < f_to = 50 Hz" in err.value.valid


@pytest.mark.parametrize(
    "kind, options, field",
    [
        ("step", {"kp": 1.0}, "kp"),
        ("ramp", {"end_speed_rpm": 600.0}, "ramp_time"),
        ("ramp", {"end_speed_rpm": 600.0, "ramp_time": 1.0, "kp": 1.0}, "ki"),
        ("ramp", {"end_speed_rpm": 600.0, "ramp_time": 1.0, "torque_limit": -1.0}, "torque_limit"),
        ("csv", {}, "series"),
        ("pulse", {}, "scenario"),
    ],
)
def test_a_study_scenario_s_errors_name_its_options(system, kind, options, field):
    with pytest.raises(ModelError) as err:
        Scenario.of(kind, options, system[0])
    assert err.value.field == field


@pytest.mark.parametrize(
    "scenario, field",
    [
        (Scenario.step(1.0, at="nowhere"), "at"),
        (Scenario.sine(1.0, 5.0, load_at="nowhere"), "load_at"),
    ],
)
def test_a_run_names_the_station_it_does_not_know(system, scenario, field):
    with pytest.raises(ModelError) as err:
        simulate(system[0], scenario, ["speed:motor"])
    assert err.value.field == field


def test_the_speed_loop_takes_both_gains_or_neither(system):
    for given, field in (({"kp": 1.0}, "ki"), ({"ki": 1.0}, "kp"), ({"torque_limit": -1.0}, "torque_limit")):
        with pytest.raises(ModelError) as err:
            SpeedControl.from_gains(system[0], **given)
        assert err.value.field == field


def test_scenarios_from_a_study_s_options(system):
    result = system[0]
    ramp = Scenario.of("ramp", {"end_speed_rpm": 600.0, "ramp_time": 2.0, "torque_limit": 2e5}, result)
    assert ramp.control.kp > 0 and ramp.control.torque_max == 2e5 and ramp.control.torque_min == -2e5
    assert ramp.control == SpeedControl.tuned(result, torque_min=-2e5, torque_max=2e5)
    t = np.linspace(0.0, 1.0, 11)
    series = Scenario.of("csv", {"at": "motor"}, result, series=(t, 100.0 * t))
    assert series.at == "motor"


@pytest.mark.parametrize("suffix", [".npz", ".json", ".mat"])
def test_the_state_space_file_reads_back(system, tmp_path, suffix):
    _, ss = system
    path = write_state_space(ss, tmp_path / f"ss{suffix}", damping="damping: per part")
    if suffix == ".npz":
        got = np.load(path)
        A, meta = got["A"], json.loads(str(got["metadata"]))
    elif suffix == ".json":
        doc = json.loads(path.read_text())
        A, meta = np.array(doc["A"]), doc
    else:
        from scipy.io import loadmat

        got = loadmat(path)
        A, meta = got["A"], json.loads(str(got["flexshaft_metadata"][0]))
    np.testing.assert_array_equal(A, ss.A)
    assert meta["inputs"] == ["motor"] and meta["output_units"] == ["rad/s"]
    assert meta["damping"] == "damping: per part"  # the damping the system carries, stated
    with pytest.raises(ModelError) as err:
        write_state_space(ss, tmp_path / "ss.txt")
    assert err.value.field == "path"

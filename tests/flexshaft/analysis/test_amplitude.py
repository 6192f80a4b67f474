"""The stepped sine at several amplitudes: a linear line's apparent modes are its modes at every
amplitude; a slipping coupling's move down as the drive grows, and only the ratio of drive to slip
torque matters (every law is positively homogeneous: scale both and the response scales)."""

import json

import numpy as np
import pytest

from flexshaft import ModelError
from flexshaft.analysis.amplitude import stepped_sine
from flexshaft.analysis.modal import modal_analysis
from flexshaft.analysis.simulate import Scenario, simulate
from flexshaft.cli import main
from flexshaft.model.assembly import assemble
from flexshaft.model.components import Coupling, Drivetrain, Rigid

# two inertias and a coupling with a damper: one elastic mode at sqrt(k (J1 + J2) / (J1 J2)) / 2π
J1, J2, K, C = 58.1, 35.0, 42429.35, 12.0
F1 = np.sqrt(K * (J1 + J2) / (J1 * J2)) / (2 * np.pi)


def _line(slip=None):
    kw = {} if slip is None else {"slip_torque": slip}
    return modal_analysis(
        assemble(Drivetrain("two", (Rigid("motor", J1), Coupling("c", K, damping=C, **kw), Rigid("gen", J2))))
    )


def test_a_linear_line_shows_its_modes_at_every_amplitude():
    sweep = stepped_sine(_line(), [1.0, 1000.0], points=11, refine=10)
    step = (sweep.frequencies_hz[0, 1] - sweep.frequencies_hz[0, 0]) / 2**10
    # the peak of |H| of a damped mode sits at f·sqrt(1 − 2ζ²) (ζ here 0.3 %: 1e-5 below f); the
    # bracket is halved 10 times from the grid step
    np.testing.assert_allclose(sweep.apparent_hz[:, 0], F1, rtol=0, atol=step + 2e-5 * F1)
    # linear: per N·m alike, the two runs' arithmetic scaled by 1000 (round-off of the fit only)
    np.testing.assert_allclose(sweep.response[0], sweep.response[1], rtol=1e-9)
    assert np.all(sweep.active == 0.0)
    assert np.max(sweep.settling) < 1e-9  # started on the steady oscillation: nothing to settle


def test_a_slipping_coupling_lowers_the_mode_as_the_drive_grows():
    """At resonance the coupling carries about Q·J2/(J1 + J2) times the drive (Q = 1/2ζ, ζ = 0.26 %:
    70 times): 5 N·m stays below the 1000 N·m slip torque, 100 and 300 N·m do not."""
    sweep = stepped_sine(_line(slip=1000.0), [5.0, 100.0, 300.0], points=15, refine=6)
    shift = sweep.shift[:, 0]
    resolution = (sweep.frequencies_hz[0, 1] - sweep.frequencies_hz[0, 0]) / 2**6 / F1
    assert abs(shift[0]) <= resolution + 2e-5 and np.all(sweep.active[0] == 0.0)
    assert shift[1] < -10 * resolution and shift[2] < shift[1] - 10 * resolution
    assert np.all(np.diff(sweep.active.max(axis=2)[:, 0]) > 0)
    assert "apparent Hz" in sweep.table()
    json.dumps(sweep.to_dict())


def test_only_the_ratio_of_drive_to_slip_torque_matters():
    """Positive homogeneity: slip torque and drive ×10 give the same motion ×10, the same curve."""
    a = stepped_sine(_line(slip=100.0), [100.0], points=9, refine=3)
    b = stepped_sine(_line(slip=1000.0), [1000.0], points=9, refine=3)
    # the same arithmetic scaled by 10: round-off apart (events located to 1e-12 of a step)
    np.testing.assert_allclose(a.response, b.response, rtol=1e-7)
    # the peaks alike to the search's resolution (round-off could tip one halving: one bracket step)
    step = (a.frequencies_hz[0, 1] - a.frequencies_hz[0, 0]) / 2**3
    assert abs(a.apparent_hz[0, 0] - b.apparent_hz[0, 0]) <= step


def test_steady_start_is_the_periodic_solution():
    res = _line()
    run = simulate(
        res, Scenario.sine(100.0, 0.8 * F1, steady=True), ["speed:gen"], rate=1000.0, duration=4 / F1
    )
    y = run.outputs["speed:gen"]
    period = int(round(1000.0 / (0.8 * F1)))
    # exact for the sampled system; sampling a non-integer period moves the samples, not the envelope
    assert abs(np.abs(y[: 2 * period]).max() - np.abs(y[-2 * period :]).max()) < 1e-3 * np.abs(y).max()


def test_bad_arguments():
    res = _line()
    with pytest.raises(ModelError, match="amplitudes"):
        stepped_sine(res, [])
    with pytest.raises(ModelError) as err:
        stepped_sine(res, [1.0], modes=[0])
    assert err.value.field == "modes"
    with pytest.raises(ModelError) as err:
        Scenario.step(1.0, steady=True)
    assert err.value.field == "steady"


def test_cli_amplitude(tmp_path, capsys):
    model = tmp_path / "two.toml"
    model.write_text(
        '[model]\nname = "two"\n[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n'
        f'[[chain]]\nname = "c"\ntype = "coupling"\nstiffness = {K}\ndamping = {C}\nslip_torque = 1000.0\n'
        '[[chain]]\nname = "gen"\ntype = "rigid"\ninertia = 35.0\n',
        encoding="utf-8",
    )
    assert main(["amplitude", str(model), "--torque", "5", "100", "--points", "7", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    amps = doc["modes"][0]["amplitudes"]
    assert [a["amplitude"] for a in amps] == [5.0, 100.0] and amps[1]["shift"] < amps[0]["shift"]
    assert main(["amplitude", str(model), "--torque", "-5"]) == 2
    assert "--torque" in capsys.readouterr().err
    assert main(["simulate", str(model), "--scenario", "step", "--steady", "--measure", "speed:gen"]) == 2
    assert "--steady" in capsys.readouterr().err

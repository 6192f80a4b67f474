"""Forced response against closed forms, a direct solve of the physical system and the study's slip case."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.analysis.forced import forced_response
from flexshaft.cli import main
from tests.conftest import EXAMPLES


def test_two_inertias_through_a_damped_coupling_match_the_closed_form():
    # J1 θ1'' = T − τ, J2 θ2'' = τ, τ = kΔ + cΔ' with Δ = θ1 − θ2 gives
    # J Δ'' + c Δ' + k Δ = T J2/(J1 + J2), J = J1 J2/(J1 + J2), so
    # τ(ω) = T (J2/(J1 + J2)) (k + iωc)/(k − ω²J + iωc). Arithmetic of a 2-DOF system: at the mode the
    # solve's condition is ~1/(2ξ) = 55 (ξ = 0.009), so ~1e-14; 1e-10 is loose. |λ| = √(k/J) of a 2-DOF
    # first-order solve: a few eps (1e-12).
    J1, J2, k, c, T = 2.0, 3.0, 1e4, 2.0, 10.0
    d = fs.Drivetrain("two", [fs.Rigid("a", J1), fs.Coupling("c", stiffness=k, damping=c), fs.Rigid("b", J2)])
    r = fs.modal_analysis(d)
    J = J1 * J2 / (J1 + J2)
    at_mode = forced_response(r, "a", amplitude=T)
    w = np.sqrt(k / J)  # |λ| of the one damped mode is √(k/J) exactly
    assert at_mode.frequencies_hz == pytest.approx([w / (2 * np.pi)], rel=1e-12)
    off = forced_response(r, "a", amplitude=T, frequencies_hz=[3.0, 30.0])
    for res in (at_mode, off):
        j = res.signals.index("torque:c")
        for f, amp in zip(res.frequencies_hz, res.amplitudes[:, j]):
            wk = 2 * np.pi * f
            tau = T * J2 / (J1 + J2) * (k + 1j * wk * c) / (k - wk * wk * J + 1j * wk * c)
            assert amp == pytest.approx(abs(tau), rel=1e-10)
    assert list(off.modes) == [-1, -1] and list(at_mode.modes) == [1]


def test_amplitudes_are_the_direct_solve_at_each_eigenfrequency():
    # (K − ω²M + iωC) x = T e_motor solved densely at each mode's frequency; the torque of part 2
    # is k (x₁ − x₂). At resonance the matrix has condition ~(λ_max/λ₁)/(2ξ) ≈ 2300/(2·7e-5) ≈ 2e7 on
    # mode 1, so both solves carry at most ~eps·2e7 ≈ 4e-9 relative error (1e-13 seen): 1e-8.
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))
    m = r.model
    res = forced_response(r, "motor", amplitude=250.0)
    K, M, C = m.K.toarray(), m.M.toarray(), m.C.toarray()
    st = {s.name: s.node for s in m.stations}
    k2 = m.drivetrain.component("part 2").stiffness
    j = res.signals.index("torque:part 2")
    a = res.signals.index("angle:generator")
    for f, row in zip(res.frequencies_hz, res.amplitudes):
        w = 2 * np.pi * f
        F = np.zeros(m.n_dof)
        F[st["motor"]] = 250.0
        x = np.linalg.solve(K - w * w * M + 1j * w * C, F)
        assert row[j] == pytest.approx(abs(k2 * (x[st["part 1/part 2"]] - x[st["part 2/part 3"]])), rel=1e-8)
        assert row[a] == pytest.approx(abs(x[st["generator"]]), rel=1e-8)


def test_customer2_coupling_slip_case(capsys):
    # The study's explanation of the slipping friction coupling (part 3): driven at mode 1 it carries
    # the largest dynamic torque of the line, at mode 2 the least of the flexible parts.
    assert main(["forced", str(EXAMPLES / "customer2.toml"), "--torque", "100", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["units"]["torque"] == "N·m (peak)" and doc["amplitude"] == 100.0
    first, second = doc["excitations"][:2]
    assert first["mode"] == 1 and first["largest_torque"] == "part 3"
    torques = {k[7:]: v for k, v in second["amplitude"].items() if k.startswith("torque:")}
    assert min(torques, key=torques.get) == "part 3"


def test_cli_table_and_bad_input(tmp_path, capsys):
    model = str(EXAMPLES / "customer1.toml")
    assert main(["forced", model, "--frequency", "11.6", "--frequency", "50"]) == 0
    out = capsys.readouterr().out
    # title, blank, header, rule, then one row per --frequency (2)
    assert "forced response to 1 N·m at motor" in out and out.count("\n") == 6
    target = tmp_path / "f.json"
    assert main(["forced", model, "-o", str(target)]) == 0
    assert len(json.loads(target.read_text())["excitations"]) == 4
    assert main(["forced", model, "-o", str(target)]) == 2  # no overwrite without --force
    assert "exists" in capsys.readouterr().err
    for bad in (["--torque", "-1"], ["--torque", "nan"], ["--at", "rotor"], ["--frequency", "-3"]):
        assert main(["forced", model, *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error" in err


def test_the_default_excitations_stop_at_the_range_of_interest():
    # A fine mesh has modes up to a megahertz; by default only the modes up to max_hz are excited -
    # the model's [model] max_hz, or the one given - each at its own natural frequency.
    import dataclasses

    d = fs.load_model(EXAMPLES / "customer1.toml")
    result = fs.modal_analysis(dataclasses.replace(d, max_hz=100.0))
    below = [
        i
        for i in range(result.count)
        if not result.rigid[i] and result.damped.natural_frequencies_hz[i] <= 100
    ]
    elastic = int((~result.rigid).sum())
    assert 0 < len(below) < elastic  # the cut is a real one: some modes below 100 Hz, some past it
    fr = forced_response(result, "motor", amplitude=1.0)
    assert list(fr.modes) == below
    assert np.allclose(fr.frequencies_hz, result.damped.natural_frequencies_hz[below], rtol=1e-12)
    lowest = [i for i in below if result.damped.natural_frequencies_hz[i] <= 20.0]
    assert list(forced_response(result, "motor", max_hz=20.0).modes) == lowest
    full = fs.modal_analysis(d)
    every = [i for i in range(full.count) if not full.rigid[i]]
    assert list(forced_response(full, "motor").modes) == every  # no range: every elastic mode


def test_the_default_station_is_the_driving_end_whatever_its_name(capsys):
    # The two-inertia closed form with the driving inertia named "hub", not "motor": with no station
    # given, the torque acts at the chain's first station (it was the literal name "motor", so such a
    # model failed). Same closed form and bound as the first test.
    J1, J2, k, c, T = 2.0, 3.0, 1e4, 2.0, 10.0
    chain = [fs.Rigid("hub", J1), fs.Coupling("c", stiffness=k, damping=c), fs.Rigid("b", J2)]
    d = fs.Drivetrain("two", chain)
    res = forced_response(fs.modal_analysis(d), amplitude=T, frequencies_hz=[3.0])
    assert res.input == "hub"
    wk, J = 2 * np.pi * 3.0, J1 * J2 / (J1 + J2)
    tau = T * J2 / (J1 + J2) * (k + 1j * wk * c) / (k - wk * wk * J + 1j * wk * c)
    assert res.amplitudes[0, res.signals.index("torque:c")] == pytest.approx(abs(tau), rel=1e-10)
    # and the command, on a model whose driving end is the rotor
    assert main(["forced", str(EXAMPLES / "nrel5mw.toml"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["input"] == "rotor"

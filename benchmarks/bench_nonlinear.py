"""Nonlinear time runs: a slipping coupling against the linear run, and against scipy's solve_ivp.

What it measures
----------------
1. The issue's case: Customer 1 (examples/customer1.toml, every mode kept), a 60 s run at 1 kHz - a
   speed ramp 0 -> 1500 rpm in 50 s with the PI loop closed (gains tuned from the model), a 6th-order
   torque ripple of 30 N·m and a 250 N·m load - once with the coupling (part 3) linear and once
   with it slipping at 300 N·m (kinetic 250 N·m): the ripple's resonance crossings and the load
   put it over, so it sticks and slips. Best of 3, the two interleaved; printed: both times and the
   ratio (the issue's target: the slipping run within 3x the linear one).
2. The same drivetrain driven open-loop by a sine at mode 1 that slips the coupling, 10 s at 1 kHz:
   flexshaft's run against ``scipy.integrate.solve_ivp`` (Radau, rtol 1e-8, terminal event functions
   and a restart in the new regime at each event) on the drivetrain's own M, C, K (the assembled
   matrices: the peer integrates the same equations). The drive is the sine itself for scipy and
   its samples held over each step for flexshaft (its exact discretisation's input), so the two
   differ by O(dt); printed: times, ratio, events counted by each, and the largest difference of the
   coupling torque relative to its range.

Run: ``.venv/bin/python benchmarks/bench_nonlinear.py`` (about a minute, solve_ivp being the slow
part). Timings are printed, never asserted.
"""

from __future__ import annotations

import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from timing import interleaved

import flexshaft as fs
from flexshaft.analysis.simulate import Scenario, SpeedControl, simulate
from flexshaft.analysis.statespace import element_rows

ROOT = Path(__file__).resolve().parents[1]
RATE = 1000.0
SLIP, KINETIC = 300.0, 250.0


def _models():
    linear = fs.load_model(ROOT / "examples" / "customer1.toml")
    comps = tuple(
        replace(c, slip_torque=SLIP, slip_kinetic_torque=KINETIC) if c.name == "part 3" else c
        for c in linear.components
    )
    return fs.modal_analysis(linear), fs.modal_analysis(replace(linear, components=comps))


def ramp_case(lin, nl) -> None:
    ctl = SpeedControl.tuned(lin, torque_min=-5000.0, torque_max=5000.0)
    sc = Scenario.ramp(1500.0, 50.0, ctl, ripple=30.0, ripple_order=6, load=-250.0)
    outs = ["torque:part 3", "speed:motor", "speed:generator"]
    runs = {}

    def run(result, key):
        runs[key] = simulate(result, sc, outs, rate=RATE, duration=60.0, max_hz=float("inf"))

    times = interleaved({"linear": lambda: run(lin, "linear"), "slipping": lambda: run(nl, "slipping")}, 3)
    acc = runs["slipping"].nonlinear.elements[0]
    print(f"60 s ramp at {RATE:g} Hz, Customer 1, {runs['linear'].time.size} samples:")
    print(f"  linear coupling:   {times['linear']:.3f} s ({runs['linear'].method})")
    print(
        f"  slipping coupling: {times['slipping']:.3f} s ({runs['slipping'].method}; slipping"
        f" {acc.active_time:.2f} s, {acc.dissipated:.4g} J dissipated)"
    )
    print(f"  ratio slipping / linear: {times['slipping'] / times['linear']:.2f} (target <= 3)")


def _reference(nl, t_end: float, amplitude: float, f: float):
    """solve_ivp (Radau, events) on the drivetrain's M, C, K with part 3 slipping (massless hub, no
    damper on it: slipping, it transmits ±T_k and its slip speed is its relative speed)."""
    model = nl.model
    M, K = model.M.toarray(), model.K.toarray()
    C = model.C.toarray() if model.C is not None else np.zeros_like(M)
    n = M.shape[0]
    diff, k0, c0 = element_rows(model, "part 3")
    drive = np.asarray(model.T[model.node_dof([model.station("motor").node])[0]].toarray()).ravel()
    Minv = np.linalg.inv(M)  # a few DOFs: the reference's own solve

    def rhs(regime):
        def f_(t, y):
            q, v, s = y[:n], y[n : 2 * n], y[2 * n]
            d, w = diff @ q, diff @ v
            actual = k0 * (d - s) + c0 * w if regime == 0 else regime * KINETIC
            force = amplitude * np.sin(2 * np.pi * f * t) * drive - diff * (actual - k0 * d - c0 * w)
            a = Minv @ (force - C @ v - K @ q)
            return np.concatenate([v, a, [0.0 if regime == 0 else w]])

        return f_

    def stuck_event(sign):
        def g(t, y):
            q, v, s = y[:n], y[n : 2 * n], y[2 * n]
            return SLIP - sign * (k0 * (diff @ q - s) + c0 * (diff @ v))

        g.terminal, g.direction = True, -1
        return g

    def slip_event(regime):
        def g(t, y):
            return regime * (diff @ y[n : 2 * n])

        g.terminal, g.direction = True, -1
        return g

    t, y, regime, events = 0.0, np.zeros(2 * n + 1), 0, 0
    grid = np.arange(0.0, t_end + 0.5 / RATE, 1.0 / RATE)
    out = np.empty(grid.size)
    while t < t_end:
        evs = [stuck_event(1), stuck_event(-1)] if regime == 0 else [slip_event(regime)]
        sol = solve_ivp(
            rhs(regime), (t, t_end), y, method="Radau", rtol=1e-8, atol=1e-10, events=evs, dense_output=True
        )
        t_stop = sol.t[-1]
        mask = (grid >= t) & (grid <= t_stop)
        ys = sol.sol(grid[mask]) if mask.any() else np.zeros((2 * n + 1, 0))
        out[mask] = [
            (k0 * (diff @ col[:n] - col[2 * n]) + c0 * (diff @ col[n : 2 * n]))
            if regime == 0
            else regime * KINETIC
            for col in ys.T
        ]
        if sol.status != 1:
            break
        y = sol.y[:, -1].copy()
        if regime == 0:
            sign = 1 if any(e.size for e in sol.t_events[:1]) else -1
            y[2 * n] = diff @ y[:n] - sign * KINETIC / k0  # the spring drops to the kinetic torque
            regime = sign
        else:
            regime = 0
        t, events = t_stop, events + 1
    return out, events


def sine_case(nl) -> None:
    f1 = float(nl.frequencies_hz[1])
    amplitude, t_end = 40.0, 10.0
    times = {}
    t0 = time.perf_counter()
    run = simulate(
        nl, Scenario.sine(amplitude, f1), ["torque:part 3"], rate=RATE, duration=t_end, max_hz=float("inf")
    )
    times["flexshaft"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref, ref_events = _reference(nl, t_end, amplitude, f1)
    times["solve_ivp"] = time.perf_counter() - t0
    ours = run.outputs["torque:part 3"]
    diff = np.max(np.abs(ours - ref)) / np.ptp(ref)
    print(
        f"{t_end:g} s sine at mode 1 ({f1:.3f} Hz, {amplitude:g} N·m) slipping part 3, {ours.size} samples:"
    )
    print(f"  flexshaft: {times['flexshaft']:.3f} s, {run.nonlinear.event_count} events")
    print(f"  solve_ivp (Radau, events): {times['solve_ivp']:.3f} s, {ref_events} events")
    print(f"  ratio flexshaft / solve_ivp: {times['flexshaft'] / times['solve_ivp']:.4f}")
    print(f"  coupling torque: largest difference {diff:.1e} of its range (held vs continuous sine)")


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    lin, nl = _models()
    ramp_case(lin, nl)
    sine_case(nl)


if __name__ == "__main__":
    main()

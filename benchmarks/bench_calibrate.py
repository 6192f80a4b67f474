"""Calibration benchmark: flexshaft's ``calibrate`` against a plain finite-difference least squares.

What it measures
----------------
The study's staged calibration, examples/calibration/study.toml, all three stages ("shared
parts" on Without DUT, then Customer 1 and Customer 2 with the shared parts' tuned values carried
and fixed, as ``flexshaft calibrate`` stages them), two ways on the same targets, parameters and
bounds:

- flexshaft: ``calibrate(model, stage.targets, stage.parameters)`` per stage - analytic Jacobian,
  modes tracked by shape, parameters on a bound put onto it, and for each missed target what one
  parameter alone would need (a root search per parameter: work the plain solve does not do);
- plain: ``scipy.optimize.least_squares`` as a scipy user would write it - residual
  ``(value/target − 1)/tolerance`` from flexshaft's ``with_parameters`` + ``modal_analysis``, modes
  taken by their number, parameters scaled by their starting values, bounds, and otherwise the
  defaults: trust-region reflective, 2-point finite-difference Jacobian, xtol = ftol = gtol = 1e-8.

Each stage of the plain pipeline starts from its own previous stages' results. The two are run in
turn, interleaved (flexshaft, plain, flexshaft, plain, ...: both see the same drift in machine
load), best of ``--repeats``, on one BLAS thread (``threadpool_limits(1)``; flexshaft's own thread
policy is one thread too). Imports are done before the timing.

Printed: both times and their ratio (the issue's target: flexshaft at most 1.0x the plain solve),
and per stage the optimum each reached - its cost ½Σ residual², its parameters, and how far apart
the two put each target's value, in units of that target's tolerance.

Run: ``.venv/bin/python benchmarks/bench_calibrate.py`` (a few seconds; ``--repeats 1`` for one run
each). Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np
import scipy
import scipy.optimize  # noqa: F401 - imported before the timing, for both
import scipy.stats  # noqa: F401 - likewise (flexshaft's multi-start uses its Latin hypercube)
from threadpoolctl import threadpool_limits

import flexshaft as fs
from flexshaft.analysis.calibrate import calibrate
from flexshaft.analysis.parameters import parameter_value, with_parameters
from flexshaft.study.tunedfile import carried, read_targets

STUDY = Path(__file__).resolve().parent.parent / "examples" / "calibration" / "study.toml"


def _stages(study, solve) -> list[dict]:
    """Every stage of ``study`` in turn, each with the values its earlier stages tuned carried and
    fixed (as ``flexshaft calibrate`` does); ``solve(model, stage)`` returns the stage's result."""
    tuned: dict = {}
    out = []
    for stage in study.stages:
        d = fs.load_model(stage.model)
        pool: dict = {}
        for name in stage.carry_from if stage.carry_from is not None else tuned:
            pool |= tuned[name]
        fixed = carried(d, pool)
        res = solve(with_parameters(d, fixed) if fixed else d, stage)
        tuned[stage.name] = dict(zip(res["names"], res["x"]))
        out.append(res)
    return out


def flexshaft_stage(d, stage) -> dict:
    """One stage by flexshaft's ``calibrate``."""
    res = calibrate(d, stage.targets, stage.parameters, starts=1)
    return {"names": res.names, "x": res.tuned, "cost": res.cost, "values": res.values}


def plain_stage(d, stage) -> dict:
    """One stage by a plain finite-difference ``least_squares``: modes by number, default settings."""
    from scipy.optimize import least_squares

    free = [b for b in stage.parameters if b.fixed is None]
    fixed = {b.name: b.fixed for b in stage.parameters if b.fixed is not None}
    d = with_parameters(d, fixed) if fixed else d
    names = [b.name for b in free]
    x0 = np.array([parameter_value(d, n) for n in names])
    lims = np.array([b.limits(v) for b, v in zip(free, x0)])
    goal = np.array([t.value for t in stage.targets])
    tol = np.array([t.tolerance for t in stage.targets])

    def values(z):
        f = fs.modal_analysis(with_parameters(d, dict(zip(names, z * x0))), damped=False).frequencies_hz
        return np.array(
            [f[t.mode] / (f[t.ratio_to] if t.ratio_to is not None else 1.0) for t in stage.targets]
        )

    def residual(z):
        return (values(z) / goal - 1) / tol

    sol = least_squares(residual, np.ones(len(names)), bounds=(lims[:, 0] / x0, lims[:, 1] / x0))
    return {
        "names": tuple(names),
        "x": sol.x * x0,
        "cost": float(sol.cost),
        "values": values(sol.x),
        "jacobians": int(sol.njev),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3, help="runs of each to take the best of")
    args = ap.parse_args(argv)
    study = read_targets(STUDY)
    print(
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; numpy {np.__version__}, "
        f"scipy {scipy.__version__}; one BLAS thread for everyone; flexshaft from {Path(fs.__file__).parent}"
    )
    runs = {
        "flexshaft calibrate": lambda: _stages(study, flexshaft_stage),
        "plain FD least_squares": lambda: _stages(study, plain_stage),
    }
    best = dict.fromkeys(runs, math.inf)
    out = {}
    with threadpool_limits(limits=1):
        for _ in range(args.repeats):
            for name, fn in runs.items():  # interleaved: a, b, a, b, ...
                t0 = time.perf_counter()
                out[name] = fn()
                best[name] = min(best[name], time.perf_counter() - t0)
    ours, plain = best["flexshaft calibrate"], best["plain FD least_squares"]
    print(f"\nexamples/calibration/{STUDY.name}: {len(study.stages)} stages, best of {args.repeats}")
    for name, t in best.items():
        print(f"  {name:24s} {t:8.3f} s")
    print(f"  flexshaft / plain        {ours / plain:8.2f}x   (target: at most 1.0x)")
    for stage, a, b in zip(study.stages, out["flexshaft calibrate"], out["plain FD least_squares"]):
        tol = np.array([t.tolerance for t in stage.targets])
        goal = np.array([t.value for t in stage.targets])
        apart = np.max(np.abs(a["values"] - b["values"]) / goal / tol)
        print(
            f"\nstage {stage.name!r}: {len(a['names'])} parameters, {len(stage.targets)} target(s); "
            f"the targets' values apart by at most {apart:.1e} of a tolerance"
        )
        print("  " + " " * 10 + "".join(f"{n:>20s}" for n in a["names"]) + f"{'cost':>16s}")
        for label, r in (("flexshaft", a), ("plain", b)):
            extra = f"  ({r['jacobians']} FD Jacobians)" if "jacobians" in r else ""
            print(f"  {label:10s}" + "".join(f"{v:20.9g}" for v in r["x"]) + f"{r['cost']:16.10g}{extra}")


if __name__ == "__main__":
    main()

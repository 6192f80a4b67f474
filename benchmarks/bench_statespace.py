"""State-space and frequency-response benchmark: a 50 000-DOF 6-DOF drivetrain with reduced parts.

What it measures
----------------
The bench line motor - shaft a - coupling - shaft b - generator in 6 DOFs per node, each shaft
a Craig–Bampton body (20 fixed-interface modes, 0.53 % damping) reduced from a Timoshenko mesh
of ~4 200 elements (about 50 000 physical DOFs in all), held by bearings at motor and generator.
Timed, best of 3 (assembly and the reduction of the parts are outside the timing - they are
`bench_reduce.py`'s subject):

- ``modal_analysis`` (all modes of the assembled, reduced model) + ``state_space`` (input: the
  motor torque; outputs: generator speed and coupling torque) + a 2 000-point ``frequency_response``;
- python-control 0.10's ``frequency_response`` of the same system (``to_control()``) on the same
  2 000 frequencies, and the largest difference between the two responses.

Target from the issue: state space and a 2 000-point FRF in under 1 s.
Peer: python-control (the test extra installs it; it evaluates C (sI − A)⁻¹ B from the state
space). Run: ``.venv/bin/python benchmarks/bench_statespace.py``. Timings are printed, never
asserted.
"""

from __future__ import annotations

import os
import time

import numpy as np
from timing import best

import flexshaft as fs
from flexshaft.model.components import Reduce
from flexshaft.sections import table_from_segments


def shaft(name, segs, n):
    t = table_from_segments(segs, name=name)
    return fs.Shaft.from_sections(name, t, fs.STEEL, max_element_length=t.length / n, reduce=Reduce(modes=20))


def bench_line() -> fs.Drivetrain:
    """The 6-DOF bench line with its two Craig–Bampton shafts (also timed by ``bench_frf.py``)."""
    return fs.Drivetrain(
        "bench",
        [
            fs.Rigid("motor", 5.0),
            shaft("a", [{"length": 1.0, "od": 0.1}, {"length": 0.5, "od": 0.08, "id": 0.03}], 4200),
            fs.Coupling("c", stiffness=2e4, inertia=0.02, damping=3.0),
            shaft("b", [{"length": 0.8, "od": 0.09}], 4200),
            fs.Rigid("gen", 2.0),
        ],
        dofs="full",
        bearings=(("motor", 2e8), ("gen", 2e8)),
    )


def main() -> None:
    try:
        import control
    except ImportError:
        raise SystemExit("needs python-control: .venv/bin/pip install -e '.[test]'") from None
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    d = bench_line()
    t0 = time.perf_counter()
    model = fs.assemble(d)
    t_asm = time.perf_counter() - t0
    print(
        f"assembled (parts meshed and reduced) in {t_asm:.1f} s: {model.n_dof} coordinates"
        f" from {6 * model.n_nodes} node DOFs"
    )

    f = np.linspace(0.5, 2000.0, 2000)

    def ours():
        r = fs.modal_analysis(model, count=model.n_dof)
        ss = fs.state_space(r, ["motor"], ["speed:gen", "torque:c"])
        return ss, fs.frequency_response(ss, f)

    t_ours, (ss, resp) = best(ours)
    sys = ss.to_control()
    t_ctrl, theirs = best(lambda: control.frequency_response(sys, 2 * np.pi * f))
    H = resp.H[:, :, 0].T  # (outputs, frequencies)
    Hc = np.asarray(theirs.complex).reshape(H.shape)
    err = np.max(np.abs(H - Hc) / np.max(np.abs(H), axis=1, keepdims=True))
    print(f"state space: {ss.A.shape[0]} states, 1 input, 2 outputs; FRF at {f.size} frequencies")
    print(
        f"flexshaft modes + state space + FRF: {t_ours:.3f} s   "
        f"target < 1 s: {'met' if t_ours < 1 else 'NOT met'}"
    )
    print(
        f"python-control frequency_response (FRF only): {t_ctrl:.3f} s   "
        f"ratio flexshaft/control {t_ours / t_ctrl:.2f}"
    )
    print(f"responses agree to {err:.1e} (relative to each output's peak)")


if __name__ == "__main__":
    main()

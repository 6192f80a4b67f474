"""
Customer 2: a slipping coupling moves mode 1 and hardly mode 2
===============================================================

In the Customer 2 set-up the bench's first torsional eigenfrequency came out 23.25 % below the
model's and the second only 3.05 % below (the study's chapter 10). The study's explanation: the
friction ("sliding") coupling, part 3, slips under the large dynamic torque mode 1 puts through it,
and mode 2 puts little torque through it - no static stiffness change moves the two modes like that.
This script shows it on :download:`customer2_slip.toml <../../examples/customer2_slip.toml>` (the
published Customer 2 with part 3 given a slip torque and a damper: the file says why each).

1. **Which section carries the torque of each mode**: the linear forced response to a 1 N·m motor
   torque at each eigenfrequency (:func:`flexshaft.forced_response`).
2. **Mode 1 at growing drive**: a stepped sine around mode 1 at several motor-torque amplitudes
   (:func:`flexshaft.analysis.amplitude.stepped_sine`): its apparent frequency drops as the coupling
   slips for more of each cycle. Every law is positively homogeneous, so only the ratio of drive to
   slip torque matters; **a fit** (Brent's method on the amplitude) finds the ratio that gives the
   measured −23.25 %.
3. **Mode 2 while mode 1 slips the coupling**: at that drive, mode 2 probed by a small second sine
   while the drive keeps mode 1 at its apparent resonance (``pump``): its apparent frequency moves a
   few per cent - by how much depends on the probe's amplitude, since a coupling that sticks and slips
   twice a mode-1 cycle makes mode 2's stiffness periodic rather than merely lower.
4. **The static explanations**: part 2 at 40 % of its stiffness (the one the study rejected) moves
   mode 2 further than mode 1; part 3 softened until mode 1 drops 23.25 % moves mode 2 by about 5 %.
   The slipping coupling, fitted on mode 1 alone, moves mode 2 by about 4 % - the bench measured 3 %.

Not run when these pages are built: its some 400 stepped-sine runs and two fits take about 50 s; run
it yourself (below).

.. code-block:: text

    python examples/customer2_slip.py            # about 50 s of stepped-sine runs; prints the comparison
    python examples/customer2_slip.py OUT_DIR    # also writes mode1_curves.png and mode2_pumped.png
"""

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

import flexshaft as fs
from flexshaft.analysis.amplitude import stepped_sine

# The model file beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else None

#: The measured shifts of Customer 2's first two torsional eigenfrequencies (the study, chapter 10).
MEASURED = {1: -0.2325, 2: -0.0305}
#: Read where the bench reads a line's motion: the generator's speed (across the chain: no anti-resonance).
MEASURE = "speed:generator"

# %%
# The model and what each mode puts through the coupling
# ------------------------------------------------------
# The linear analyses use the coupling stuck. The forced response to 1 N·m at the motor, at each
# eigenfrequency, gives the peak torque in each section per N·m of drive.

drivetrain = fs.load_model(HERE / "customer2_slip.toml")
result = fs.modal_analysis(drivetrain)
slip = drivetrain.component("part 3").slip_torque
f_linear = {k: float(result.frequencies_hz[k]) for k in (1, 2)}
forced = fs.forced_response(result, "motor", amplitude=1.0)
print(f"{drivetrain.name}: part 3 slips at {slip:g} N·m")
for k in (1, 2):
    ex = next(e for e in forced.to_dict()["excitations"] if e["mode"] == k)
    torque = ex["amplitude"]["torque:part 3"]
    print(
        f"  mode {k} at {f_linear[k]:.3f} Hz: part 3 carries {torque:.4g} N·m per N·m of motor torque"
        f" (largest: {ex['largest_torque']})"
    )

# %%
# Mode 1 at growing drive, and the fit
# ------------------------------------
# A stepped sine around mode 1 (11 frequencies, the peak's bracket halved 5 times) at drive
# amplitudes from one that never slips to several that do. Then Brent's method on the drive amplitude
# for the measured −23.25 %: each step one more stepped sine.


def mode1_shift(amplitude: float) -> float:
    """Mode 1's apparent frequency shift (fraction) with the motor driven at ``amplitude`` N·m."""
    sweep = stepped_sine(result, [amplitude], modes=[1], points=11, refine=5, measure=MEASURE)
    return float(sweep.shift[0, 0])


ladder = stepped_sine(result, [5.0, 100.0, 300.0, 600.0], modes=[1], points=11, refine=5, measure=MEASURE)
print(ladder.table())
drive = brentq(lambda a: mode1_shift(a) - MEASURED[1], 600.0, 1500.0, rtol=1e-3)
fitted = stepped_sine(result, [drive], modes=[1], points=11, refine=5, measure=MEASURE)
f1_apparent = float(fitted.apparent_hz[0, 0])
print(
    f"fit: a motor torque of {drive:.4g} N·m at mode 1 ({drive / slip:.3g} × the slip torque) puts mode 1 at"
    f" {f1_apparent:.3f} Hz ({fitted.shift[0, 0]:+.2%}; measured {MEASURED[1]:+.2%}); the coupling slips"
    f" {fitted.active[0, 0].max():.0%} of the time there"
)

# %%
# Mode 2 while mode 1 slips the coupling
# --------------------------------------
# The drive goes on at mode 1's apparent frequency with the fitted amplitude (the pump), and a probe
# sine of 5 % and 20 % of it steps around mode 2. Its apparent frequency: a few per cent down.

pumped = stepped_sine(
    result,
    [0.05 * drive, 0.2 * drive],
    modes=[2],
    points=11,
    refine=5,
    measure=MEASURE,
    pump=(drive, f1_apparent),
)
shift2 = pumped.shift[:, 0]
print(pumped.table())
print(
    f"mode 2 with mode 1 slipping the coupling: {np.nanmin(shift2):+.2%} … {np.nanmax(shift2):+.2%}"
    f" (probe 5 … 20 % of the drive; measured {MEASURED[2]:+.2%}); driven alone, mode 2 does not slip it"
)

# %%
# The static explanation
# ----------------------
# A stiffness that is just lower, no slip: part 2 at 40 % of its stiffness; and part 3 softened until
# mode 1 drops by the measured 23.25 % (Brent's method on its stiffness).


def static_shifts(name: str, factor: float) -> np.ndarray:
    """Modes 1 and 2's shifts with component ``name``'s stiffness times ``factor`` (linear model)."""
    comps = tuple(
        replace(c, stiffness=c.stiffness * factor) if c.name == name else c for c in drivetrain.components
    )
    f = fs.modal_analysis(replace(drivetrain, components=comps)).frequencies_hz
    return np.array([f[1] / f_linear[1] - 1, f[2] / f_linear[2] - 1])


part2 = static_shifts("part 2", 0.4)
factor3 = brentq(lambda x: static_shifts("part 3", x)[0] - MEASURED[1], 0.1, 1.0, rtol=1e-9)
part3 = static_shifts("part 3", factor3)
print("static stiffness changes (no slip):")
print(f"  part 2 at 40 %:            mode 1 {part2[0]:+.2%}, mode 2 {part2[1]:+.2%}")
print(f"  part 3 at {factor3:.0%} (fitted):    mode 1 {part3[0]:+.2%}, mode 2 {part3[1]:+.2%}")
print(
    f"measured: mode 1 {MEASURED[1]:+.2%}, mode 2 {MEASURED[2]:+.2%}; the slipping coupling: mode 1"
    f" {fitted.shift[0, 0]:+.2%}, mode 2 {np.nanmin(shift2):+.2%} … {np.nanmax(shift2):+.2%}"
)

# %%
# The response curves
# -------------------
# Mode 1's curves at each drive amplitude (the peak moving down and flattening as the coupling slips),
# and mode 2's under the pump.

curves = ladder.plot()
curves2 = pumped.plot()
if OUT is not None:
    OUT.mkdir(parents=True, exist_ok=True)
    curves.savefig(OUT / "mode1_curves.png", dpi=120)
    curves2.savefig(OUT / "mode2_pumped.png", dpi=120)
    print(f"pictures: {OUT / 'mode1_curves.png'}, {OUT / 'mode2_pumped.png'}")

"""
A run-up, simulated and analysed as measured data would be
===========================================================

Customer 1 (:download:`customer1.toml <../../examples/customer1.toml>`) is run from 0 to 1800 rpm in
100 s with the speed loop closed (PI gains tuned from the model, 2 ms low-pass to the air-gap torque,
1500 N·m limit), a 6th-order torque ripple from the drive and some broadband noise. The coupling
torque and the motor speed, sampled at 1 kHz, go through the spectrogram against speed; the
Campbell diagram says where the 6th order meets a mode, and the spectrogram shows the coupling
torque rising there.

.. code-block:: text

    python examples/run_up.py            # prints the crossings and what the spectrogram shows
    python examples/run_up.py OUT_DIR    # also writes run_up.csv, spectrogram.png and campbell.png
"""

import sys
from pathlib import Path

import numpy as np

import flexshaft as fs
from flexshaft.analysis.simulate import RPM
from flexshaft.views.plots import spectrogram_figure

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else None

# %%
# The run
# -------
# The speed loop's gains come from the model's modes; the scenario is a speed ramp with the drive's
# ripple; :func:`flexshaft.simulate` solves the closed loop and samples the named outputs at 1 kHz.

result = fs.modal_analysis(fs.load_model(HERE / "customer1.toml"))
control = fs.SpeedControl.tuned(result, tau=0.002, torque_min=-1500.0, torque_max=1500.0)
scenario = fs.Scenario.ramp(1800.0, 100.0, control, ripple=30.0, ripple_order=6, noise=20.0, seed=7)
run = fs.simulate(result, scenario, ["torque:part 3", "speed:motor", "control:torque"], rate=1000.0)
print(f"run-up: {run.time[-1]:.0f} s at {run.rate_hz:g} Hz, {run.method}")
print(f"  speed loop: kp {control.kp:.4g} N·m·s/rad, ki {control.ki:.4g} N·m/rad")

# %%
# Where the 6th order meets the modes
# -----------------------------------
# The Campbell diagram's crossings, and at each the coupling torque's 6th-order line in the
# spectrogram (1 s segments, each at the speed measured over it): its ridge follows the mode's
# frequency and its amplitude peaks at the crossing's speed.

diagram = fs.campbell(result, (0.0, 1800.0), (6,))
speed_rpm = run.outputs["speed:motor"] / RPM
sg = fs.spectrogram(run.outputs["torque:part 3"], run.rate_hz, segment=1.0, speed=speed_rpm)
print("6th order crossing the modes (Campbell) and the coupling torque's 6th-order line there:")
for c in diagram.crossings:
    line = fs.ridge(sg, c.frequency_hz - 5, c.frequency_hz + 5)
    at = int(np.argmin(np.abs(sg.speed_rpm - c.speed_rpm)))
    k = int(np.argmin(np.abs(sg.frequencies_hz - c.frequency_hz)))
    print(
        f"  mode {c.mode} ({c.frequency_hz:.2f} Hz) at {c.speed_rpm:.0f} rpm: ridge {line[at]:.2f} Hz, "
        f"amplitude {sg.amplitude[k, at]:.3g} N·m"
    )

# %%
# The pictures
# ------------
# The spectrogram with the orders 1, 2 and 6 and the eigenfrequencies drawn over it, and the
# Campbell diagram.

# sphinx_gallery_thumbnail_number = 1
spectrogram = spectrogram_figure(sg, orders=(1, 2, 6), eigenfrequencies=diagram.frequencies_hz[0], max_hz=300)
crossings = diagram.plot()

# %%
# With ``OUT_DIR``: the run's signals as CSV (``flexshaft spectrum`` reads them) and both pictures.

if OUT is not None:
    OUT.mkdir(parents=True, exist_ok=True)
    columns = {name: (y, run.units[name]) for name, y in run.outputs.items()}
    fs.write_signals(OUT / "run_up.csv", run.time, columns, overwrite=True)
    spectrogram.savefig(OUT / "spectrogram.png")
    crossings.savefig(OUT / "campbell.png")
    print(f"written: {OUT / 'run_up.csv'}, {OUT / 'spectrogram.png'}, {OUT / 'campbell.png'}")

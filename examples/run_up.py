"""A test-bench run-up, simulated and analysed as measured data would be.

Customer 1 is run from 0 to 1800 rpm in 100 s with the speed loop closed (PI gains tuned from the
model, 2 ms low-pass to the air-gap torque, 1500 N·m limit), a 6th-order torque ripple from the
drive and some broadband noise. The coupling torque and the motor speed, sampled at 1 kHz, go
through the spectrogram against speed; the Campbell diagram says where the 6th order meets a
mode, and the spectrogram shows the coupling torque rising there.

    python examples/run_up.py            # prints the crossings and what the spectrogram shows
    python examples/run_up.py OUT_DIR    # also writes run_up.csv, spectrogram.png and campbell.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import flexshaft as fs
from flexshaft.analysis.simulate import RPM

HERE = Path(__file__).resolve().parent


def main(out: Path | None = None) -> None:
    result = fs.modal_analysis(fs.load_model(HERE / "customer1.toml"))
    control = fs.SpeedControl.tuned(result, tau=0.002, torque_min=-1500.0, torque_max=1500.0)
    scenario = fs.Scenario.ramp(1800.0, 100.0, control, ripple=30.0, ripple_order=6, noise=20.0, seed=7)
    run = fs.simulate(result, scenario, ["torque:part 3", "speed:motor", "control:torque"], rate=1000.0)
    print(f"run-up: {run.time[-1]:.0f} s at {run.rate_hz:g} Hz, {run.method}")
    print(f"  speed loop: kp {control.kp:.4g} N·m·s/rad, ki {control.ki:.4g} N·m/rad")

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
    if out is not None:
        from flexshaft.views.plots import campbell_figure, spectrogram_figure

        out.mkdir(parents=True, exist_ok=True)
        columns = {name: (y, run.units[name]) for name, y in run.outputs.items()}
        fs.write_signals(out / "run_up.csv", run.time, columns, overwrite=True)
        fig = spectrogram_figure(sg, orders=(1, 2, 6), eigenfrequencies=diagram.frequencies_hz[0], max_hz=300)
        fig.savefig(out / "spectrogram.png")
        campbell_figure(diagram).savefig(out / "campbell.png")
        print(f"written: {out / 'run_up.csv'}, {out / 'spectrogram.png'}, {out / 'campbell.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else None)

"""
The bench's recordings, made
============================

Recordings of the three test-bench set-ups
(:download:`without_dut_cad.toml <../../examples/without_dut_cad.toml>`,
:download:`customer1_cad.toml <../../examples/customer1_cad.toml>`,
:download:`customer2_cad.toml <../../examples/customer2_cad.toml>`), as the bench's torque flange and
encoders would record them, for :download:`bench_study.toml <../../examples/bench_study.toml>` to
identify and calibrate from. The "bench" is the published model with
a few stiffnesses off by a few per cent - as a real bench differs from its drawings - and the study
must find them again:

- part 1 +3 %, part 2 +4 % (the shared parts, in every set-up), part 3 (the DUT coupling) -6 %;
- 0.53 % damping on every elastic mode (the study's measured mean, its Tables 1-2);
- a random motor torque (white, 2 kN·m standard deviation, held over each sample) about its mean;
- three runs per set-up of 150 s at 1280 Hz: ``torque flange`` (N·m, part 2's torque flange) and
  ``speed generator`` (rpm; ``speed end`` on Without DUT, which has no generator), with 2 % sensor
  noise; Without DUT and Customer 2 as TDMS, Customer 1 as MDF 4.

The simulation is exact for the held torque: the bench's modes below 800 Hz (flexshaft assembles the
bench's drivetrain; its output rows come from :func:`flexshaft.state_space`), each a second-order
system discretised with a zero-order hold (``examples/operational_run.py``'s ``modal_run``), not
flexshaft's ``simulate``. The modes above 800 Hz, far above the 300 Hz studied and the recorder's
640 Hz Nyquist frequency, are left out (a recorder's anti-alias filter removes them too).

The recordings are made on first use, never downloaded: ``python examples/bench_recordings.py [DIR]``
writes them into ``DIR`` (default ``examples/recordings/``, git-ignored) with ``bench.json``, the
bench's true values; a second run with the same settings finds them and does nothing.

.. note::
   Not run when these pages are built: it writes 31 MB of recordings (about 3 s). Run it yourself:
   ``python examples/bench_recordings.py``, then ``flexshaft study examples/bench_study.toml -o DIR``
   (needs ``pip install 'flexshaft[measured]'`` for the TDMS and MDF 4 files).
"""

import json
import sys
from pathlib import Path

import numpy as np

import flexshaft as fs

# The model files beside this script (the gallery and notebooks run it without __file__, in its folder).
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
sys.path.insert(0, str(HERE))
from operational_run import modal_run  # noqa: E402 - the sibling example's exact simulation

# %%
# The bench
# ---------
# How it differs from the model files, and how it is recorded.

#: The set-ups: model file, the files' format, and the channel recording the far end's speed.
SETUPS = {
    "Without DUT": ("without_dut_cad.toml", ".tdms", ("speed end", "part 2 end")),
    "Customer 1": ("customer1_cad.toml", ".mf4", ("speed generator", "generator")),
    "Customer 2": ("customer2_cad.toml", ".tdms", ("speed generator", "generator")),
}
#: How the bench differs from the model files (relative change of each stiffness it has).
CHANGES = {"part 1.stiffness": 0.03, "part 2.stiffness": 0.04, "part 3.stiffness": -0.06}
DAMPING_RATIO = 0.0053
RATE = 1280.0  # Hz: Nyquist 640 Hz, at least 2.5 x the 250 Hz identified (identify's decimation rule)
SECONDS = 150.0
RUNS = 3
DRIVE_STD = 2000.0  # N·m
NOISE = 0.02
CUTOFF_HZ = 800.0
MAX_HZ = 300.0  # the study's range: every set-up meshed for it
SEED = 2026
SETTINGS = {
    "changes": CHANGES,
    "damping_ratio": DAMPING_RATIO,
    "rate_hz": RATE,
    "seconds": SECONDS,
    "runs": RUNS,
    "drive_std": DRIVE_STD,
    "noise": NOISE,
    "cutoff_hz": CUTOFF_HZ,
    "seed": SEED,
    "version": 1,
}


# %%
# The recordings
# --------------
# Each set-up's bench assembled by flexshaft, its modes run exactly for a held random torque, the
# torque flange and the far end's encoder recorded with noise.


def bench_of(setup: str):
    """The set-up's drivetrain as the model file gives it, and as the bench is (its stiffnesses moved)."""
    model = fs.mesh_for_range(fs.load_model(HERE / SETUPS[setup][0]), MAX_HZ).drivetrain
    from flexshaft.analysis.parameters import parameter_value

    names = {p.name for p in fs.parameters(model)}
    nominal = {n: parameter_value(model, n) for n in CHANGES if n in names}
    true = {n: v * (1 + CHANGES[n]) for n, v in nominal.items()}
    return model, fs.with_parameters(model, true), nominal, true


def record(setup: str, bench, seed: int) -> tuple[np.ndarray, dict]:
    """One run of ``bench`` (a Drivetrain): ``torque flange`` (N·m) and the far end's speed (rpm)."""
    far_channel, far_station = SETUPS[setup][2]
    result = fs.modal_analysis(fs.assemble(bench), damped=False)
    system = fs.state_space(
        result, ["motor"], ["torque:part 2: torque flange", f"speed:{far_station}"], max_hz=CUTOFF_HZ
    )
    m = system.frequencies_hz.size
    omega = 2 * np.pi * system.frequencies_hz
    omega[omega < 1e-6 * omega.max()] = 0.0  # the free spin
    rng = np.random.default_rng(seed)
    dt = 1 / RATE
    lowest = omega[omega > 0].min()
    warm = int(10 / (DAMPING_RATIO * lowest) * RATE)  # ten decay times of the slowest mode
    n = int(SECONDS * RATE)
    drive = DRIVE_STD * rng.standard_normal(n + warm)
    q, qd = modal_run(omega, DAMPING_RATIO, system.B[m:, 0], drive, dt, warm)
    y = system.C[:, :m] @ q + system.C[:, m:] @ qd
    elastic = omega > 0
    vibration = system.C[1, m:][elastic] @ qd[elastic]  # the speed without the spin's random walk
    to_rpm = 60 / (2 * np.pi)
    columns = {}
    for name, x, level, scale, unit in (
        ("torque flange", y[0], np.std(y[0]), 1.0, "N·m"),
        (far_channel, y[1], np.std(vibration), to_rpm, "rpm"),
    ):
        columns[name] = (scale * (x + NOISE * level * rng.standard_normal(n)), unit)
    return np.arange(n) * dt, columns


def exact_modes(bench) -> list:
    """The bench's elastic natural frequencies up to the study's range, Hz (undamped)."""
    result = fs.modal_analysis(fs.assemble(bench), damped=False)
    return [float(f) for f, r in zip(result.frequencies_hz, result.rigid) if not r and f <= MAX_HZ]


def ensure_recordings(folder=None, progress=print) -> dict:
    """The recordings in ``folder`` (default ``examples/recordings``), made unless there with these
    settings; returns the manifest (``bench.json``): per set-up its files, the nominal and the true
    stiffnesses (N·m/rad) and the bench's exact modes (Hz)."""
    folder = Path(folder) if folder is not None else HERE / "recordings"
    manifest_path = folder / "bench.json"
    if manifest_path.is_file():
        try:
            manifest = json.loads(manifest_path.read_text())
        except ValueError:
            manifest = {}
        files = [folder / f for s in manifest.get("setups", {}).values() for f in s["files"]]
        if manifest.get("settings") == SETTINGS and files and all(f.is_file() for f in files):
            return manifest
    folder.mkdir(parents=True, exist_ok=True)
    manifest = {"units": {"stiffness": "N·m/rad", "frequency": "Hz"}, "settings": SETTINGS, "setups": {}}
    for k, setup in enumerate(SETUPS):
        model, bench, nominal, true = bench_of(setup)
        files = []
        for run in range(RUNS):
            time, columns = record(setup, bench, SEED + 10 * k + run)
            name = f"{setup.lower().replace(' ', '-')}-run{run + 1}{SETUPS[setup][1]}"
            fs.write_measured(folder / name, time, columns, overwrite=True)
            files.append(name)
            progress(f"recorded {setup!r} run {run + 1} of {RUNS}: {folder / name}")
        manifest["setups"][setup] = {
            "model": SETUPS[setup][0],
            "files": files,
            "nominal": nominal,
            "true": true,
            "exact_modes_hz": exact_modes(bench),
        }
    manifest_path.write_text(json.dumps(manifest, indent=1, ensure_ascii=False))
    return manifest


# %%
# Made, or found from an earlier run
# ----------------------------------

if __name__ == "__main__":
    out = ensure_recordings(sys.argv[1] if len(sys.argv) > 1 else None)
    for setup, s in out["setups"].items():
        truth = ", ".join(f"{n} {v:.6g}" for n, v in s["true"].items())
        print(f"{setup}: {len(s['files'])} runs; bench: {truth} N·m/rad; modes {s['exact_modes_hz']} Hz")

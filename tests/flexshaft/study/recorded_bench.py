"""A known bench, recorded: the truth a study's ``[[measurement]]`` is checked against.

Four inertias on three massless shafts, free at both ends (SI: kg·m², N·m/rad). The *bench* differs
from its *model file* in two stiffnesses (part 2 +5 %, part 3 -6 %), as a real bench differs from its
drawings. Every elastic mode is damped ``ZETA`` (modal damping C = M Φ diag(2ζω) Φᵀ M, Φ
mass-normalised: the free spin stays undamped). A white-noise torque on the motor, held over each
sample, drives it.

The simulation is exact and independent of flexshaft (and of ``examples/operational_run.py``'s modal
method): the first-order system x' = A x + B u is discretised with a zero-order hold by the matrix
exponential of the augmented matrix [[A, B], [0, 0]] (``scipy.linalg.expm``), exact at the samples for
a held input, and stepped sample by sample. The truth is ``scipy.linalg.eigh`` on the bench's (K, M).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

import flexshaft as fs

INERTIAS = {"motor": 2.0, "hub": 0.3, "flange": 0.5, "generator": 0.2}
MODEL_STIFFNESS = {"part 1": 1.5e4, "part 2": 8.0e4, "part 3": 2.5e4}
BENCH_STIFFNESS = {"part 1": 1.5e4, "part 2": 8.4e4, "part 3": 2.35e4}  # part 2 +5 %, part 3 -6 %
ZETA = 0.01
RATE = 2000.0  # Hz
DRIVE_STD = 40.0  # N·m per sample
NOISE = 0.02  # sensor noise: this fraction of each channel's vibration


def matrices(stiffness: dict) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the free chain motor - hub - flange - generator."""
    m = np.diag(list(INERTIAS.values()))
    k = np.zeros((4, 4))
    for i, ki in enumerate(stiffness.values()):
        k[i : i + 2, i : i + 2] += ki * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return m, k


def bench_modes() -> np.ndarray:
    """The bench's elastic natural frequencies, Hz (the truth)."""
    m, k = matrices(BENCH_STIFFNESS)
    w2 = scipy.linalg.eigh(k, m, eigvals_only=True)
    return np.sqrt(w2[1:]) / (2 * np.pi)


def model_text() -> str:
    """The model file: the bench as drawn (its nominal stiffnesses)."""
    names = list(INERTIAS)
    lines = ['[model]\nname = "recorded bench"\nmax_hz = 300.0\n']
    for i, name in enumerate(names):
        lines.append(f'[[chain]]\nname = "{name}"\ntype = "rigid"\ninertia = {INERTIAS[name]!r}\n')
        if i < 3:
            part = f"part {i + 1}"
            lines.append(
                f'[[chain]]\nname = "{part}"\ntype = "coupling"\nstiffness = {MODEL_STIFFNESS[part]!r}\n'
                "inertia = 0.0\n"
            )
    return "\n".join(lines)


def _held(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation: expm([[A, B], [0, 0]]·dt) = [[Ad, Bd], [0, I]]."""
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    e = scipy.linalg.expm(aug * dt)
    return e[:n, :n], e[:n, n:]


def record(seed: int, seconds: float) -> tuple[np.ndarray, dict]:
    """One run as the bench records it: ``torque flange`` (part 2's torque, N·m), ``speed motor`` and
    ``speed generator`` (rpm), with sensor noise; a warm-up of ten decay times of mode 1 dropped."""
    m, k = matrices(BENCH_STIFFNESS)
    w2, phi = scipy.linalg.eigh(k, m)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    c = m @ phi @ np.diag(2 * ZETA * omega * (omega > 1e-6 * omega.max())) @ phi.T @ m
    minv = np.linalg.inv(m)
    a = np.block([[np.zeros((4, 4)), np.eye(4)], [-minv @ k, -minv @ c]])
    b = np.concatenate([np.zeros(4), minv[:, 0]])[:, None]  # the torque acts on the motor
    dt = 1 / RATE
    ad, bd = _held(a, b, dt)
    rng = np.random.default_rng(seed)
    warm = int(10 / (ZETA * omega[1]) * RATE)
    n = int(seconds * RATE)
    u = DRIVE_STD * rng.standard_normal(warm + n)
    x = np.zeros(8)
    states = np.empty((n, 8))
    for i in range(warm + n):
        if i >= warm:
            states[i - warm] = x
        x = ad @ x + bd[:, 0] * u[i]
    theta, speed = states[:, :4].T, states[:, 4:].T
    to_rpm = 60 / (2 * np.pi)
    spin = speed.mean(axis=0)  # the rigid spin's random walk: no part of the vibration
    clean = {
        "torque flange": (BENCH_STIFFNESS["part 2"] * (theta[1] - theta[2]), "N·m", None),
        "speed motor": (to_rpm * speed[0], "rpm", to_rpm * (speed[0] - spin)),
        "speed generator": (to_rpm * speed[3], "rpm", to_rpm * (speed[3] - spin)),
    }
    columns = {}
    for name, (x_, unit, vibration) in clean.items():
        level = np.std(x_ if vibration is None else vibration)
        columns[name] = (x_ + NOISE * level * rng.standard_normal(n), unit)
    return np.arange(n) * dt, columns


def write_runs(folder, seeds=(1, 2, 3), seconds: float = 60.0, suffixes=(".tdms", ".mf4", ".csv")) -> list:
    """One run per seed, written in turn as TDMS, MDF 4 and CSV: ``folder/run<seed><suffix>``."""
    paths = []
    for seed, suffix in zip(seeds, suffixes * len(seeds)):
        time, columns = record(seed, seconds)
        path = folder / f"run{seed}{suffix}"
        if suffix == ".csv":
            fs.write_signals(path, time, columns, overwrite=True)
        else:
            fs.write_measured(path, time, columns, overwrite=True)
        paths.append(path)
    return paths

"""
An operational run, identified
==============================

A free three-inertia torsional line driven by white noise, simulated exactly, recorded as a test
bench would record it, and its modes identified from the record alone (SSI-COV) - beside the true
ones.

The line: inertias J = 0.30, 0.05, 0.40 kg·m² joined by massless shafts k1 = 2.0e4 and k2 = 1.5e4
N·m/rad, free at both ends. Its elastic modes lie at 35.48 and 138.24 Hz (``scipy.linalg.eigh`` on
(K, M), printed exactly below), each damped 0.53 % (modal damping C = M Φ diag(2ζω) Φᵀ M with
mass-normalised Φ: the rigid-body spin stays undamped). A white-noise torque drives inertia 1,
constant over each sample (a zero-order hold); the bench records at 2 kHz for 300 s the two shaft
torques k1(θ1 − θ2), k2(θ2 − θ3) (``torque s1``, ``torque s2``, N·m) and the three speeds
(``speed 1..3``, rad/s), each with 2 % sensor noise. The speeds carry the rigid-body drift: the
drive's net torque has no mean but integrates to a random walk of the line's spin.

The simulation is exact and uses numpy and scipy only (not flexshaft's models): modal
decomposition, each elastic mode a second-order system discretised with a zero-order hold
(``scipy.signal.cont2discrete``, exact for the held input) and run by ``scipy.signal.lfilter``, the
rigid mode the held double integrator as cumulative sums. The model is in the script: there is no
model file to download; ``OUT_DIR`` below gets one.

.. code-block:: text

    python examples/operational_run.py           # identifies the modes, prints them beside the truth
    python examples/operational_run.py OUT_DIR   # also writes operational_run.csv (and .tdms, .mf4
                                                 # with the measured extra), line.toml and
                                                 # stabilisation.png there

The tests take the functions of this script (the simulation) without running it: what it does when
run is under ``if __name__ == "__main__"``.
"""

import sys
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.signal

import flexshaft as fs
from flexshaft.measurement.identify import identify_modes

# %%
# The line and its exact modes
# ----------------------------
# Three inertias on two massless shafts, free at both ends: its modes are the generalised eigenproblem
# of (K, M), solved by ``scipy.linalg.eigh`` (mass-normalised shapes). They are the truth the
# identification is measured against.

#: The line (kg·m², N·m/rad) and its modal damping (fraction), as in the docstring.
INERTIAS = (0.30, 0.05, 0.40)
STIFFNESSES = (2.0e4, 1.5e4)
DAMPING_RATIO = 0.0053
#: The drive torque's standard deviation per sample, N·m: the shaft torques come out at tens of N·m.
DRIVE_STD = 40.0
TORQUES = ("torque s1", "torque s2")
SPEEDS = ("speed 1", "speed 2", "speed 3")


def line_matrices():
    """The line's mass and stiffness matrices (kg·m², N·m/rad), degrees of freedom θ1, θ2, θ3."""
    m = np.diag(INERTIAS)
    k1, k2 = STIFFNESSES
    k = np.array([[k1, -k1, 0.0], [-k1, k1 + k2, -k2], [0.0, -k2, k2]])
    return m, k


def true_modes():
    """The exact elastic modes of the line.

    Returns
    -------
    dict
        ``frequencies_hz`` (2,), ``damping_ratios`` (2,), ``angle_shapes`` (3, 2: θ per mode,
        mass-normalised), ``speed_shapes`` (the speeds' shape is the angles' shape: a speed is iω
        times its angle in every mode) and ``torque_shapes`` (2, 2: k1(θ1 − θ2), k2(θ2 − θ3)), plus
        ``omega`` (rad/s, all three modes, the rigid one 0) and ``phi`` (3, 3) for the simulation.
    """
    m, k = line_matrices()
    w2, phi = scipy.linalg.eigh(k, m)  # mass-normalised: Φᵀ M Φ = I
    omega = np.sqrt(np.clip(w2, 0.0, None))
    omega[0] = 0.0  # the free line's spin: exactly 0, eigh gives round-off
    elastic = phi[:, 1:]
    k1, k2 = STIFFNESSES
    torque = np.vstack([k1 * (elastic[0] - elastic[1]), k2 * (elastic[1] - elastic[2])])
    return {
        "frequencies_hz": omega[1:] / (2.0 * np.pi),
        "damping_ratios": np.full(2, DAMPING_RATIO),
        "angle_shapes": elastic,
        "speed_shapes": elastic,
        "torque_shapes": torque,
        "omega": omega,
        "phi": phi,
    }


# %%
# The simulation
# --------------
# Each elastic mode is a second-order system driven by the held torque, discretised exactly with a
# zero-order hold and run by ``scipy.signal.lfilter``; the rigid spin is the held double integrator.
# The record starts after ten decay times, so it is stationary from its first sample.


def _held_mode(omega: float, zeta: float, gain: float, dt: float):
    """Transfer functions (b, a) from a held input to the modal coordinate q and to its rate q̇ of
    q̈ + 2ζωq̇ + ω²q = gain·u, exact at the samples for u constant over each step."""
    a = np.array([[0.0, 1.0], [-(omega**2), -2.0 * zeta * omega]])
    b = np.array([[0.0], [gain]])
    ad, bd, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), dt, method="zoh")
    out = []
    for row in np.eye(2):
        num, den = scipy.signal.ss2tf(ad, bd, row[None, :], np.zeros((1, 1)))
        out.append((num[0], den))
    return out


def modal_response(m, k, zeta, drive, dt: float, dof: int = 0, warm: int = 0):
    """The exact response of a free or held line (M, K) with modal damping to a held torque.

    Each elastic mode (``scipy.linalg.eigh`` on (K, M), mass-normalised) is a second-order system
    run by :func:`_held_mode`; a rigid mode (ω = 0) is the held double integrator as cumulative sums.

    Parameters
    ----------
    m, k : ndarray (n, n)
        Mass (kg·m²) and stiffness (N·m/rad) matrices.
    zeta : float or sequence of float
        Damping ratio of every elastic mode, or one per mode (rigid modes take none: give one per
        mode, lowest first, and the rigid ones' entries are ignored).
    drive : ndarray (samples,)
        Torque on degree of freedom ``dof``, N·m, held over each sample.
    dt : float
        Sample step, s.
    dof : int
        The driven degree of freedom.
    warm : int
        Samples run first and dropped (a stationary record from its first kept sample).

    Returns
    -------
    theta, speed : ndarray (n, samples - warm)
        Angles (rad) and speeds (rad/s) of the degrees of freedom.
    vibration : ndarray (n, samples - warm)
        The speeds without the rigid modes (what sets a speed channel's noise level).
    omega : ndarray (n,)
        Every mode's circular frequency, rad/s (rigid ones 0).
    """
    w2, phi = scipy.linalg.eigh(k, m)  # mass-normalised: Φᵀ M Φ = I
    omega = np.sqrt(np.clip(w2, 0.0, None))
    omega[w2 < 1e-9 * w2.max()] = 0.0  # a free line's spin: 0 up to eigh's round-off
    q, qd = modal_run(omega, zeta, phi[dof], drive, dt, warm)
    rigid = omega == 0.0
    return phi @ q, phi @ qd, phi[:, ~rigid] @ qd[~rigid], omega


def modal_run(omega, zeta, gains, drive, dt: float, warm: int = 0):
    """Modal coordinates q and rates q̇ of q̈_r + 2ζ_r ω_r q̇_r + ω_r² q_r = g_r·u, exact at the samples for
    u held over each one (:func:`_held_mode`); a mode of ω = 0 is the held double integrator.

    Parameters
    ----------
    omega : ndarray (modes,)
        Circular frequencies, rad/s (0: a rigid mode).
    zeta : float or ndarray (modes,)
        Damping ratios (a rigid mode's is ignored).
    gains : ndarray (modes,)
        g_r: each mode's share of the input (a mass-normalised shape's value where the torque acts).
    drive : ndarray (samples,)
        The held input (N·m).
    dt : float
        Sample step, s.
    warm : int
        Samples run first and dropped.

    Returns
    -------
    q, qd : ndarray (modes, samples - warm)
    """
    zetas = np.broadcast_to(np.asarray(zeta, dtype=float), omega.shape)
    n = drive.size - warm
    q, qd = np.empty((omega.size, n)), np.empty((omega.size, n))
    for r in range(omega.size):
        g = gains[r] * drive
        if omega[r] == 0.0:  # q̇[k+1] = q̇[k] + dt·g[k], q[k+1] = q[k] + dt·q̇[k] + dt²/2·g[k]
            rate = dt * np.concatenate([[0.0], np.cumsum(g)[:-1]])
            angle = np.concatenate([[0.0], np.cumsum(dt * rate[:-1] + 0.5 * dt**2 * g[:-1])])
            q[r], qd[r] = angle[warm:], rate[warm:]
            continue
        (bq, aq), (bv, av) = _held_mode(omega[r], zetas[r], gains[r], dt)
        q[r] = scipy.signal.lfilter(bq, aq, drive)[warm:]
        qd[r] = scipy.signal.lfilter(bv, av, drive)[warm:]
    return q, qd


def operational_run(seed: int = 1, duration: float = 300.0, rate: float = 2000.0, noise: float = 0.02):
    """Simulate the line driven by white noise, as the bench would record it.

    Parameters
    ----------
    seed : int
        Seed of the drive torque and the sensor noise (numpy's default Generator).
    duration : float
        Record length, s (a further 10 decay times run first and are dropped, so the record is
        stationary from its first sample).
    rate : float
        Sampling rate, Hz.
    noise : float
        Sensor noise: white, its standard deviation this fraction of each channel's vibration (the
        channel's standard deviation without the rigid-body drift, which would otherwise set a speed's
        noise by how far the line happened to wander).

    Returns
    -------
    time : ndarray (n,)
        s, from 0.
    columns : dict of str to ndarray
        ``torque s1``, ``torque s2`` (N·m) and ``speed 1..3`` (rad/s).
    units : dict of str to str
        Each column's unit.
    truth : dict
        :func:`true_modes`.
    """
    truth = true_modes()
    omega = truth["omega"]
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate
    n = int(round(duration * rate))
    warm = int(round(10.0 / (DAMPING_RATIO * omega[1]) * rate))  # ten decay times of the slowest mode
    drive = DRIVE_STD * rng.standard_normal(n + warm)  # N·m on inertia 1, held over each sample
    theta, speed, vibration, _ = modal_response(*line_matrices(), DAMPING_RATIO, drive, dt, 0, warm)
    k1, k2 = STIFFNESSES
    clean = {
        "torque s1": k1 * (theta[0] - theta[1]),
        "torque s2": k2 * (theta[1] - theta[2]),
        "speed 1": speed[0],
        "speed 2": speed[1],
        "speed 3": speed[2],
    }
    scale = {"torque s1": None, "torque s2": None, "speed 1": 0, "speed 2": 1, "speed 3": 2}
    columns = {}
    for name, x in clean.items():
        level = np.std(x) if scale[name] is None else np.std(vibration[scale[name]])
        columns[name] = x + noise * level * rng.standard_normal(n)
    units = {name: ("N·m" if name in TORQUES else "rad/s") for name in columns}
    return np.arange(n) * dt, columns, units, truth


# %%
# The same line as a model file and as a data logger's files, for the ``OUT_DIR`` run (``flexshaft
# modes OUT_DIR/line.toml`` gives the true frequencies; ``flexshaft identify`` reads the files).


def model_text() -> str:
    """The line as a flexshaft model file (numbers only: three inertias, two massless shafts)."""
    j1, j2, j3 = INERTIAS
    k1, k2 = STIFFNESSES
    return f"""# The free three-inertia line of examples/operational_run.py (SI: kg·m², N·m/rad).
# Its elastic modes: {true_modes()["frequencies_hz"][0]:.4f} and {true_modes()["frequencies_hz"][1]:.4f} Hz.

[model]
name = "operational line"

[[chain]]
name = "inertia 1"
type = "rigid"
inertia = {j1!r}

[[chain]]
name = "s1"
type = "shaft"
stiffness = {k1!r}
inertia = 0.0

[[chain]]
name = "inertia 2"
type = "rigid"
inertia = {j2!r}

[[chain]]
name = "s2"
type = "shaft"
stiffness = {k2!r}
inertia = 0.0

[[chain]]
name = "inertia 3"
type = "rigid"
inertia = {j3!r}
"""


def write_measurement_files(out: Path, time, columns: dict, units: dict) -> list[Path]:
    """The same run in the bench's own formats, as a data logger writes them: TDMS (NI) and MDF 4
    (ASAM), units in the channels' metadata. Skipped (nothing written, ``[]``) without the
    ``flexshaft[measured]`` extra (npTDMS, asammdf)."""
    import importlib.util

    written: list[Path] = []
    data = {name: (x, units[name]) for name, x in columns.items()}
    if importlib.util.find_spec("nptdms") is not None:
        written.append(fs.write_measured(out / "operational_run.tdms", time, data, overwrite=True))
    if importlib.util.find_spec("asammdf") is not None:
        written.append(fs.write_measured(out / "operational_run.mf4", time, data, overwrite=True))
    return written


# %%
# The run
# -------
# 300 s at 2 kHz; the torques in N·m, the speeds in rad/s.

if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else None
    time, columns, units, truth = operational_run()
    print(
        f"simulated: {time[-1] + time[1]:.0f} s at {1 / time[1]:g} Hz, channels "
        + ", ".join(f"{c} [{units[c]}]" for c in columns)
    )
    print(
        "true elastic modes: "
        + ", ".join(f"{f:.6f} Hz" for f in truth["frequencies_hz"])
        + f", damping {100 * DAMPING_RATIO:.2f} % each"
    )

# %%
# Identified, from the torques and from the speeds
# ------------------------------------------------
# Each set of channels alone, up to 200 Hz: the frequencies come out within a fraction of a per cent
# of the truth, the damping ratios within their scatter across the record's segments (±: one
# standard deviation), the shapes normalised to their largest channel.

if __name__ == "__main__":
    for label, names in (("torques", TORQUES), ("speeds", SPEEDS)):
        found = identify_modes([(time, columns, units)], channels=names, max_hz=200.0)
        for mode in found.modes:
            shape = ", ".join(f"{c} {v:+.3f}" for c, v in mode.shape.items())
            print(
                f"  from the {label}: {mode.frequency_hz:9.4f} Hz  damping {100 * mode.damping_ratio:.3f} %"
                f" (segments: ±{100 * mode.segment_damping_std:.3f} %)  shape {shape}"
            )

# %%
# The stabilisation diagram of the speeds' identification: every pole of every model order, the
# stable ones that make each mode coloured, its frequency dashed.

if __name__ == "__main__":
    from flexshaft.views.stabilisation import stabilisation_figure

    # sphinx_gallery_thumbnail_number = 1
    diagram = stabilisation_figure(found)

# %%
# With ``OUT_DIR``: the run as the bench's files, the line's model file and the diagram.

if __name__ == "__main__" and out is not None:
    out.mkdir(parents=True, exist_ok=True)
    csv = fs.write_signals(
        out / "operational_run.csv",
        time,
        {name: (x, units[name]) for name, x in columns.items()},
        overwrite=True,
    )
    model = out / "line.toml"
    model.write_text(model_text(), encoding="utf-8")
    written = [csv, model, *write_measurement_files(out, time, columns, units)]
    picture = out / "stabilisation.png"
    diagram.savefig(picture)
    written.append(picture)
    print("written: " + ", ".join(str(p) for p in written))

"""Operational modal identification of measured runs: natural frequencies, damping ratios, mode shapes.

One or more runs of a test bench (free decays, run-ups, random or operational response), each with the
same channels (flange torques, shaft speeds), go through covariance-driven stochastic subspace
identification (SSI-COV, :mod:`flexshaft.measurement.ssi`) with a stabilisation diagram; each run is also cut
into segments and identified again, so each mode comes with its spread across segments and across runs.

Steps, for each run:

1. Preprocessing. The mean and the linear trend are removed; the record is decimated (polyphase FIR
   anti-alias filter, ``scipy.signal.resample_poly``) so its Nyquist frequency is 2.5 to 5 times
   ``max_hz``; a zero-phase Butterworth high-pass (order :data:`HIGHPASS_ORDER`, forward and backward)
   at ``min_hz`` / 4 removes the rigid-body drift (a free line's speeds wander as a random walk, which
   a linear detrend does not remove); what the high-pass leaves near its corner is identified as poles
   below ``min_hz`` and discarded. Each channel is divided by its standard deviation (torques and speeds
   come in different units; the algorithm weighs them equally) and the shapes are scaled back.
2. SSI-COV on the whole run: correlations at lags 0..2i, the block Toeplitz matrix, its SVD, poles for
   the model orders 2, 4, ... (:data:`DEFAULT_MAX_ORDER` unless told); stable poles
   (:func:`~flexshaft.measurement.ssi.stabilise`) that are physical (0 < ζ <= 20 %, min_hz < f < max_hz)
   clustered into modes (:func:`~flexshaft.measurement.ssi.cluster_modes`).
3. The runs' modes matched across runs (within :data:`MATCH_FREQUENCY` and MAC >= :data:`MATCH_MAC`,
   never two modes of one run); a mode is kept when found in at least half the runs.
4. Segments: each run cut into K equal segments, each identified as in 2, its modes assigned to the
   runs' modes. K by default: segments of at least :data:`SEGMENT_PERIODS` periods and
   :data:`SEGMENT_DECAY` / (ζ·f) seconds of every mode found, at most :data:`MAX_SEGMENTS`, and at
   least two where the record allows; the estimator's scatter of ζ, about 1/√(π·ζ·f·T) relative
   (Brincker & Ventura 2015; simulations of ``examples/operational_run.py`` scatter a little less), is
   then at most 1/√(10π) = 18 % per segment. A mode must be found in more than half of all the
   segments (:data:`CONFIRM_FRACTION`; in exactly half it is kept as doubtful, no calibration target):
   a mode of a whole record that its independent parts do not reproduce is noise that the high model
   orders had room to fit. A run whose segments' RMS differ by more than :data:`STATIONARY_RATIO` (a free
   decay, a run-up: its parts would not hold the same modes) stays whole, as does one given
   ``segments=1``; its modes are then not confirmed this way.
5. Each mode: the mean of its runs' estimates, their standard deviation across runs, across segments,
   and the range of all; its shape the median over the runs.
6. A cross-check by frequency-domain decomposition (:mod:`flexshaft.measurement.fdd`): the peak of the
   first singular value of each run's spectral density matrix near each mode, and the MAC of its
   singular vector with the mode's shape.
7. The doubts (:func:`~flexshaft.measurement.identified.with_doubts`): a mode whose shape is not a
   normal mode's (MPC below :data:`~flexshaft.measurement.identified.MIN_MPC`) is listed but is no
   calibration target; a damping ratio that is not positive or whose spread exceeds it is no damping
   target.

SI throughout: s, Hz, each channel's SI unit; damping ratios as fractions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from ..errors import ModelError
from ..linalg.mac import mac
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import check_frequency, check_int
from .checks import as_signal, uniform_rate
from .fdd import fdd_peak, segment_samples, spectral_matrix
from .identified import Identification, IdentifiedMode, RunSummary, Stabilisation, with_doubts
from .identifyinput import (
    DEFAULT_MAX_ORDER,
    Run,
    as_runs,
    model_orders,
    reference_rows,
    run_channels,
    run_rates,
    run_units,
)
from .ssi import (
    CLUSTER_FREQUENCY,
    CLUSTER_MAC,
    MAX_DAMPING,
    STABLE_DAMPING,
    STABLE_FREQUENCY,
    STABLE_MAC,
    aligned_median,
    cluster_modes,
    correlations,
    group,
    mpc,
    physical,
    ssi_poles,
    stabilise,
)

__all__ = [
    "CONFIRM_FRACTION",
    "DEFAULT_MAX_ORDER",
    "HARMONIC_DAMPING",
    "HIGHPASS_ORDER",
    "MATCH_FREQUENCY",
    "MATCH_MAC",
    "MAX_SEGMENTS",
    "LOWEST_MODE_FRACTION",
    "MIN_HZ_FRACTION",
    "MIN_RECORD_PERIODS",
    "NYQUIST_FACTOR",
    "SEGMENT_DECAY",
    "SEGMENT_PERIODS",
    "STATIONARY_RATIO",
    "Identification",
    "run_rates",
    "IdentifiedMode",
    "Run",
    "RunSummary",
    "Stabilisation",
    "default_min_hz",
    "harmonic_note",
    "identify_modes",
]

#: After decimation the Nyquist frequency is at least this many times ``max_hz`` (and below twice that):
#: the modes sit well inside the band the anti-alias filter passes flat, and their poles well away from
#: z = ±1, where they are hard to resolve.
NYQUIST_FACTOR = 2.5
#: ``min_hz`` when not given and a lowest mode is expected (a model's first elastic mode): this fraction
#: of it - a model before calibration is rarely off by half, and the drift's high-pass (a quarter of
#: ``min_hz``) then sits three octaves below the mode.
LOWEST_MODE_FRACTION = 0.5
#: ``min_hz`` when not given and no mode is expected, as a fraction of ``max_hz``: a drivetrain's modes
#: span about a decade and a half (the Customer 1 bench: 11.6 to 555 Hz); the Toeplitz matrix then has
#: 125 to 250 block rows at the rates :data:`NYQUIST_FACTOR` decimates to.
MIN_HZ_FRACTION = 0.02
#: The high-pass against the drift: its corner at ``min_hz`` times this, well below the lowest mode
#: (order 4 run forward and backward: at 4 times the corner it passes 1 − 1.5e-5 of the power, with
#: no phase).
HIGHPASS_FRACTION = 0.25
HIGHPASS_ORDER = 4
#: The Toeplitz matrix's block rows i span this many periods of ``min_hz`` (lags up to 2i span twice
#: that): the lowest mode of interest is seen turning within the matrix.
LAG_PERIODS = 0.5
#: A run must hold at least this many periods of ``min_hz``.
MIN_RECORD_PERIODS = 20
#: A cluster of stable poles is a mode when it spans at least this fraction of the model orders
#: compared (all but the first).
MIN_STABLE_FRACTION = 0.25
#: Modes of different runs, or of a segment and a run, are the same mode within this relative
#: frequency distance ...
MATCH_FREQUENCY = 0.02
#: ... and with at least this MAC (with one channel, frequency alone decides).
MATCH_MAC = 0.9
#: A segment's mode is a run's mode within this many standard deviations of a segment's frequency
#: estimate (√(ζ/(π·f·T)) relative: 0.4 to 1.3 times what simulations of the example line scatter) ...
MATCH_SIGMAS = 5.0
#: ... but never closer than this (relative): a lightly damped mode of a long segment.
MIN_MATCH_FREQUENCY = 0.0025
#: A mode found in more than this fraction of all segments (of every run; a run not cut counts as one
#: segment) is confirmed; in fewer it is dropped: a mode of a whole record that independent parts of it
#: do not reproduce is noise the model orders had room to fit. Found in exactly this fraction (1 of
#: the 2 segments a record of 20 decay times of its lowest mode is cut into) the vote is undecided: a
#: true, weakly excited mode and a recurring noise pole look alike there (both with MPC 1 and an FDD
#: peak in the example line's 60 s runs), so the mode is kept, marked doubtful - listed, never a target.
CONFIRM_FRACTION = 0.5
#: Default segments: each at least this many periods of the lowest mode ...
SEGMENT_PERIODS = 100
#: ... and at least this / (ζ·f) seconds of it (ζ, f: the lowest mode's damping ratio and frequency).
SEGMENT_DECAY = 10.0
#: At most this many segments per run by default.
MAX_SEGMENTS = 8
#: A run is cut into segments by default only when their RMS values lie within this factor of each
#: other: a stationary response's segments differ by a few per cent (long ones by less), a free
#: decay's by orders of magnitude.
STATIONARY_RATIO = 2.0
#: A mode damped less than this (fraction) gets a note: a sinusoid in the record (an order of a constant
#: shaft speed) is identified as a pole of almost no damping; a drivetrain's torsional modes are damped
#: some 0.1 to 5 %.
HARMONIC_DAMPING = 1e-4
#: Channels whose unit is a time derivative of an angle (or of a torque): their shapes lead by the
#: phase of λ per derivative, which is undone so that all channels share one phase.
DERIVATIVES = {"rad/s": 1, "rpm": 1, "deg/s": 1, "rad/s²": 2, "rad/s^2": 2, "N·m/s": 1}


# --- one run -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Setup:
    """What every record is identified with."""

    orders: tuple  # model orders
    refs: np.ndarray  # reference channels' rows
    min_hz: float
    max_hz: float
    derivative: np.ndarray  # per channel: 0 an angle or torque, 1 a speed, 2 an acceleration
    scales0: np.ndarray  # the first run's channel scales: shapes are compared in these units


@dataclass(frozen=True)
class _Prepared:
    """A run after preprocessing: channels scaled to unit standard deviation at the decimated rate."""

    y: np.ndarray  # (l, n)
    scales: np.ndarray  # (l,) in each channel's unit
    rate_hz: float  # decimated
    decimation: int
    rate_in_hz: float
    duration_s: float


def _decimation(rate_hz: float, max_hz: float) -> int:
    """The decimation factor: the Nyquist frequency after it 2.5 to 5 times ``max_hz``."""
    return max(1, int(rate_hz // (2.0 * NYQUIST_FACTOR * max_hz)))


def _prepare(run: Run, k: int, names, min_hz: float, max_hz: float) -> _Prepared:
    time = as_signal(run.time, f"runs[{k}].time", "s", min_samples=2)
    rate = uniform_rate(time, f"runs[{k}].time")
    nyquist = rate / 2.0
    if not max_hz < nyquist:
        raise ModelError(
            f"is not below runs[{k}]'s Nyquist frequency ({nyquist:g} Hz at {rate:g} Hz)",
            field="max_hz",
            value=max_hz,
            unit="Hz",
            valid=f"a frequency below {nyquist:g} Hz",
        )
    duration = time.size / rate
    need = MIN_RECORD_PERIODS / min_hz
    if duration < need:
        raise ModelError(
            f"is too short for min_hz = {min_hz:g} Hz",
            field=f"runs[{k}]",
            value=duration,
            unit="s",
            valid=f"a record of at least {need:g} s ({MIN_RECORD_PERIODS} periods of min_hz); or a higher "
            "min_hz",
        )
    x = np.empty((len(names), time.size))
    for c, name in enumerate(names):
        samples = as_signal(run.columns[name], f"runs[{k}].columns[{name!r}]", run.units.get(name, ""))
        if samples.size != time.size:
            raise ModelError(
                f"has {samples.size} samples, the time {time.size}",
                field=f"runs[{k}].columns[{name!r}]",
                valid="one sample per time",
            )
        x[c] = samples
    # mean and linear trend off first: the decimation and high-pass filters then start and end near 0
    x = scipy.signal.detrend(x, axis=1, type="linear")
    q = _decimation(rate, max_hz)
    if q > 1:
        x = scipy.signal.resample_poly(x, 1, q, axis=1)
    rate_d = rate / q
    corner = HIGHPASS_FRACTION * min_hz
    sos = scipy.signal.butter(HIGHPASS_ORDER, corner, btype="highpass", fs=rate_d, output="sos")
    # an odd extension a period of the corner long: the filter's start-up dies out in it
    x = scipy.signal.sosfiltfilt(sos, x, axis=1, padlen=min(x.shape[1] - 1, int(rate_d / corner)))
    scales = np.std(x, axis=1)
    for c, name in enumerate(names):
        if not scales[c] > 0:
            raise ModelError(
                "is constant once its mean and drift are removed",
                field=f"runs[{k}].columns[{name!r}]",
                valid="a channel that vibrates",
            )
    return _Prepared(x / scales[:, None], scales, rate_d, q, rate, duration)


def _block_rows(p: _Prepared, k: int, setup: _Setup) -> int:
    """i: the Toeplitz matrix's rank (r·i) must hold the highest order, its lags span LAG_PERIODS."""
    i = max(
        math.ceil(setup.orders[-1] / setup.refs.size) + 1, math.ceil(LAG_PERIODS * p.rate_hz / setup.min_hz)
    )
    # the matrix is (i·channels) x (i·references): its SVD is the work and the memory
    check_ceiling(
        "ssi_rows",
        i * p.y.shape[0],
        field="min_hz",
        value=setup.min_hz,
        unit="Hz",
        detail=f"needs {i} block rows of lags at {p.rate_hz:g} Hz for {p.y.shape[0]} channels, "
        f"a Toeplitz matrix of {i * p.y.shape[0]} rows",
        hint="a higher min_hz, or fewer channels",
    )
    if p.y.shape[1] < 8 * i:
        raise ModelError(
            f"holds {p.y.shape[1]} samples at {p.rate_hz:g} Hz, too few for lags up to {2 * i}",
            field=f"runs[{k}]",
            valid=f"at least {8 * i} samples after decimation; a higher min_hz or fewer orders",
        )
    return i


@dataclass(frozen=True)
class _Record:
    """The identification of one record (a run or a segment).

    Its modes' shapes are complex, in the first run's scaled units (each channel divided by its
    standard deviation in run 0, so records of different runs compare) and turned so that speeds share
    the angles' phase.
    """

    poles: tuple  # OrderPoles per order
    stable: tuple  # flags per order
    physical: tuple  # flags per order
    clusters: tuple  # PoleCluster per mode
    frequency_hz: np.ndarray  # per mode
    damping_ratio: np.ndarray
    shapes: np.ndarray  # (l, modes) complex
    mpc: np.ndarray


def _identify(y: np.ndarray, rate_hz: float, block_rows: int, scales: np.ndarray, setup: _Setup) -> _Record:
    """SSI-COV of one record ``y`` (scaled channels at ``rate_hz``; ``scales`` its run's)."""
    corr = correlations(y, 2 * block_rows, setup.refs)
    poles = ssi_poles(corr, rate_hz, setup.orders, block_rows)
    stable = stabilise(poles)
    keep = tuple(physical(p, setup.min_hz, setup.max_hz) for p in poles)
    min_members = max(1, math.ceil(MIN_STABLE_FRACTION * (len(setup.orders) - 1)))
    clusters = cluster_modes(poles, stable, keep, min_members)
    shapes, mpcs = [], []
    for c in clusters:
        turned = c.shape * _turn(c.damping_ratio, setup.derivative)
        mpcs.append(mpc(turned))
        shapes.append(turned * scales / setup.scales0)
    return _Record(
        poles=poles,
        stable=stable,
        physical=keep,
        clusters=clusters,
        frequency_hz=np.array([c.frequency_hz for c in clusters]),
        damping_ratio=np.array([c.damping_ratio for c in clusters]),
        shapes=np.column_stack(shapes) if shapes else np.zeros((y.shape[0], 0), dtype=complex),
        mpc=np.array(mpcs),
    )


def _turn(zeta: float, derivative: np.ndarray) -> np.ndarray:
    """Per channel, the factor that undoes a derivative's phase lead: (λ/|λ|)^(−d)."""
    direction = complex(-zeta, math.sqrt(max(0.0, 1.0 - zeta * zeta)))  # λ/|λ|
    return direction ** (-derivative.astype(float))


# --- across runs and segments ------------------------------------------------------------------------


@dataclass(frozen=True)
class _Group:
    """One mode across runs: its runs' modes."""

    centre: float  # median frequency, Hz
    damping_ratio: float  # median damping ratio
    chosen: dict  # run -> index of the mode in that run's record
    shape: np.ndarray  # median complex shape (reference units)


def _match_runs(records: list[_Record]) -> tuple[list[_Group], list[str]]:
    """The runs' modes grouped across runs (:func:`~flexshaft.measurement.ssi.group`, within
    :data:`MATCH_FREQUENCY` and MAC >= :data:`MATCH_MAC`, never two of one run); a group is a mode
    when it holds at least half of the runs."""
    f = np.concatenate([r.frequency_hz for r in records])
    if f.size == 0:
        return [], []
    shapes = np.column_stack([r.shapes for r in records])
    run_of = np.concatenate([np.full(r.frequency_hz.size, k) for k, r in enumerate(records)])
    index = np.concatenate([np.arange(r.frequency_hz.size) for r in records])
    labels = group(f, shapes, MATCH_FREQUENCY, MATCH_MAC, apart=run_of)
    groups, notes = [], []
    for label in np.unique(labels):
        at = np.flatnonzero(labels == label)  # at most one mode of each run
        centre = float(np.median(f[at]))
        if at.size < math.ceil(len(records) / 2):
            notes.append(
                f"a mode near {centre:.4g} Hz was found in {at.size} of {len(records)} runs only: left out"
            )
            continue
        chosen = {int(run_of[a]): int(index[a]) for a in at}
        zeta = float(np.median(np.concatenate([r.damping_ratio for r in records])[at]))
        groups.append(_Group(centre, zeta, chosen, aligned_median(shapes[:, at])))
    return sorted(groups, key=lambda g: g.centre), notes


def _segment_need(groups: list[_Group], records: list[_Record]) -> float | None:
    """The shortest segment that suits every mode, s: :data:`SEGMENT_PERIODS` periods and
    :data:`SEGMENT_DECAY` / (ζ·f) seconds of each (None without modes)."""
    need = None
    for g in groups:
        f = float(np.mean([records[k].frequency_hz[j] for k, j in g.chosen.items()]))
        zeta = float(np.mean([records[k].damping_ratio[j] for k, j in g.chosen.items()]))
        need = max(need or 0.0, SEGMENT_PERIODS / f, SEGMENT_DECAY / (zeta * f))
    return need


def _segments_of(p: _Prepared, k: int, segments, need, min_hz: float, block_rows: int) -> tuple[int, str]:
    """Into how many segments run ``k`` is cut, and why not more (a note, or "").

    ``segments`` when given (checked: each segment long enough); else as many as are ``need`` seconds
    long (None: no mode, one segment), at most :data:`MAX_SEGMENTS`, and two where that is one but two
    are long enough: every mode is then checked in two independent halves. A record whose segments'
    RMS differ by more than :data:`STATIONARY_RATIO` is not stationary (a free decay, a run-up): its
    segments would not hold the same modes, so it stays whole.
    """
    shortest = max(MIN_RECORD_PERIODS / min_hz, 8 * block_rows / p.rate_hz)  # s
    if segments is not None:
        if segments > 1 and p.duration_s / segments < shortest:
            raise ModelError(
                f"cuts runs[{k}] ({p.duration_s:g} s) into segments of {p.duration_s / segments:g} s",
                field="segments",
                value=segments,
                valid=f"segments of at least {shortest:g} s ({MIN_RECORD_PERIODS} periods of min_hz and "
                f"{8 * block_rows} samples at {p.rate_hz:g} Hz): "
                f"at most {int(p.duration_s // shortest) or 1}",
            )
        return segments, ""
    if need is None:
        return 1, ""
    count = int(min(MAX_SEGMENTS, p.duration_s // need))
    if count < 2:
        if p.duration_s / 2 < shortest:
            return 1, f"runs[{k}] ({p.duration_s:g} s) is too short to cut in two: it counts as one segment"
        count = 2
    length = p.y.shape[1] // count
    rms = np.sqrt(np.mean(p.y[:, : count * length].reshape(p.y.shape[0], count, length) ** 2, axis=(0, 2)))
    if rms.max() > STATIONARY_RATIO * rms.min():
        return 1, (
            f"runs[{k}] is not stationary (its {count} segments' RMS differ {rms.max() / rms.min():.3g}-fold:"
            " a free decay or a run-up?): it counts as one segment; segments= cuts it anyway"
        )
    return count, ""


def _assign(record: _Record, groups: list[_Group], seconds: float) -> dict:
    """Which mode of ``record`` (a segment of ``seconds``) is each of the ``groups``' modes.

    A record's mode is a group's when their frequencies lie within :data:`MATCH_SIGMAS` standard
    deviations of a segment's frequency estimate, √(ζ/(π·f·T)) relative (Brincker & Ventura's estimate
    of the random error; ζ and f the group's), but at least :data:`MIN_MATCH_FREQUENCY` and at most
    :data:`MATCH_FREQUENCY`, and their MAC is at least :data:`MATCH_MAC` (with one channel, frequency
    alone decides). Each of the record's modes counts for at most one group, the nearest; each group
    then takes the nearest of those that count for it. Returns {group index: index in record}.
    """
    out = {}
    if record.frequency_hz.size == 0 or not groups:
        return out
    centres = np.array([g.centre for g in groups])
    zeta = np.array([g.damping_ratio for g in groups])
    tol = np.clip(
        MATCH_SIGMAS * np.sqrt(np.abs(zeta) / (np.pi * centres * seconds)),
        MIN_MATCH_FREQUENCY,
        MATCH_FREQUENCY,
    )
    df = np.abs(record.frequency_hz[:, None] - centres[None, :]) / centres[None, :]
    ok = df <= tol[None, :]
    if record.shapes.shape[0] > 1:
        ok &= mac(record.shapes, np.column_stack([g.shape for g in groups])) >= MATCH_MAC
    dist = np.where(ok, df, np.inf)
    for j, m in enumerate(np.argmin(dist, axis=1)):  # each of the record's modes: its nearest group
        m = int(m)
        if np.isfinite(dist[j, m]) and (m not in out or dist[j, m] < dist[out[m], m]):
            out[m] = j
    return out


def _std(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.std(v, ddof=1)) if v.size >= 2 else math.nan


def _real_shape(shape: np.ndarray, scales0: np.ndarray) -> np.ndarray:
    """A complex shape in reference units as a real shape in the channels' units, largest component 1:
    turned so that component is real and positive, then its real part."""
    phys = shape * scales0
    return (phys / phys[int(np.argmax(np.abs(phys)))]).real


def _mode(
    g: _Group, records: list[_Record], segment_values: list, total_segments: int, names, setup, fdd: list
) -> IdentifiedMode:
    """One group's :class:`IdentifiedMode`; ``segment_values`` its (f, ζ) per segment it was found in,
    ``fdd`` its (FDD frequency, MAC) per run (None where not found)."""
    peaks = np.array([c for c in fdd if c is not None], dtype=float).reshape(-1, 2)
    n_runs = len(records)
    rf, rz = np.full(n_runs, math.nan), np.full(n_runs, math.nan)
    for k, j in g.chosen.items():
        rf[k], rz[k] = records[k].frequency_hz[j], records[k].damping_ratio[j]
    seg = np.array(segment_values, dtype=float).reshape(-1, 2)
    every_f = np.concatenate([rf[np.isfinite(rf)], seg[:, 0]])
    every_z = np.concatenate([rz[np.isfinite(rz)], seg[:, 1]])
    shape = _real_shape(g.shape, setup.scales0)
    return IdentifiedMode(
        frequency_hz=float(np.nanmean(rf)),
        damping_ratio=float(np.nanmean(rz)),
        frequency_std_hz=_std(rf),
        damping_std=_std(rz),
        run_frequencies_hz=tuple(float(v) for v in rf),
        run_damping_ratios=tuple(float(v) for v in rz),
        found_in_runs=len(g.chosen),
        segment_frequency_std_hz=_std(seg[:, 0]),
        segment_damping_std=_std(seg[:, 1]),
        frequency_range_hz=(float(every_f.min()), float(every_f.max())),
        damping_range=(float(every_z.min()), float(every_z.max())),
        found_in_segments=int(seg.shape[0]),
        segments=total_segments,
        shape={name: float(shape[c]) for c, name in enumerate(names)},
        mpc=float(np.mean([records[k].mpc[j] for k, j in g.chosen.items()])),
        stable_poles=int(sum(len(records[k].clusters[j].members) for k, j in g.chosen.items())),
        fdd_frequency_hz=float(peaks[:, 0].mean()) if peaks.size else math.nan,
        fdd_mac=float(peaks[:, 1].mean()) if peaks.size else math.nan,
    )


def _fdd_check(k: int, p: _Prepared, record: _Record, groups: list[_Group], setup: _Setup) -> list:
    """Per group: (the FDD peak's frequency Hz, the MAC of its singular vector with SSI's shape) in run
    ``k``, or None where the group's mode is not in this run or s₁ has no peak near it."""
    here = [(m, g.chosen[k]) for m, g in enumerate(groups) if k in g.chosen]
    out = [None] * len(groups)
    if not here:
        return out
    nper = segment_samples(
        p.rate_hz, [(record.frequency_hz[j], record.damping_ratio[j]) for _, j in here], p.y.shape[1]
    )
    frequencies, g = spectral_matrix(p.y, p.rate_hz, nper)
    for m, j in here:
        peak = fdd_peak(frequencies, g, record.frequency_hz[j], MATCH_FREQUENCY)
        if peak is not None:
            f, vector = peak
            turned = vector * _turn(record.damping_ratio[j], setup.derivative) * p.scales / setup.scales0
            out[m] = (f, mac(turned, record.shapes[:, j]))
    return out


def _diagram(k: int, record: _Record, groups: list[_Group], index_of: dict, max_hz: float) -> Stabilisation:
    """Run ``k``'s stabilisation diagram, each pole marked with the mode (its index in the result) it
    counts for."""
    mode_of_cluster = {
        g.chosen[k]: index_of[m] for m, g in enumerate(groups) if k in g.chosen and m in index_of
    }
    member = {}
    for c, cluster in enumerate(record.clusters):
        for jp in cluster.members:
            member[jp] = mode_of_cluster.get(c, -1)
    parts = []
    for j, p in enumerate(record.poles):
        inside = np.flatnonzero(p.frequency_hz <= max_hz)
        parts.append(
            (
                np.full(inside.size, p.order),
                p.frequency_hz[inside],
                p.damping_ratio[inside],
                record.stable[j][inside],
                record.physical[j][inside],
                np.array([member.get((j, int(q)), -1) for q in inside], dtype=int),
            )
        )
    order, f, z, stable, phys, mode = (np.concatenate(col) for col in zip(*parts, strict=True))
    return Stabilisation(
        run=k, order=order, frequency_hz=f, damping_ratio=z, stable=stable, physical=phys, mode=mode
    )


def _method(setup: _Setup, names, prepared, rows) -> str:
    rates = sorted({(p.decimation, p.rate_hz) for p in prepared})
    rate_text = ", ".join(f"decimated by {q} to {r:g} Hz" if q > 1 else f"kept at {r:g} Hz" for q, r in rates)
    refs = "all channels" if setup.refs.size == len(names) else ", ".join(names[r] for r in setup.refs)
    orders = setup.orders
    return (
        "covariance-driven stochastic subspace identification (SSI-COV, Peeters & De Roeck 1999), "
        f"model orders {orders[0]}..{orders[-1]} ({len(orders)} orders), references: {refs}; "
        f"preprocessing: mean and linear trend removed, {rate_text} (polyphase FIR anti-alias filter), "
        f"rigid-body drift removed by a zero-phase order-{HIGHPASS_ORDER} Butterworth high-pass at "
        f"{HIGHPASS_FRACTION * setup.min_hz:g} Hz (forward and backward) and poles below min_hz = "
        f"{setup.min_hz:g} Hz discarded; channels scaled to unit standard deviation, shapes scaled back; "
        f"correlations at lags 0..2i by FFT, divided by the record length; i = "
        f"{'/'.join(str(i) for i in sorted(set(rows)))} block rows; stable pole: within "
        f"{100 * STABLE_FREQUENCY:g} % in frequency, {100 * STABLE_DAMPING:g} % in damping and MAC >= "
        f"{STABLE_MAC:g} of a pole of the previous order; physical: 0 < damping <= {100 * MAX_DAMPING:g} %, "
        f"{setup.min_hz:g} Hz < f < {setup.max_hz:g} Hz; stable physical poles clustered (within "
        f"{100 * CLUSTER_FREQUENCY:g} % and MAC >= {CLUSTER_MAC:g}), a mode where a cluster spans at "
        f"least {100 * MIN_STABLE_FRACTION:g} % of the orders, its value the cluster's median; modes matched "
        f"across runs and segments within {100 * MATCH_FREQUENCY:g} % and MAC >= {MATCH_MAC:g}, kept when "
        f"found in at least half of the runs and more than {100 * CONFIRM_FRACTION:g} % of the segments "
        "(in exactly that many: listed as doubtful); "
        "a mode's value "
        "the mean over the runs, its spread the standard deviation across runs and across segments; "
        "cross-checked by frequency-domain decomposition (Brincker, Zhang & Andersen 2001): the peak of "
        "the first singular value of the Welch spectral density matrix (Hann, half overlap) near each mode, "
        "and the MAC of its singular vector with the mode's shape"
    )


def _band(max_hz, min_hz, items: list[Run], lowest_mode_hz) -> tuple[float, float, str]:
    """The band searched, Hz, and why its low end is where it is."""
    max_hz = check_frequency(max_hz, "max_hz", lo=0.0, lo_open=True)
    if min_hz is None:
        min_hz, why = default_min_hz(items, max_hz, lowest_mode_hz)
        if not min_hz < max_hz:
            raise ModelError(
                f"is too short for max_hz = {max_hz:g} Hz",
                field="runs",
                valid=f"records of at least {MIN_RECORD_PERIODS / max_hz:g} s ({MIN_RECORD_PERIODS} periods "
                "of max_hz); or a higher max_hz",
                has_value=False,
            )
        return max_hz, min_hz, why
    min_hz = check_frequency(min_hz, "min_hz", lo=0.0, lo_open=True)
    if not min_hz < max_hz:
        raise ModelError(
            "is not below max_hz", field="min_hz", value=min_hz, unit="Hz", valid=f"below {max_hz:g} Hz"
        )
    return max_hz, min_hz, "given"


def default_min_hz(runs, max_hz: float, lowest_mode_hz: float | None = None) -> tuple[float, str]:
    """The lowest frequency identified when none is given, Hz, and why, in a few words.

    With ``lowest_mode_hz`` (a model's first elastic mode): :data:`LOWEST_MODE_FRACTION` of it.
    Without: :data:`MIN_HZ_FRACTION` of ``max_hz``. Never below what the shortest run holds
    :data:`MIN_RECORD_PERIODS` periods of (the lowest frequency it can identify).

    Parameters
    ----------
    runs : sequence of Run, SignalTable or (time, columns, units)
        The runs, as :func:`identify_modes` takes them.
    max_hz : float
        The highest frequency of interest, Hz.
    lowest_mode_hz : float, optional
        The lowest mode expected, Hz: a model's first elastic mode.

    Returns
    -------
    min_hz : float
        Hz.
    why : str
        Where it comes from, e.g. ``"from the model's first mode, 11.6 Hz"``.
    """
    max_hz = check_frequency(max_hz, "max_hz", lo=0.0, lo_open=True)
    durations = []
    for k, run in enumerate(as_runs(runs)):
        time = as_signal(run.time, f"runs[{k}].time", "s", min_samples=2)
        durations.append(time.size / uniform_rate(time, f"runs[{k}].time"))
    shortest = min(durations)
    record = MIN_RECORD_PERIODS / shortest  # Hz: the lowest the record can identify
    length = f"the record's length, {MIN_RECORD_PERIODS} periods in {shortest:.3g} s"
    if lowest_mode_hz is not None:
        f1 = check_frequency(lowest_mode_hz, "lowest_mode_hz", lo=0.0, lo_open=True)
        wanted = LOWEST_MODE_FRACTION * f1
        if record <= wanted < max_hz:
            return wanted, f"from the model's first mode, {f1:.4g} Hz"
        if wanted < record:
            inside = "inside" if record < f1 else "below it: a longer record would see it"
            return record, f"from {length}; the model's first mode, {f1:.4g} Hz, {inside}"
    fraction = MIN_HZ_FRACTION * max_hz
    if fraction >= record:
        return fraction, f"max_hz / {1 / MIN_HZ_FRACTION:g}: no model to say where the first mode is"
    return record, f"from {length}"


def _in_segments(items, prepared, rows, records, groups, segments, names, setup, notes):
    """Each run in segments (or whole), their modes assigned to :func:`_match_runs`' groups: per group
    the (f, ζ) of each segment it was found in, and each run's summary (why one stays whole: ``notes``)."""
    need = _segment_need(groups, records)
    values = [[] for _ in groups]  # per group: (f, ζ) of each segment it was found in
    summaries = []
    for k, p in enumerate(prepared):
        count, why = _segments_of(p, k, segments, need, setup.min_hz, rows[k])
        if why:
            notes.append(why)
        length = p.y.shape[1] // count
        if count == 1:  # the run is its one segment
            for m, g in enumerate(groups):
                if k in g.chosen:
                    values[m].append(
                        (records[k].frequency_hz[g.chosen[k]], records[k].damping_ratio[g.chosen[k]])
                    )
        else:
            for s in range(count):
                part = _identify(p.y[:, s * length : (s + 1) * length], p.rate_hz, rows[k], p.scales, setup)
                for m, j in _assign(part, groups, length / p.rate_hz).items():
                    values[m].append((part.frequency_hz[j], part.damping_ratio[j]))
        summaries.append(
            RunSummary(
                index=k,
                source=items[k].source,
                duration_s=p.duration_s,
                rate_hz=p.rate_in_hz,
                decimated_rate_hz=p.rate_hz,
                decimation=p.decimation,
                block_rows=rows[k],
                segments=count,
                segment_s=length / p.rate_hz,
                scales={name: float(p.scales[c]) for c, name in enumerate(names)},
            )
        )
    return values, summaries


def _confirmed(groups, records, values, total, n_runs, names, setup, checks, notes):
    """The modes: the groups found in more than half of the segments (a mode of a whole record that its
    independent parts do not reproduce is noise the model orders had room to fit; in exactly half:
    kept as doubtful), with notes on those left out and on harmonics; and each kept group's index among
    them."""
    modes, index_of = [], {}
    for m, g in enumerate(groups):
        found = len(values[m])
        if total > n_runs and found < CONFIRM_FRACTION * total:
            notes.append(
                f"a mode near {g.centre:.4g} Hz was found in {len(values[m])} of {total} segments only: "
                "left out"
            )
            continue
        index_of[m] = len(modes)
        mode = _mode(g, records, values[m], total, names, setup, [c[m] for c in checks])
        tie = total > n_runs and not found > CONFIRM_FRACTION * total
        undecided = f"found in {found} of {total} segments: too few to confirm it" if tie else ""
        modes.append(with_doubts(mode, len(names), undecided))
    if not modes:
        notes.append(f"no mode was found between {setup.min_hz:g} and {setup.max_hz:g} Hz")
    notes += [harmonic_note(mode) for mode in modes if mode.damping_ratio < HARMONIC_DAMPING]
    return modes, index_of


def harmonic_note(mode: IdentifiedMode) -> str:
    """The note on a mode damped less than :data:`HARMONIC_DAMPING`: without a model that says a mode is
    there, it may be a sinusoid in the record."""
    return (
        f"the mode at {mode.frequency_hz:.6g} Hz has a damping ratio of {100 * mode.damping_ratio:.2g} %: "
        "a harmonic (an order of a constant speed, a mains frequency) rather than a mode?"
    )


@follows_policy
def identify_modes(
    runs,
    *,
    channels=None,
    max_hz,
    min_hz=None,
    lowest_mode_hz=None,
    orders=None,
    references=None,
    segments=None,
) -> Identification:
    """Identify the modes of measured runs by SSI-COV, with their spread across segments and runs.

    Parameters
    ----------
    runs : sequence of Run, SignalTable or (time, columns, units)
        One or more runs (one Run or SignalTable may be given alone): time in s (uniform), columns
        ``name -> samples`` in SI, units ``name -> SI unit``. Every run needs the channels used.
    channels : sequence of str, optional
        The channels to use, in this order (default: every channel of the first run; then every run
        must have the same channels).
    max_hz : float
        The highest frequency of interest, Hz: below every run's Nyquist frequency.
    min_hz : float, optional
        The lowest frequency of interest, Hz (default :func:`default_min_hz`: half of
        ``lowest_mode_hz``, else ``max_hz`` / 50, never below what the record resolves): the drift's
        high-pass sits at a quarter of it, and every run must hold :data:`MIN_RECORD_PERIODS` periods.
    lowest_mode_hz : float, optional
        The lowest mode expected, Hz (a model's first elastic mode): sets the default ``min_hz``.
    orders : int or sequence of int, optional
        The model orders of the stabilisation diagram: a highest order (2, 4, ... up to it) or a list
        of even orders (default up to :data:`DEFAULT_MAX_ORDER`).
    references : sequence of str, optional
        The reference channels of the correlations (default: all channels). Fewer references make a
        smaller Toeplitz matrix; each mode must show in at least one of them.
    segments : int, optional
        Into how many segments each run is cut (default: see the module docstring; a run that is not
        stationary, such as a free decay, stays whole). 1: none; the spread is then across runs only
        and a mode need not be confirmed in segments.

    Returns
    -------
    Identification
        The modes sorted by frequency, with each run's stabilisation diagram.

    Raises
    ------
    ModelError
        No runs or channels, channel sets or units that differ between runs, samples that are not
        finite, a time base that is not uniform, ``max_hz`` at or above a run's Nyquist frequency, a
        record too short for ``min_hz``, unusable orders, references or segments.
    """
    items = as_runs(runs)
    names = run_channels(items, channels)
    units = run_units(items, names)
    max_hz, min_hz, why = _band(max_hz, min_hz, items, lowest_mode_hz)
    refs = reference_rows(references, names)
    order_list = model_orders(orders)
    if segments is not None:
        segments = check_int(segments, "segments", lo=1, hi=1000)
    prepared = [_prepare(run, k, names, min_hz, max_hz) for k, run in enumerate(items)]
    setup = _Setup(
        orders=order_list,
        refs=refs,
        min_hz=min_hz,
        max_hz=max_hz,
        derivative=np.array([DERIVATIVES.get(units[n], 0) for n in names]),
        scales0=prepared[0].scales,
    )
    rows = [_block_rows(p, k, setup) for k, p in enumerate(prepared)]

    # every run whole, then its modes matched across the runs
    records = [_identify(p.y, p.rate_hz, i, p.scales, setup) for p, i in zip(prepared, rows, strict=True)]
    groups, notes = _match_runs(records)

    # the cross-check: each run's frequency-domain decomposition, its peaks near the run's modes
    checks = [_fdd_check(k, p, records[k], groups, setup) for k, p in enumerate(prepared)]

    values, summaries = _in_segments(items, prepared, rows, records, groups, segments, names, setup, notes)
    total = sum(s.segments for s in summaries)
    modes, index_of = _confirmed(groups, records, values, total, len(items), names, setup, checks, notes)
    return Identification(
        modes=tuple(modes),
        channels=names,
        units=units,
        references=tuple(names[r] for r in refs),
        min_hz=min_hz,
        max_hz=max_hz,
        band_reason=why,
        orders=order_list,
        method=_method(setup, names, prepared, rows),
        runs=tuple(summaries),
        diagrams=tuple(_diagram(k, r, groups, index_of, max_hz) for k, r in enumerate(records)),
        notes=tuple(notes),
    )

"""The drivetrain as a linear system: named inputs and outputs, state space in modal form, frequency response.

Signals have one syntax everywhere:

- an **input** is a station name: a torque applied there, N·m (``"motor"``: the air-gap torque);
- an **output** is ``"angle:STATION"`` (rad), ``"speed:STATION"`` (rad/s) or ``"torque:COMPONENT"``
  (N·m, the torque its spring and damper transmit, positive when a positive motor torque drives
  it; ``"torque:PART: STATION"`` at a named station inside a part, e.g. a torque flange).

The state space is built from the one modal result: the states are the modal coordinates η and
their rates (q = Φη, Φ mass-normalised), ``A = [[0, I], [−Ω², −ΦᵀCΦ]]`` (the modal damping matrix in
full, so non-proportional damping is kept), ``B = [[0], [ΦᵀF]]``. The rigid-body mode is kept
exactly: a free drivetrain has its pole at 0 (Rayleigh damping too: it damps deformation only) and
nothing drifts.
Modes above ``max_hz`` may be left out (truncation). The frequency response is evaluated from the
same modal form, m × m per frequency (stacked in chunks; elementwise when the modal damping is
diagonal), never a dense inverse of the physical matrices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.damping import modal_damping_block
from ..linalg.firstorder import damped_eigen
from ..system.threads import follows_policy
from ..validation import MAX_FREQUENCY_HZ, MAX_SPEED_RPM, check_frequency, check_real
from .modal import ModalResult, rayleigh_alpha

__all__ = [
    "StateSpace",
    "FrequencyResponse",
    "state_space",
    "frequency_response",
    "frequency_grid",
    "signal_names",
    "response_system",
    "default_frf_range",
    "element_rows",
]


@dataclass(frozen=True)
class StateSpace:
    """ẋ = A x + B u, y = C x + D u in the modal coordinates of a drivetrain (SI).

    Attributes
    ----------
    A, B, C, D : ndarray
        The system matrices; x = [η; η̇] (2m states), u the input torques (N·m), y the outputs.
    inputs, outputs : tuple of str
        The signal names, in the order of the columns of B and the rows of C.
    input_units, output_units : tuple of str
        Their units.
    states : tuple of str
        ``"mode k"`` and ``"mode k rate"`` for the modal coordinates kept.
    modes : ndarray of int
        The modes kept (as ``flexshaft modes`` numbers them).
    frequencies_hz : ndarray
        Their undamped frequencies, Hz.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple
    outputs: tuple
    input_units: tuple
    output_units: tuple
    states: tuple
    modes: np.ndarray
    frequencies_hz: np.ndarray

    def to_control(self):
        """The system as a python-control ``StateSpace`` (``pip install control``)."""
        try:
            import control
        except ImportError:
            raise ModelError(
                "needs python-control", field="to_control", valid="pip install control"
            ) from None
        return control.ss(
            self.A, self.B, self.C, self.D, inputs=list(self.inputs), outputs=list(self.outputs)
        )

    def poles(self) -> np.ndarray:
        """The eigenvalues of A, 1/s.

        Solved by :func:`~flexshaft.linalg.firstorder.damped_eigen` on the similar matrix
        [[0, Ω], [−Ω, −ΦᵀCΦ]] (A scaled by diag(Ω, I)) while A is in its modal form: its norm is
        ω_max where A's is ω_max², so a model with very stiff modes (a 6-DOF line's 1 MHz axial
        modes beside a 10 Hz torsion mode) keeps its low poles to full precision (eigenvalue
        errors go as ε·‖A‖). A rigid-body mode (ω = 0) keeps its roots 0 and −rᵀCr either way.
        """
        return damped_eigen(self.A)


@dataclass(frozen=True)
class FrequencyResponse:
    """Complex response of every output to every input at each frequency.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (f,)
    H : ndarray of complex, shape (f, n_outputs, n_inputs)
        Output per unit input (rad/N·m, rad/s/N·m, N·m/N·m).
    inputs, outputs, input_units, output_units : tuple of str
    """

    frequencies_hz: np.ndarray
    H: np.ndarray
    inputs: tuple
    outputs: tuple
    input_units: tuple
    output_units: tuple

    def peaks(self, output: int = 0, input: int = 0) -> list[dict]:
        """The local maxima of ``|H|`` with their half-power damping: ξ ≈ (f₂ − f₁)/(2 f_peak)."""
        mag = np.abs(self.H[:, output, input])
        f = self.frequencies_hz
        out = []
        for k in range(1, mag.size - 1):
            if mag[k] > mag[k - 1] and mag[k] >= mag[k + 1]:
                half = mag[k] / np.sqrt(2.0)
                lo = k
                while lo > 0 and mag[lo] > half:
                    lo -= 1
                hi = k
                while hi < mag.size - 1 and mag[hi] > half:
                    hi += 1
                if mag[lo] > half or mag[hi] > half:
                    continue  # the half-power points lie outside the range
                f1 = np.interp(half, [mag[lo], mag[lo + 1]], [f[lo], f[lo + 1]])
                f2 = np.interp(half, [mag[hi], mag[hi - 1]], [f[hi], f[hi - 1]])
                out.append(
                    {
                        "frequency_hz": float(f[k]),
                        "magnitude": float(mag[k]),
                        "damping_ratio": float((f2 - f1) / (2 * f[k])),
                    }
                )
        return out

    def to_dict(self) -> dict:
        """The ``flexshaft frf --json`` document: frequencies (Hz), real and imaginary parts (output unit per
        N·m; one output: a list per frequency), and the peaks with their half-power damping."""
        H = self.H[:, :, 0] if self.H.shape[2] == 1 else self.H
        one = H.ndim == 2 and H.shape[1] == 1
        return {
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "units": {"frequency": "Hz", "input": list(self.input_units), "output": list(self.output_units)},
            "frequency_hz": self.frequencies_hz.tolist(),
            "real": (H[:, 0].real if one else H.real).tolist(),
            "imag": (H[:, 0].imag if one else H.imag).tolist(),
            "peaks": self.peaks(),
        }

    def csv(self) -> str:
        """The response as CSV: frequency (Hz), then per output its real and imaginary parts."""
        lines = [
            "frequency_hz,"
            + ",".join(
                f"{o} real ({u}/N·m),{o} imag ({u}/N·m)" for o, u in zip(self.outputs, self.output_units)
            )
        ]
        for k, fk in enumerate(self.frequencies_hz):
            lines.append(
                f"{fk:.9g},"
                + ",".join(
                    f"{self.H[k, j, 0].real:.9g},{self.H[k, j, 0].imag:.9g}" for j in range(len(self.outputs))
                )
            )
        return "\n".join(lines)

    def table(self, peaks=None) -> str:
        """The ``flexshaft frf`` table: the peaks (``peaks``: :meth:`peaks`, where the caller has them)."""
        rows = [f"frequency response {self.inputs[0]} -> {', '.join(self.outputs)}; peaks:"]
        rows += [
            f"  {p['frequency_hz']:10.4f} Hz  |H| {p['magnitude']:.4g}  half-power damping "
            f"{100 * p['damping_ratio']:.4f} %"
            for p in (self.peaks() if peaks is None else peaks)
        ]
        return "\n".join(rows)

    def plot(self, *, damping: str | None = None, before=None):
        """The Bode plot (magnitude and phase of every output), a matplotlib Figure (never shown);
        ``damping``, the assumption the response is under, named in its title; ``before``, the same
        response of the model before calibration, drawn dashed beside it."""
        from ..views.plots import bode_figure

        return bode_figure(self, damping=damping, before=before)


def signal_names(model) -> dict[str, list[str]]:
    """The valid input and output names of a model."""
    stations = [s.name for s in model.stations]
    # A rigid mesh carries its torque as a constraint force, not through a spring of its own.
    flexible = [
        c.name
        for c in model.drivetrain.components
        if c.type != "rigid" and not (c.type == "gear" and c.rigid_mesh)
    ]
    named = [s for s in stations if ": " in s]
    return {
        "inputs": stations,
        "outputs": [f"angle:{s}" for s in stations]
        + [f"speed:{s}" for s in stations]
        + [f"torque:{c}" for c in flexible]
        + [f"torque:{s}" for s in named],
    }


def _station_row(model, name: str, field: str) -> np.ndarray:
    """The row (on the coordinates) that reads θx at a station."""
    try:
        st = model.station(name, field)
    except ModelError:
        raise ModelError(
            "no such signal",
            field=field,
            value=name,
            valid=", ".join(signal_names(model)["inputs" if field == "input" else "outputs"]),
        ) from None
    return np.asarray(model.T[model.node_dof([st.node])[0]].toarray()).ravel()


def _torque_rows(model, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Rows (on q and on q̇) of the torque an element transmits: k·(θ₁ − n·θ₂) + c·(θ̇₁ − n·θ̇₂), N·m
    (:func:`element_rows`)."""
    diff, k, c = element_rows(model, name)
    return k * diff, c * diff


def element_rows(model, name: str) -> tuple[np.ndarray, float, float]:
    """The row (on the coordinates q) reading an element's relative rotation θ₁ − n·θ₂ (rad), and its
    stiffness k (N·m/rad) and damper c (N·m·s/rad): it transmits k·(θ₁ − n·θ₂) + c·(θ̇₁ − n·θ̇₂), N·m.

    θ₁ is its driving-side (motor-side) node: a positive motor torque driving the line reads
    positive, as a torque flange would show it. c is the component's dashpot ``damping``; a
    shaft's modal ``damping_ratio`` acts on its own modes and is not part of this torque. n is 1
    but for a gear mesh (its ratio: the mesh torque on the driving wheel, in the driving frame).
    """
    comps = model.drivetrain.components
    names = [c.name for c in comps]
    at_node = None
    if name in names and f"torque:{name}" in signal_names(model)["outputs"]:
        ci = names.index(name)
        at_node = int(model.start_node[ci])
    else:
        for st in model.stations:
            if st.name == name and ": " in name:
                at_node = st.node
                ci = names.index(name.split(": ")[0])
        if at_node is None:
            raise ModelError(
                "no such signal",
                field="output",
                value=f"torque:{name}",
                valid=", ".join(signal_names(model)["outputs"]),
            )
    el = np.flatnonzero((model.element_component == ci) & (model.element_nodes == at_node))
    if el.size == 0:
        raise ModelError(
            "no element starts there",
            field="output",
            value=f"torque:{name}",
            valid=", ".join(signal_names(model)["outputs"]),
        )
    e = int(el[0])
    rows = model.T[model.node_dof([at_node + 1, at_node])].toarray()
    diff = rows[1] - model.element_ratio[e] * rows[0]  # θ₁ − n·θ₂: rows holds [θ₂, θ₁]
    return diff, float(model.element_stiffness[e]), float(model.element_damping[e])


@follows_policy
def state_space(
    result: ModalResult, inputs, outputs, *, max_hz: float | None = None, speed_rpm: float = 0.0
) -> StateSpace:
    """The modal state space of a drivetrain between named inputs and outputs.

    Parameters
    ----------
    result : ModalResult
        The modes (all of them, or enough to cover ``max_hz``).
    inputs, outputs : sequence of str
        Signal names (see the module docstring); an unknown one is an error listing the valid ones.
    max_hz : float, optional
        Keep only the modes up to this frequency, Hz (the rigid-body mode is always kept).
    speed_rpm : float
        The line's speed (at the driving end), rpm, at most
        :data:`~flexshaft.validation.MAX_SPEED_RPM` either way: a spinning 6-DOF model's gyroscopic
        forces −Ω·G·q̇ join the damping block, A = [[0, I], [−Ω², −Φᵀ(C + ΩG)Φ]] (a torsion model has
        none, so its system does not depend on speed). Linear at that fixed speed.
    """
    model = result.model
    speed_rpm = check_real(speed_rpm, "speed", "rpm", lo=-MAX_SPEED_RPM, hi=MAX_SPEED_RPM)
    inputs, outputs = list(inputs), list(outputs)
    if not inputs or not outputs:
        raise ModelError(
            "needs at least one input and one output",
            field="signals",
            valid=", ".join(signal_names(model)["outputs"]),
        )
    keep = np.ones(result.count, dtype=bool)
    if max_hz is not None:
        max_hz = check_frequency(max_hz, "max_hz", lo_open=True)
        keep = result.rigid | (result.frequencies_hz <= max_hz)
    Phi = result.shapes[:, keep]
    w = result.omega[keep]
    m = w.size
    Dm = modal_damping_block(model.C, Phi, result.rigid[keep], rayleigh_alpha(model))
    if speed_rpm and model.G is not None:
        Gm = Phi.T @ (model.G @ Phi)
        # the line's speed in rad/s; a 6-DOF model has no gear stages, every shaft turns with it
        Dm = Dm + (speed_rpm * 2 * np.pi / 60) * 0.5 * (Gm - Gm.T)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(w**2), -Dm]])
    F = np.column_stack([_station_row(model, name, "input") for name in inputs])
    B = np.vstack([np.zeros((m, len(inputs))), Phi.T @ F])
    rows_q, rows_v, units = [], [], []
    for name in outputs:
        kind, _, what = name.partition(":")
        if kind == "angle":
            r = _station_row(model, what, "output")
            rows_q.append(r), rows_v.append(np.zeros_like(r)), units.append("rad")
        elif kind == "speed":
            r = _station_row(model, what, "output")
            rows_q.append(np.zeros_like(r)), rows_v.append(r), units.append("rad/s")
        elif kind == "torque":
            rq, rv = _torque_rows(model, what)
            rows_q.append(rq), rows_v.append(rv), units.append("N·m")
        else:
            raise ModelError(
                "no such signal", field="output", value=name, valid=", ".join(signal_names(model)["outputs"])
            )
    C = np.hstack([np.array(rows_q) @ Phi, np.array(rows_v) @ Phi])
    modes = np.flatnonzero(keep)
    return StateSpace(
        A=A,
        B=B,
        C=C,
        D=np.zeros((len(outputs), len(inputs))),
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        input_units=("N·m",) * len(inputs),
        output_units=tuple(units),
        states=tuple(f"mode {k}" for k in modes) + tuple(f"mode {k} rate" for k in modes),
        modes=modes,
        frequencies_hz=result.frequencies_hz[keep],
    )


def frequency_grid(system: StateSpace, f_from: float, f_to: float, points: int) -> np.ndarray:
    """An evenly spaced grid, Hz, refined around every resonance inside it.

    A lightly damped drivetrain mode (ξ = 0.01 %) has a half-power band of 2ξf, far
    narrower than any practical even grid, which would then miss or misplace the peak.
    So 13 points spaced ξf/2 apart (± 3 half-power bandwidths) are added around each
    pole's natural frequency ``|λ|/2π`` inside [f_from, f_to]: the peak of ``|H|`` is found
    within ξf/4 and its half-power points are resolved.
    """
    f_from = check_frequency(f_from, "from")
    f_to = check_frequency(f_to, "to", lo=f_from, lo_open=True)
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise ModelError("must be a whole number >= 2", field="points", value=points, valid="2, 3, ...")
    from ..system.limits import check_ceiling

    check_ceiling("frf_points", int(points), field="points")
    f = [np.linspace(f_from, f_to, int(points))]
    for lam in system.poles():
        if lam.imag <= 0:
            continue
        fn = abs(lam) / (2 * np.pi)
        xi = -lam.real / abs(lam)
        if xi <= 1e-12:
            continue  # an undamped mode: its peak is infinite, there is no band to resolve
        local = fn * (1.0 + 0.5 * xi * np.arange(-6, 7))
        f.append(local[(local >= f_from) & (local <= f_to)])
    return np.unique(np.concatenate(f))


#: The most memory one chunk of frequencies may take in :func:`frequency_response`, bytes. A
#: non-diagonal modal damping block needs an m × m complex matrix per frequency (16·m² bytes):
#: examples/ptss_full.toml's 1 159 modes at 2 000 frequencies would be 43 GB stacked at once.
#: 64 MB holds Customer 1's 10 000 frequencies in one chunk, 3 of that 6-DOF model's.
FRF_CHUNK_BYTES = 64 * 2**20


def _off_diagonal_zero(X: np.ndarray) -> bool:
    """True when every off-diagonal entry of the square X is exactly 0 (not merely small)."""
    return np.count_nonzero(X) == np.count_nonzero(np.diag(X))


def _on_a_pole(fk: float) -> ModelError:
    # Exactly on an undamped pole: at 0 Hz for a free drivetrain (its rigid-body mode),
    # or at the natural frequency of a mode without damping. The response is infinite.
    return ModelError(
        "the response is infinite there: an undamped pole (a free drivetrain's rigid-body "
        "mode at 0 Hz, or a mode without damping)",
        field="frequencies",
        value=float(fk),
        unit="Hz",
        valid="frequencies off the undamped poles (start above 0 Hz for a free drivetrain)",
    )


def _check_coupled_work(frequencies: int, m: int) -> None:
    """Refuse a response whose coupled modes make every frequency a long dense solve (ceiling
    ``dense_work``): 16 000 frequencies of 1 159 coupled modes were hours of LAPACK."""
    from ..system.limits import check_ceiling, dense_work

    work = dense_work(frequencies, m)
    check_ceiling(
        "dense_work",
        work,
        field="frequencies",
        value=frequencies,
        unit="frequencies",
        detail=f"each a dense solve of the {m} modes the damping couples, the work of {work:.3g} solves "
        "of order 1000",
        hint="keep fewer modes, --max-hz, or ask for fewer frequencies",
    )


def _checked_frequencies(frequencies_hz) -> np.ndarray:
    """The frequencies as a float array, Hz: a non-empty 1-D list of finite values from 0 to
    :data:`~flexshaft.validation.MAX_FREQUENCY_HZ`, else refused naming the first bad one."""
    try:
        f = np.asarray(frequencies_hz, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(
            "not a list of numbers", field="frequencies", unit="Hz", valid="finite frequencies >= 0 Hz"
        ) from None
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f) & (f >= 0) & (f <= MAX_FREQUENCY_HZ)):
        bad = f[~(np.isfinite(f) & (f >= 0) & (f <= MAX_FREQUENCY_HZ))]
        raise ModelError(
            f"must be a non-empty 1-D list of finite frequencies from 0 to {MAX_FREQUENCY_HZ:g} Hz",
            field="frequencies",
            value=float(bad.flat[0]) if bad.size else None,
            unit="Hz",
            valid=f"finite frequencies >= 0 and <= {MAX_FREQUENCY_HZ:g} Hz",
        )
    return f


@follows_policy
def frequency_response(system: StateSpace, frequencies_hz) -> FrequencyResponse:
    """The frequency response H(f) = C (i2πf·I − A)⁻¹ B + D of a modal state space.

    Evaluated in the modal form ``A = [[0, I], [−Ω², −Dm]]``, never as a dense inverse: at
    ω = 2πf the modal coordinates solve (Ω² − ω²I + iω·Dm) η = Bq (m × m, half the size of
    sI − A) and y = (Cq + iω·Cv) η + D, where ``B = [[0], [Bq]]`` and ``C = [Cq, Cv]``.

    Parameters
    ----------
    system : StateSpace
        The modal state space, as :func:`state_space` builds it.
    frequencies_hz : array_like of float, shape (f,)
        The frequencies, Hz: a non-empty 1-D list of finite values from 0 to
        :data:`~flexshaft.validation.MAX_FREQUENCY_HZ`.

    Returns
    -------
    FrequencyResponse
        ``H`` of shape (f, n_outputs, n_inputs), complex: each output per unit input torque, in
        the output's unit per N·m (rad/(N·m), rad/s/(N·m), N·m/(N·m)).

    Raises
    ------
    ModelError
        The frequencies are not a non-empty 1-D list of finite numbers in that range, or one sits
        exactly on an undamped pole (a free drivetrain's rigid-body mode at 0 Hz, a mode without
        damping): the response is infinite there. The message names the first such frequency.

    Notes
    -----
    When Ω² and Dm are both diagonal, exactly (modal damping: every off-diagonal entry 0; a
    ΦᵀCΦ with round-off off the diagonal does not count), each mode is its own oscillator,
    η_j = Bq_j / (ω_j² − ω² + iω·d_j): no solve at all. Otherwise the frequencies go in chunks
    of at most :data:`FRF_CHUNK_BYTES` of stacked matrices, each chunk one batched LU solve
    (LAPACK ``zgesv`` per matrix, the same matrices and pivots as one solve per frequency).
    """
    f = _checked_frequencies(frequencies_hz)
    m = system.A.shape[0] // 2
    W2 = -system.A[m:, :m]  # Ω²
    Dm = -system.A[m:, m:]  # ΦᵀCΦ (+ the gyroscopic ΩΦᵀGΦ of a spinning 6-DOF line)
    Bq = system.B[m:]
    q = Bq.shape[1]
    # Both output blocks in one matrix: one product per chunk gives Cq·η and Cv·η side by side.
    p = system.C.shape[0]
    CqCv = np.vstack([system.C[:, :m], system.C[:, m:]]).T  # (m, 2p)
    diagonal = _off_diagonal_zero(W2) and _off_diagonal_zero(Dm)
    if not diagonal:
        _check_coupled_work(f.size, m)
    # Bytes per frequency: its matrix (or only its diagonal), right-hand side and solution.
    per_frequency = 16 * m * ((1 if diagonal else m) + 2 * q)
    step = max(1, FRF_CHUNK_BYTES // per_frequency)
    H = np.empty((f.size, p, q), dtype=complex)
    if diagonal:
        w2, d = np.diag(W2), np.diag(Dm)
    else:
        Bc = Bq.astype(complex)
        on_diagonal = np.arange(m)
    for lo in range(0, f.size, step):
        fc = f[lo : lo + step]
        w = (2 * np.pi) * fc  # rad/s: s = iω, s² = −ω² exactly
        n = w.size
        if diagonal:
            den = np.empty((n, m), dtype=complex)
            den.real = w2 - (w * w)[:, None]
            den.imag = w[:, None] * d
            # An exact zero is what makes LU's pivot, and the solve, fail; anything else divides.
            zero = np.flatnonzero(np.any(den == 0, axis=1))
            if zero.size:
                raise _on_a_pole(fc[zero[0]])
            eta = Bq[None, :, :] / den[:, :, None]
        else:
            # Ω² − ω²I + iω·Dm with real parts and imaginary parts written apart: the same numbers
            # as W2 + s·Dm + s²·I in complex arithmetic (s = iω: the cross terms are exact zeros).
            # Written in place, so that the chunk's matrices are all the memory it takes.
            M = np.empty((n, m, m), dtype=complex)
            M.real = W2
            M.real[:, on_diagonal, on_diagonal] -= (w * w)[:, None]
            np.multiply(w[:, None, None], Dm, out=M.imag)
            try:
                eta = np.linalg.solve(M, np.broadcast_to(Bc, (n, m, q)))
            except np.linalg.LinAlgError:
                # The batched solve says only that some matrix is singular: the first one, in
                # frequency order, is the one to name (the same LU, one matrix at a time).
                for k in range(n):
                    try:
                        np.linalg.solve(M[k], Bc)
                    except np.linalg.LinAlgError:
                        raise _on_a_pole(fc[k]) from None
                raise
        # y = Cq·η + iω·Cv·η, as one real product per part: (n·q, m) @ (m, 2p).
        e = eta.transpose(0, 2, 1).reshape(n * q, m)
        with np.errstate(over="ignore", invalid="ignore"):  # a response past 1e308 is refused below
            Y = (e.real @ CqCv + 1j * (e.imag @ CqCv)).reshape(n, q, 2 * p).transpose(0, 2, 1)
            H[lo : lo + n] = Y[:, :p] + (1j * w)[:, None, None] * Y[:, p:] + system.D
    finite = np.isfinite(H).reshape(f.size, -1).all(axis=1)
    if not finite.all():
        # 1e-300 Hz beside a free drivetrain's rigid-body pole: |H| ~ 1/(ω²J) = 1e598 rad/(N·m)
        raise ModelError(
            "the response there is beyond double precision: that close to an undamped pole (a free "
            "drivetrain's rigid-body mode at 0 Hz, or a mode without damping)",
            field="frequencies",
            value=float(f[np.argmin(finite)]),
            unit="Hz",
            valid="frequencies farther from the undamped poles (a free drivetrain: from 1e-6 Hz, say)",
        )
    return FrequencyResponse(f, H, system.inputs, system.outputs, system.input_units, system.output_units)


@follows_policy
def response_system(
    drivetrain, inputs, outputs, *, max_hz: float | None = None, speed_rpm: float = 0.0
) -> tuple[ModalResult, StateSpace]:
    """A drivetrain's modes and its state space between named inputs and outputs, in one step.

    Parameters
    ----------
    drivetrain : Drivetrain
        The model (as :func:`flexshaft.input.modelfile.load_model` gives it); it is assembled here.
    inputs, outputs : sequence of str
        Signal names (see the module docstring).
    max_hz : float, optional
        Keep only the modes up to this frequency, Hz (the rigid-body mode is always kept).
    speed_rpm : float
        The line's speed, rpm: a 6-DOF model's gyroscopic terms join the damping.

    Returns
    -------
    (ModalResult, StateSpace)
        Every mode :func:`flexshaft.analysis.modal.response_modes` keeps, and the system built from them.
    """
    from ..model.assembly import assemble
    from .modal import response_modes

    result = response_modes(assemble(drivetrain))
    return result, state_space(result, inputs, outputs, max_hz=max_hz, speed_rpm=speed_rpm)


def default_frf_range(
    system: StateSpace, f_from: float = 0.0, f_to: float | None = None
) -> tuple[float, float]:
    """The frequency range of a response: ``f_to`` by default 1.5 × the highest mode kept.

    Parameters
    ----------
    system : StateSpace
        The system (its ``frequencies_hz``, Hz).
    f_from : float
        First frequency, Hz (checked: 0 <= f_from < f_to).
    f_to : float, optional
        Last frequency, Hz; by default 1.5 × the highest mode kept (at least 1.5 Hz), at most
        :data:`~flexshaft.validation.MAX_FREQUENCY_HZ`.

    Returns
    -------
    (float, float)
        ``(f_from, f_to)``, Hz.
    """
    # the default's ceiling is the option's: a mode above 1e9 Hz (a micrometre disc) is past the range
    top = 1.5 * max(float(system.frequencies_hz.max()), 1.0)
    f_to = f_to if f_to is not None else min(top, MAX_FREQUENCY_HZ)
    if not (0 <= f_from < f_to):
        raise ModelError(
            "must be below f_to",
            field="f_from",
            value=f_from,
            unit="Hz",
            valid=f"0 <= f_from < f_to = {f_to:g} Hz",
        )
    return f_from, f_to

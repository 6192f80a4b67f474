"""The discrete linear machinery of a time run: zero-order-hold discretisation, a linear recursion
run in modal blocks, and the digital speed loop's two linear forms (free, held at a torque limit)
with the run that switches between them (see :mod:`flexshaft.analysis.simulate` for the equations).
:mod:`flexshaft.analysis.hybrid` runs the same loop on a plant that changes at events.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from scipy.signal import lfilter

from ..errors import ModelError
from .scenario import SpeedControl, torque_limits

__all__ = [
    "zoh",
    "ModalBlocks",
    "loop_open",
    "closed_systems",
    "loop_form",
    "closed_run",
    "closed_stepped",
    "limit_crossed",
    "limit_switched",
    "BLOCK_MIN",
    "BLOCK_MAX",
    "COND_MAX",
]

#: Blocks of the vectorised run grow from this many steps to the largest, doubling while no
#: limit switches (memory stays bounded: a block holds n_states complex values per step).
BLOCK_MIN, BLOCK_MAX = 256, 65536
#: Above this eigenvector condition number a loop matrix counts as near-defective: its modal
#: recursion would lose more than half the digits, so the run steps the equations instead.
COND_MAX = 1e8


def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation: one matrix exponential of the augmented system."""
    n, m = A.shape[0], B.shape[1]
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = A * dt, B * dt
    E = sla.expm(aug)
    Ad = E[:n, :n]
    # A state nothing drives back (a zero column of A: a free line's rigid-body angle) maps onto
    # itself exactly; expm's Padé solve and squarings can leave round-off there, which would turn
    # that state's pure accumulation into a near-defective eigenvalue pair.
    for i in np.flatnonzero(~np.any(A, axis=0)):
        Ad[:, i] = 0.0
        Ad[i, i] = 1.0
    return Ad, E[:n, n:]


class ModalBlocks:
    """x_{k+1} = F x_k + G w_k, y_k = H x_k + E w_k, run in modal blocks (see the module docstring)."""

    def __init__(self, F, G, H, E):
        n = F.shape[0]
        eye = np.eye(n)
        # Accumulators: a state that maps onto itself and feeds nothing else (exactly: expm of a
        # zero column is the unit column), summed by cumsum instead of an eigen-recursion.
        acc = np.array([np.array_equal(F[:, i], eye[:, i]) for i in range(n)], dtype=bool)
        keep = ~acc
        self.H, self.E = H, E
        self.acc, self.keep = acc, keep
        Fk = F[np.ix_(keep, keep)]
        self.ok = True
        if keep.any():
            lam, V = np.linalg.eig(Fk)
            cond = np.linalg.cond(V)
            if not np.isfinite(cond) or cond > COND_MAX:
                self.ok = False
                return
            self.lam, self.V = lam, V
            self.Vi = np.linalg.solve(V, np.eye(V.shape[0]))
            self.GV = self.Vi @ G[keep]
            self.HV = H[:, keep] @ V
        self.Fa = F[np.ix_(acc, keep)]  # what the kept states add to each accumulator per step
        self.Ga = G[acc]
        self.Ha = H[:, acc]

    def block(self, x0: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outputs at steps 0 … L−1 of a block starting at state x0, and the state after it."""
        L = W.shape[0]
        keep, acc = self.keep, self.acc
        Y = W @ self.E.T
        x_end = np.empty_like(x0)
        xk = None
        if keep.any():
            z0 = self.Vi @ x0[keep]
            drive = W @ self.GV.T  # (L, n_keep) complex
            Z = np.empty((L + 1, z0.size), dtype=complex)
            Z[0] = z0
            for i, lam in enumerate(self.lam):
                Z[1:, i] = lfilter([1.0], [1.0, -lam], drive[:, i], zi=[lam * z0[i]])[0]
            Y += (Z[:L] @ self.HV.T).real
            x_end[keep] = (self.V @ Z[L]).real
            if acc.any():
                xk = (Z[:L] @ self.V.T).real  # kept states at each step, for the accumulators
        if acc.any():
            inc = W @ self.Ga.T
            if xk is not None:
                inc = inc + xk @ self.Fa.T
            a = x0[acc] + np.vstack([np.zeros((1, inc.shape[1])), np.cumsum(inc, axis=0)])
            Y += a[:L] @ self.Ha.T
            x_end[acc] = a[L]
        return Y, x_end

    def run(self, x0, W, progress=None) -> np.ndarray:
        N = W.shape[0]
        Y = np.empty((N, self.H.shape[0]))
        k, x = 0, x0
        while k < N:
            L = min(BLOCK_MAX, N - k)
            Y[k : k + L], x = self.block(x, W[k : k + L])
            k += L
            if progress is not None:
                progress(k, N)
        return Y


def loop_open(Ad, Bd, C, x0, W) -> np.ndarray:
    """The reference: one step at a time."""
    Y = np.empty((W.shape[0], C.shape[0]))
    x = x0.copy()
    for k in range(W.shape[0]):
        Y[k] = C @ x
        x = Ad @ x + Bd @ W[k]
    return Y


def closed_systems(Ad, Bd, C, control: SpeedControl, dt: float):
    """The loop's two linear forms on the state [x, I, T] and inputs [r, load, held torque].

    Outputs: the plant outputs, then the drive torque T_k applied, then the unlimited command u_k.
    """
    return {
        held: ModalBlocks(*loop_form(Ad, Bd, C, control.kp, control.ki, control.tau, dt, held))
        for held in (False, True)
    }


def loop_form(Ad, Bd, C, kp: float, ki: float, tau: float, dt: float, held: bool):
    """``F, G, H, E`` of one linear form of the loop (see :func:`closed_systems`): free (the command
    applied) or ``held`` (the torque held at a limit, the integrator frozen)."""
    n = Ad.shape[0]
    cs = C[-1]  # the measured speed is the last plant output
    a = math.exp(-dt / tau) if tau > 0 else 0.0
    lowpass = tau > 0
    bT, bL = Bd[:, 0], Bd[:, 1]
    N = n + 2  # x, I, T
    iI, iT = n, n + 1
    F = np.zeros((N, N))
    G = np.zeros((N, 4))  # r, load, held torque, disturbance on the air-gap torque
    # command u = kp·(r − cs·x) + I, either applied (free) or replaced by the held torque
    u_x, u_I, u_r = -kp * cs, 1.0, kp
    F[:n, :n] = Ad
    G[:n, 1] = bL
    G[:n, 3] = bT
    if lowpass:
        F[:n, iT] = bT  # the plant sees T_k
        F[iT, iT] = a
        if held:
            G[iT, 2] = 1 - a
        else:
            F[iT, :n] += (1 - a) * u_x
            F[iT, iI] += (1 - a) * u_I
            G[iT, 0] += (1 - a) * u_r
    else:
        # T_k = u_k: the plant sees the command itself (no state for T; its row stays 0)
        if held:
            G[:n, 2] = bT
        else:
            F[:n, :n] += np.outer(bT, u_x)
            F[:n, iI] += bT * u_I
            G[:n, 0] += bT * u_r
    F[iI, iI] = 1.0
    if not held:
        F[iI, :n] += ki * dt * (-cs)
        G[iI, 0] += ki * dt
    H = np.zeros((C.shape[0] + 2, N))
    E = np.zeros((C.shape[0] + 2, 4))
    E[C.shape[0], 3] = 1.0  # the air-gap torque includes the ripple and noise
    H[: C.shape[0], :n] = C
    # applied torque T_k
    if lowpass:
        H[C.shape[0], iT] = 1.0
    elif held:
        E[C.shape[0], 2] = 1.0
    else:
        H[C.shape[0], :n], H[C.shape[0], iI], E[C.shape[0], 0] = u_x, u_I, u_r
    # unlimited command u_k
    H[C.shape[0] + 1, :n], H[C.shape[0] + 1, iI], E[C.shape[0] + 1, 0] = u_x, u_I, u_r
    return F, G, H, E


def closed_run(Ad, Bd, C, x0, hold, r, load, dist, control, dt, method, progress):
    """The closed loop, in linear pieces between limit switches (or stepped, ``method="loop"``)."""
    N = r.size
    lo, hi = control.torque_min, control.torque_max
    s0 = np.concatenate([x0, [hold, hold]])  # integrator and low-pass start at the holding torque
    if method == "loop":
        return closed_stepped(Ad, Bd, C, s0, r, load, dist, control, dt), "loop"
    if math.isfinite(control.power_limit):
        # a limit that moves with the speed every sample holds the loop in no linear form: stepped
        return closed_stepped(Ad, Bd, C, s0, r, load, dist, control, dt), "loop (power limit)"
    forms = closed_systems(Ad, Bd, C, control, dt)
    if not (forms[False].ok and forms[True].ok):
        return closed_stepped(
            Ad, Bd, C, s0, r, load, dist, control, dt
        ), "loop (a loop matrix is near-defective)"
    n_out = C.shape[0]
    Y = np.empty((N, n_out))
    T = np.empty(N)
    k, s, held, limit = 0, s0, False, 0.0
    size, switches, stalls = BLOCK_MIN, 0, 0
    while k < N:
        L = min(size, N - k)
        W = np.column_stack([r[k : k + L], load[k : k + L], np.full(L, limit), dist[k : k + L]])
        form = forms[held]
        out, s_end = form.block(s, W)
        u = out[:, -1]
        bad = limit_crossed(u, held, limit, lo, hi)
        j = int(bad[0]) if bad.size else L
        if j > 0:
            if j < L:
                out, s_end = form.block(s, W[:j])
            Y[k : k + j], T[k : k + j] = out[:, :n_out], out[:, n_out]
            k, s = k + j, s_end
            stalls = 0
        else:
            stalls += 1
            if stalls > 2:  # cannot happen with complementary conditions; never spin
                raise ModelError("the limit logic does not advance (please report)", field="control")
        if j < L:
            switches += 1
            held, limit = limit_switched(held, limit, u[j], lo, hi)
            size = BLOCK_MIN
        else:
            size = min(2 * size, BLOCK_MAX)
        if progress is not None:
            progress(k, N)
    return {"plant": Y, "torque": T}, f"modal blocks ({switches} limit switches)"


def limit_crossed(u: np.ndarray, held: bool, limit: float, lo: float, hi: float) -> np.ndarray:
    """The samples where the loop changes form. Held: where the unlimited command ``u`` is no longer
    beyond the limit (it may come back inside, or go past the other limit: the free form then holds
    at that one at once). Free: where ``u`` is beyond a limit."""
    if held:
        return np.flatnonzero(u <= hi) if limit == hi else np.flatnonzero(u >= lo)
    return np.flatnonzero((u > hi) | (u < lo))


def limit_switched(held: bool, limit: float, u: float, lo: float, hi: float) -> tuple[bool, float]:
    """The loop's form (held?) and held torque after a switch at a sample where the unlimited command
    is ``u``."""
    if held:
        return False, limit
    return True, (hi if u > hi else lo)


def closed_stepped(Ad, Bd, C, s0, r, load, dist, control, dt):
    """The reference: the control law stepped one sample at a time (module docstring)."""
    n = Ad.shape[0]
    N = r.size
    x, I, T = s0[:n].copy(), float(s0[n]), float(s0[n + 1])
    a = math.exp(-dt / control.tau) if control.tau > 0 else 0.0
    Y = np.empty((N, C.shape[0]))
    Ts = np.empty(N)
    power = math.isfinite(control.power_limit)
    lo, hi = control.torque_min, control.torque_max
    for k in range(N):
        y = C @ x
        Y[k] = y
        e = r[k] - y[-1]
        u = control.kp * e + I
        if power:
            lo, hi = (float(v) for v in torque_limits(control, y[-1]))
        if u > hi:
            u = hi
        elif u < lo:
            u = lo
        else:
            I += control.ki * dt * e
        applied = (T if control.tau > 0 else u) + dist[k]
        Ts[k] = applied
        x = Ad @ x + Bd @ np.array([applied, load[k]])
        if control.tau > 0:
            T = a * T + (1 - a) * u
    return {"plant": Y, "torque": Ts}

"""The modes of a calibration's targets, followed by their shape from point to point.

Modes are followed by their shape, never by their number: the modes a target names are those of the
starting model, and at every evaluation each is found again as the mode whose shape matches it best
(inertia-weighted MAC, :func:`~flexshaft.linalg.mac.mac`: a model's distinct modes have MAC 0) along
the straight path from the last evaluated point - halving the step until every tracked mode has a
clear match - so two modes crossing on the way keep their targets.
"""

from __future__ import annotations

import numpy as np

from ...errors import ModelError
from ...linalg.mac import mac
from ..modal import ModalResult, modal_analysis
from ..parametrised import ParametrisedModel

__all__ = ["Tracker", "undamped_modes", "target_values", "MAC_CLEAR", "MAX_HALVINGS"]

#: A tracked mode's best match must have at least this MAC (and beat the runner-up), or the step
#: from the last point is halved.
MAC_CLEAR = 0.8
#: Halvings of one step before tracking gives up (2⁻¹² of the step).
MAX_HALVINGS = 12


class Tracker:
    """The modes of the targets, followed by shape from point to point (see the module docstring).

    The model at a point is ``model`` there (a :class:`ParametrisedModel`: no assembly at all where
    K and M are affine in the parameters)."""

    def __init__(self, model: ParametrisedModel, start: np.ndarray, wanted: np.ndarray, result=None):
        self.param = model
        self.wanted = wanted  # mode numbers of the starting model the targets use
        self.point = start.copy()
        self.result = self._solve(start) if result is None else result  # the modes at start, if known
        self.modes = wanted.copy()
        self.shapes = self.result.shapes[:, wanted]

    def _solve(self, x: np.ndarray):
        return undamped_modes(self.param.model(x), self.wanted)

    def _match(self, result) -> np.ndarray | None:
        macs = mac(self.shapes, result.shapes, result.model.M)  # inertia-weighted: distinct modes 0
        macs[:, result.rigid] = 0.0
        best = np.argmax(macs, axis=1)
        top = macs[np.arange(best.size), best]
        second = np.sort(macs, axis=1)[:, -2] if macs.shape[1] > 1 else np.zeros(best.size)
        if np.any(top < MAC_CLEAR) or np.any(second > top - 0.1) or np.unique(best).size != best.size:
            return None
        return best

    def go(self, x: np.ndarray):
        """Move to x along the straight path, halving steps until every mode is matched clearly."""
        x = np.asarray(x, dtype=float)
        if np.array_equal(x, self.point):
            return self.result, self.modes
        for _ in range(1000):  # sub-steps; each one accepted moves the reference on
            result = self._solve(x)
            matched = self._match(result)
            if matched is not None:
                self._accept(x, result, matched)
                return result, matched
            step, frac = x - self.point, 0.5
            for _ in range(MAX_HALVINGS):
                mid = self.point + frac * step
                r_mid = self._solve(mid)
                m_mid = self._match(r_mid)
                if m_mid is not None:
                    self._accept(mid, r_mid, m_mid)
                    break
                frac *= 0.5
            else:
                raise ModelError(
                    "cannot follow the targets' modes by shape (two modes too alike along the way)",
                    field="target",
                    valid="targets on modes that stay distinguishable, or narrower bounds",
                )
        raise ModelError("mode tracking does not converge", field="target")

    def _accept(self, x, result, matched):
        self.point = x.copy()
        self.result = result
        self.modes = matched
        self.shapes = result.shapes[:, matched]


def undamped_modes(m, wanted) -> ModalResult:
    """The undamped modes the tracker compares: all of a model up to 2000 coordinates (a tracked
    mode may move anywhere among them), else the lowest beyond the highest wanted (checked to be
    the model's: :func:`check_targets`)."""
    n = m.n_dof
    return modal_analysis(m, n if n <= 2000 else min(n, max(int(np.max(wanted)) + 6, 16)), damped=False)


def target_values(result, modes_of: dict, targets) -> np.ndarray:
    f = result.frequencies_hz
    out = []
    for t in targets:
        v = f[modes_of[t.mode]]
        if t.ratio_to is not None:
            v = v / f[modes_of[t.ratio_to]]
        out.append(v)
    return np.array(out)

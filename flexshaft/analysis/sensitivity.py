"""The exact sensitivity of every mode to each model parameter (named as
:mod:`flexshaft.analysis.parameters` names them).

Sensitivities are analytic: for a mass-normalised mode φ with eigenvalue λ = ω²,
``∂λ/∂p = φᵀ(∂K/∂p − λ ∂M/∂p)φ`` - exact for the discrete model. ∂K/∂p and ∂M/∂p are the
derivatives of the assembled matrices, taken by a central difference of the assembly, which is
exact to round-off for every parameter the matrices are linear or quadratic in (all but a
section scale in a 6-DOF model, where it is O(h²) = 1e-12). The first-order damping ratio
ξ = φᵀCφ/(2ω) gets its derivative from ∂C/∂p, ∂ω and the mode's own derivative ∂φ (by modal
expansion over all modes, exact when every mode of the model is computed: torsion models up to
2000 coordinates). Flexible bodies are differentiated on the unreduced model (the physical
sensitivity; the reduced model reproduces it to its reduction error), which carries no damping of a
flexible body's own: ∂ξ/∂p of a body's ``damping_ratio`` is NaN there (the calibration evaluates it
on the reduced model, :mod:`flexshaft.analysis.calibrate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..model.assembly import assemble
from ..model.components import Drivetrain, Shaft
from ..system.threads import follows_policy
from ..validation import check_int
from .modal import ModalResult, modal_analysis

# The parameters' names and values are parameters.py's and the parametrised model parametrised.py's;
# these are imported here too for the callers that name them from this module.
from .parameters import find_parameter, parameter_value, parameters, with_parameters
from .parametrised import STEP, in_double_precision

__all__ = [
    "Sensitivities",
    "sensitivities",
    "lowest_elastic",
    "frequency_derivatives",
    "MAX_DAMPING_DOFS",
]

#: Largest model whose damping-ratio sensitivities are computed (all its modes are needed).
MAX_DAMPING_DOFS = 2000


@dataclass(frozen=True)
class Sensitivities:
    """How every listed mode moves with every parameter.

    Attributes
    ----------
    parameters : tuple of Parameter
    values : ndarray, shape (p,)
        Each parameter's value, SI.
    modes : ndarray of int
        The modes (numbered as ``flexshaft modes`` does; rigid-body modes left out).
    frequencies_hz : ndarray, shape (m,)
    damping_ratios : ndarray, shape (m,)
        First-order ratios φᵀCφ/(2ω) (0 without damping).
    dfrequency : ndarray, shape (m, p)
        ∂f/∂p, Hz per parameter unit.
    ddamping : ndarray, shape (m, p) or None
        ∂ξ/∂p (first-order ξ), per parameter unit; None where not all modes are available; NaN for a
        flexible body's ``damping_ratio`` (its damping acts on the reduced model, not on the unreduced
        one differentiated here).
    """

    parameters: tuple
    values: np.ndarray
    modes: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    dfrequency: np.ndarray
    ddamping: np.ndarray | None

    @property
    def normalised(self) -> np.ndarray:
        """(p/f)·∂f/∂p: % change of each frequency per % change of each parameter, shape (m, p)."""
        return self.dfrequency * self.values[None, :] / self.frequencies_hz[:, None]

    @property
    def normalised_damping(self) -> np.ndarray | None:
        """(p/ξ)·∂ξ/∂p, shape (m, p); NaN where ξ = 0."""
        if self.ddamping is None:
            return None
        with np.errstate(divide="ignore", invalid="ignore"):
            z = self.damping_ratios[:, None]
            return np.where(z > 0, self.ddamping * self.values[None, :] / z, np.nan)

    def to_dict(self) -> dict:
        """The ``flexshaft sensitivity --json`` document."""

        def num(x):
            x = float(x)
            return x if np.isfinite(x) else None

        nd = self.normalised_damping
        return {
            "units": {
                "frequency": "Hz",
                "dfrequency": "Hz per parameter unit",
                "normalised": "% per % (p/f·∂f/∂p)",
                "damping_ratio": "fraction (first order, φᵀCφ/2ω)",
            },
            "parameters": [
                {"name": p.name, "value": float(v), "unit": p.unit}
                for p, v in zip(self.parameters, self.values)
            ],
            "modes": [
                {
                    "mode": int(m),
                    "frequency_hz": float(self.frequencies_hz[i]),
                    "damping_ratio": float(self.damping_ratios[i]),
                    "dfrequency": {p.name: num(v) for p, v in zip(self.parameters, self.dfrequency[i])},
                    "normalised": {p.name: num(v) for p, v in zip(self.parameters, self.normalised[i])},
                    **(
                        {}
                        if self.ddamping is None
                        else {
                            "ddamping": {p.name: num(v) for p, v in zip(self.parameters, self.ddamping[i])},
                            "normalised_damping": {p.name: num(v) for p, v in zip(self.parameters, nd[i])},
                        }
                    ),
                }
                for i, m in enumerate(self.modes)
            ],
        }

    def plot(self):
        """The normalised sensitivities as a heat map (modes × parameters), a matplotlib Figure."""
        from ..views.plots import sensitivity_figure

        return sensitivity_figure(self)

    def table(self, name: str) -> str:
        """The ``flexshaft sensitivity`` table of the model ``name``: % per % for each parameter and
        mode."""
        width = max(16, *(len(p.name) for p in self.parameters))
        rows = [
            f"{name}: frequency sensitivities, % per % (p/f·∂f/∂p); Hz per unit with --json",
            "",
            f"{'parameter':<{width}} {'value':>12} {'unit':>9}  "
            + "  ".join(f"{f'mode {m}':>9}" for m in self.modes),
            f"{'':<{width}} {'':>12} {'':>9}  "
            + "  ".join(f"{f'{f:.4g} Hz':>9}" for f in self.frequencies_hz),
        ]
        for k, p in enumerate(self.parameters):
            cells = "  ".join(f"{v:9.4f}" for v in self.normalised[:, k])
            rows.append(f"{p.name:<{width}} {self.values[k]:12.6g} {p.unit:>9}  {cells}")
        return "\n".join(rows)


def _mode_numbers(modes, model) -> np.ndarray:
    """``modes`` as mode numbers of ``model``'s elastic modes, checked before anything is solved:
    whole numbers from the first elastic mode (the rigid-body modes come first) to the last."""
    n, rigid = model.n_dof, model.rigid_basis.shape[1]
    valid = f"an elastic mode, {rigid} … {n - 1}" if n > rigid else "a model with elastic modes"
    try:
        numbers = list(np.ravel(np.asarray(modes, dtype=object)))
    except (TypeError, ValueError):
        raise ModelError("not a list of mode numbers", field="mode", valid=valid) from None
    if not numbers:
        raise ModelError("no modes", field="mode", valid=valid)
    out = []
    for i in numbers:
        k = check_int(i, "mode", lo=0)
        if k < rigid or k >= n:
            zero = "mode 0" if rigid == 1 else f"modes 0 … {rigid - 1}"
            raise ModelError(
                f"the model has {n} modes, {zero} rigid-body",
                field="mode",
                value=k,
                valid=valid,
            )
        out.append(k)
    return np.array(out, dtype=int)


def lowest_elastic(model, count, field: str) -> np.ndarray:
    """The numbers of the lowest ``count`` elastic modes of an assembled model, as ``flexshaft modes``
    numbers them (the rigid-body modes first); more than the model has is refused, naming ``field``.

    Parameters
    ----------
    model : AssembledModel
    count : int
    field : str
        The option or argument the count came from (``"--modes"``), for the message.
    """
    n, rigid = model.n_dof, model.rigid_basis.shape[1]
    count = check_int(count, field, lo=1)
    if count > n - rigid:
        zero = "mode 0 is" if rigid == 1 else f"modes 0 … {rigid - 1} are"
        raise ModelError(
            f"the model has only {n} DOFs, so {n} modes, {n - rigid} of them elastic ({zero} rigid-body)",
            field=field,
            value=count,
            valid=f"at most {n - rigid}" if n > rigid else "a model with elastic modes",
        )
    return np.arange(rigid, rigid + count)


def _matrices(d: Drivetrain, inertia_model):
    m = assemble(d, inertia_model, reduce=False)
    C = m.C if m.C is not None else sp.csr_matrix(m.K.shape)
    return m, m.K, m.M, C


def _ratio_derivatives(Phi, lam, sel, w, zeta, dlam, dKP, dMP, C, dC) -> np.ndarray:
    """∂ξ/∂p of the first-order ratios ξ = φᵀCφ/(2ω) of the modes ``sel`` (every mode of the model in
    ``Phi``, mass-normalised; ``dlam`` their ∂λ, ``dKP``, ``dMP`` = ∂K·Φ, ∂M·Φ, ``dC`` = ∂C)."""
    out = np.empty(sel.size)
    for a, i in enumerate(sel):
        # ∂φ_i = Σ_{j≠i} φ_j·φ_jᵀ(∂K − λ_i∂M)φ_i/(λ_i − λ_j) − ½(φ_iᵀ∂Mφ_i)·φ_i (mass-normalised)
        r = Phi.T @ (dKP[:, i] - lam[i] * dMP[:, i])
        gap = lam[i] - lam
        coef = np.where(np.arange(lam.size) == i, 0.0, r / np.where(gap == 0, np.inf, gap))
        coef[i] = -0.5 * (Phi[:, i] @ dMP[:, i])
        dphi = Phi @ coef
        dw = dlam[a] / (2 * w[a])
        out[a] = (2 * Phi[:, i] @ (C @ dphi) + Phi[:, i] @ (dC @ Phi[:, i])) / (2 * w[a]) - zeta[a] * dw / w[
            a
        ]
    return out


@follows_policy
@in_double_precision
def sensitivities(
    drivetrain: Drivetrain,
    names=None,
    *,
    modes=None,
    inertia_model: str | None = None,
    result: ModalResult | None = None,
) -> Sensitivities:
    """Analytic sensitivities of the modes of ``drivetrain`` to the named parameters.

    Parameters
    ----------
    drivetrain : Drivetrain
    names : sequence of str, optional
        Parameters (default: every parameter, see :func:`parameters`).
    modes : sequence of int, optional
        Modes to report, numbered as ``flexshaft modes`` numbers them (default: every elastic mode
        computed: all of a model up to :data:`MAX_DAMPING_DOFS` coordinates, else the solver's
        default count). A rigid-body mode or a number beyond the model's modes is refused before
        anything is solved (:func:`lowest_elastic` gives the lowest N).
    inertia_model : str, optional
    result : ModalResult, optional
        The modes of the unreduced model of ``drivetrain``, if already computed (its assembly is
        used as it is).
    """
    if not isinstance(drivetrain, Drivetrain):
        raise ModelError("needs a Drivetrain", field="model", valid="a Drivetrain (load_model)")
    plist = (
        [p for p in parameters(drivetrain)]
        if names is None
        else [find_parameter(drivetrain, n) for n in names]
    )
    if not plist:
        raise ModelError("no parameters", field="parameter", valid="at least one")
    twice = [p.name for k, p in enumerate(plist) if p in plist[:k]]
    if twice:
        raise ModelError("a parameter is listed twice", field="parameter", value=twice[0], valid="each once")
    if result is not None and not result.model.bodies:
        # the modes were solved on this very (unreduced) assembly: its matrices, not a second one
        model0 = result.model
        C0 = model0.C if model0.C is not None else sp.csr_matrix(model0.K.shape)
        K0, M0 = model0.K, model0.M
    else:
        model0, K0, M0, C0 = _matrices(drivetrain, inertia_model)
    wanted = None if modes is None else _mode_numbers(modes, model0)
    if result is None:
        count = model0.n_dof if model0.n_dof <= MAX_DAMPING_DOFS else None
        if count is None and wanted is not None:
            count = max(int(wanted.max()) + 1, 1)  # up to the highest mode asked for, however many
        result = modal_analysis(model0, count, damped=False)
    elastic = np.flatnonzero(~result.rigid)
    sel = elastic if wanted is None else wanted
    bad = [int(i) for i in sel if i < 0 or i >= result.count or result.rigid[i]]
    if bad:
        raise ModelError(
            "no such elastic mode",
            field="mode",
            value=bad[0],
            valid=f"{int(elastic[0])} … {result.count - 1}" if elastic.size else "a model with elastic modes",
        )
    Phi = result.shapes
    lam = result.omega**2
    values = np.array([parameter_value(drivetrain, p.name) for p in plist])
    full = result.count == model0.n_dof  # every mode: the modal expansion of ∂φ is exact
    dlam = np.zeros((sel.size, len(plist)))
    dzeta = np.zeros((sel.size, len(plist))) if full else None
    w = np.sqrt(lam[sel])
    C = C0
    zeta = np.einsum("ij,ij->j", Phi[:, sel], C @ Phi[:, sel]) / (2 * w)
    for k, p in enumerate(plist):
        v = values[k]
        h = STEP * (abs(v) if v != 0 else 1.0)
        plus = _matrices(with_parameters(drivetrain, {p.name: v + h}), inertia_model)
        if v == 0:
            # at the bound 0 (no damper yet): a forward difference, as exact for the linear dependence
            minus, h = (model0, K0, M0, C0), h / 2
        else:
            minus = _matrices(with_parameters(drivetrain, {p.name: v - h}), inertia_model)
        if plus[1].shape != K0.shape or minus[1].shape != K0.shape:
            raise ModelError(
                "changes the model's mesh, so it has no derivative here", field="parameter", value=p.name
            )
        dK = (plus[1] - minus[1]) / (2 * h)
        dM = (plus[2] - minus[2]) / (2 * h)
        dC = (plus[3] - minus[3]) / (2 * h)
        dKP, dMP = dK @ Phi, dM @ Phi
        for a, i in enumerate(sel):
            dlam[a, k] = Phi[:, i] @ dKP[:, i] - lam[i] * (Phi[:, i] @ dMP[:, i])
        if dzeta is not None:
            dzeta[:, k] = _ratio_derivatives(Phi, lam, sel, w, zeta, dlam[:, k], dKP, dMP, C, dC)
    if dzeta is not None:
        for k, p in enumerate(plist):
            c = drivetrain.component(p.owner) if p.kind == "component" else None
            if p.field == "damping_ratio" and isinstance(c, Shaft) and c.reduce is not None:
                # a flexible body's damping acts on its reduced model only: not seen here (see above)
                dzeta[:, k] = np.nan
    f = w / (2 * np.pi)
    dfreq = dlam / (2 * w[:, None]) / (2 * np.pi)  # f = √λ/2π: ∂f = ∂λ/(2ω·2π)
    return Sensitivities(
        parameters=tuple(plist),
        values=values,
        modes=sel,
        frequencies_hz=f,
        damping_ratios=zeta,
        dfrequency=dfreq,
        ddamping=dzeta,
    )


@follows_policy
def frequency_derivatives(result: ModalResult, derivatives, modes) -> np.ndarray:
    """∂f/∂x of the given modes from ∂λ = φᵀ(∂K − λ∂M)φ (mass-normalised φ), Hz per parameter unit.

    Parameters
    ----------
    result : ModalResult
        The modes at the point (mass-normalised shapes).
    derivatives : sequence of (∂K, ∂M)
        Per parameter (:meth:`ParametrisedModel.derivatives`).
    modes : sequence of int
        Elastic modes of ``result``.

    Returns
    -------
    ndarray, shape (len(modes), len(derivatives))
    """
    modes = np.asarray(modes, dtype=int)
    Phi = result.shapes[:, modes]
    lam = result.omega[modes] ** 2
    dlam = np.empty((modes.size, len(derivatives)))
    for k, (dK, dM) in enumerate(derivatives):
        dlam[:, k] = np.einsum("ij,ij->j", Phi, dK @ Phi) - lam * np.einsum("ij,ij->j", Phi, dM @ Phi)
    w = result.omega[modes]
    return dlam / (2 * w[:, None]) / (2 * np.pi)  # f = √λ/2π: ∂f = ∂λ/(2ω·2π)

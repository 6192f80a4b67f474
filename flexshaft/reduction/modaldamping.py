"""Damping of a flexible body's own modes: one ratio, per mode, per frequency band, or Rayleigh.

:class:`ModalDamping` says which ratio each elastic free-free mode of a
reduced part gets; :func:`flexshaft.reduction.craig_bampton` turns it into the
reduced damping matrix. Rigid-body modes get no ratio.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..linalg.damping import RAYLEIGH_ALPHA_MAX, RAYLEIGH_BETA_MAX, check_rayleigh, rayleigh_ratio
from ..validation import FRACTION, FRACTION_VALID

__all__ = ["ModalDamping"]


_BAND = "(f_lo_hz, f_hi_hz, ratio) with 0 <= f_lo_hz < f_hi_hz, both finite (Hz), and ratio in [0, 1)"


def _check_fraction(value: object, field: str) -> float:
    """A damping ratio as a float in [0, 1), or a ModelError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ModelError("not a number", field=field, value=value, valid=FRACTION_VALID, has_value=True)
    x = float(value)
    if not FRACTION.contains(x):
        raise ModelError("must be in [0, 1)", field=field, value=x, valid=FRACTION_VALID)
    return x


def _as_sequence(value: object, field: str, valid: str) -> tuple:
    """``value`` as a tuple, refusing scalars and strings (a string is a sequence of characters)."""
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
        raise ModelError("not a sequence", field=field, value=value, valid=valid, has_value=True)
    return tuple(value)


def _check_band(band: object, k: int) -> tuple[float, float, float]:
    """One (f_lo_hz, f_hi_hz, ratio) band, validated; ``k`` names it in messages."""
    field = f"damping_bands[{k}]"
    items = _as_sequence(band, field, _BAND)
    if len(items) != 3 or any(isinstance(v, bool) or not isinstance(v, numbers.Real) for v in items):
        raise ModelError("must be three numbers", field=field, value=band, valid=_BAND, has_value=True)
    lo, hi, ratio = (float(v) for v in items)
    shown = (lo, hi, ratio)
    if not (np.isfinite(lo) and lo >= 0.0):
        raise ModelError(
            "f_lo_hz must be finite and >= 0", field=field, value=shown, unit="(Hz, Hz, -)", valid=_BAND
        )
    if not (np.isfinite(hi) and hi > lo):
        raise ModelError(
            "f_hi_hz must be finite and above f_lo_hz",
            field=field,
            value=shown,
            unit="(Hz, Hz, -)",
            valid=_BAND,
        )
    if not FRACTION.contains(ratio):
        raise ModelError("ratio must be in [0, 1)", field=field, value=shown, unit="(Hz, Hz, -)", valid=_BAND)
    return shown


@dataclass(frozen=True)
class ModalDamping:
    """Damping of a flexible body's free-free modes, set per mode, per band or as Rayleigh.

    The modes are those of the orthonormalised basis of :func:`craig_bampton`
    (the reduced part's own free-free modes, ``FlexibleBody.free_hz``).
    Rigid-body modes get ratio 0 under ``ratio``, ``by_mode`` and ``bands``.

    Parameters
    ----------
    ratio : float
        Damping ratio (fraction, [0, 1)) of every elastic mode that ``bands``
        does not cover. The study's 0.53 % by default. Unused with ``by_mode``
        or ``rayleigh``.
    by_mode : sequence of float
        Ratios (fractions, [0, 1)) of elastic modes 1, 2, … in frequency order,
        rigid-body modes not counted. Modes past the end of the list get the
        last listed ratio, so ``(0.01, 0.02)`` damps mode 1 at 1 % and every
        higher mode at 2 %. Messages name entry ``k`` (from 0)
        ``damping_ratio[k]``.
    bands : sequence of (f_lo_hz, f_hi_hz, ratio)
        Frequency bands, Hz: an elastic mode with f_lo_hz <= f < f_hi_hz gets
        the band's ratio, modes in no band get ``ratio``. Bands may touch but
        not overlap. Messages name band ``k`` (from 0) ``damping_bands[k]``.
    rayleigh : (float, float), optional
        (alpha 1/s, beta s), both >= 0: the reduced damping matrix is then
        exactly C = alpha·M + beta·K on the Craig–Bampton matrices and mode i
        has ξ_i = alpha/(2ω_i) + beta·ω_i/2 (a ratio >= 1 means that mode is
        overdamped). Rigid-body modes are reported at 0, but alpha·M also
        resists rigid-body velocity (a damper to ground, decay rate alpha
        1/s): keep alpha = 0 for a body that moves freely in a multibody
        model. Excludes ``by_mode`` and ``bands``.

    Raises
    ------
    ModelError
        On a ratio outside [0, 1), a band that is malformed or overlaps
        another, a negative or non-finite Rayleigh coefficient, or Rayleigh
        together with ``by_mode`` or ``bands``, or ``by_mode`` with ``bands``
        (per-mode ratios already cover every mode).

    Examples
    --------
    >>> ModalDamping(by_mode=(0.01, 0.02))  # mode 1 at 1 %, all higher at 2 %
    ModalDamping(ratio=0.0053, by_mode=(0.01, 0.02), bands=(), rayleigh=None)
    >>> ModalDamping(ratio=0.005, bands=[(0.0, 500.0, 0.02)])  # 2 % below 500 Hz
    ModalDamping(ratio=0.005, by_mode=(), bands=((0.0, 500.0, 0.02),), rayleigh=None)
    """

    ratio: float = 0.0053
    by_mode: tuple[float, ...] = ()
    bands: tuple[tuple[float, float, float], ...] = ()
    rayleigh: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "ratio", _check_fraction(self.ratio, "damping_ratio"))
        by_mode = _as_sequence(self.by_mode, "damping_ratio", "a sequence of fractions in [0, 1)")
        by_mode = tuple(_check_fraction(z, f"damping_ratio[{k}]") for k, z in enumerate(by_mode))
        object.__setattr__(self, "by_mode", by_mode)
        bands = _as_sequence(self.bands, "damping_bands", "a sequence of " + _BAND)
        bands = tuple(_check_band(b, k) for k, b in enumerate(bands))
        _check_no_overlap(bands)
        object.__setattr__(self, "bands", bands)
        if by_mode and bands:
            raise ModelError(
                "cannot be combined with ratios per mode (by_mode), which already cover every elastic mode",
                field="damping_bands",
                valid="either by_mode or bands",
            )
        if self.rayleigh is not None:
            object.__setattr__(self, "rayleigh", _check_rayleigh(self.rayleigh))
            if by_mode or bands:
                raise ModelError(
                    "cannot be combined with ratios per mode (by_mode) or per band (bands)",
                    field="rayleigh",
                    valid="rayleigh alone, or by_mode / bands without rayleigh",
                )

    def ratios(self, free_hz, rigid) -> np.ndarray:
        """The damping ratio of each free-free mode.

        Parameters
        ----------
        free_hz : array_like, shape (n,)
            Frequencies of the modes, Hz (``FlexibleBody.free_hz``).
        rigid : array_like of bool, shape (n,)
            Which modes are rigid-body modes; they get 0.

        Returns
        -------
        ndarray, shape (n,)
            Ratios (fractions); elastic modes ranked by frequency for ``by_mode``.
        """
        f = np.asarray(free_hz, dtype=float)
        rigid = np.asarray(rigid, dtype=bool)
        if f.ndim != 1 or rigid.shape != f.shape:
            raise ModelError(
                f"has shape {rigid.shape} for {f.shape} frequencies",
                field="rigid",
                valid="one flag per frequency",
            )
        out = np.zeros(f.shape)
        elastic = ~rigid
        if self.rayleigh is not None:
            out[elastic] = rayleigh_ratio(*self.rayleigh, f[elastic])
        elif self.by_mode:
            # Rank the elastic modes by frequency; past the list the last ratio carries on.
            idx = np.flatnonzero(elastic)[np.argsort(f[elastic], kind="stable")]
            table = np.asarray(self.by_mode)
            out[idx] = table[np.minimum(np.arange(idx.size), table.size - 1)]
        else:
            out[elastic] = self.ratio
            for lo, hi, z in self.bands:
                out[elastic & (f >= lo) & (f < hi)] = z
        return out


def _check_no_overlap(bands: tuple[tuple[float, float, float], ...]) -> None:
    """Refuse bands that share frequencies (touching, f_hi == next f_lo, is fine)."""
    order = sorted(range(len(bands)), key=lambda k: bands[k][0])
    for a, b in zip(order, order[1:], strict=False):
        if bands[b][0] < bands[a][1]:
            raise ModelError(
                f"overlaps damping_bands[{a}] = {bands[a]}",
                field=f"damping_bands[{b}]",
                value=bands[b],
                unit="(Hz, Hz, -)",
                valid="bands that do not overlap (they may touch: f_hi_hz of one = f_lo_hz of the next)",
            )


def _check_rayleigh(value: object) -> tuple[float, float]:
    """(alpha 1/s, beta s), both finite, >= 0 and at most RAYLEIGH_ALPHA_MAX / RAYLEIGH_BETA_MAX."""
    valid = f"(alpha 1/s, beta s), 0 <= alpha <= {RAYLEIGH_ALPHA_MAX:g}, 0 <= beta <= {RAYLEIGH_BETA_MAX:g}"
    items = _as_sequence(value, "rayleigh", valid)
    if len(items) != 2:
        raise ModelError("must be two numbers", field="rayleigh", value=value, valid=valid, has_value=True)
    return check_rayleigh(items[0], items[1])

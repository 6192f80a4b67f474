"""Signal analysis for simulated and measured drivetrain signals (flange torque, speed).

The same analysis for both: amplitude-correct spectra with Welch averaging
(:func:`spectrum`), peaks with their half-power damping (:func:`find_peaks`), the damping of a
free decay in time (:func:`log_decrement`) and in frequency (:func:`decay_damping`), and
spectrograms of run-ups with order lines (:func:`spectrogram`, :func:`order_lines`,
:func:`ridge`), and the modes of one or more measured runs by covariance-driven stochastic subspace
identification with their spread (:func:`identify_modes`). SI throughout: seconds, hertz, the
signal's own unit; speeds for order lines in rpm. Only numpy and scipy.

Names load lazily (PEP 562): a reader of signal files that needs only :mod:`.checks` (the time
base, a signal's samples) imports neither scipy.signal nor the identification (0.8 s together).
"""

from __future__ import annotations

import importlib
import sys
import types

# public name -> the submodule that defines it
_EXPORTS = {
    "Identification": "identified",
    "IdentifiedMode": "identified",
    "RunSummary": "identified",
    "Stabilisation": "identified",
    "Run": "identify",
    "identify_modes": "identify",
    "Decay": "peaks",
    "DecayPeak": "peaks",
    "Peak": "peaks",
    "decay_damping": "peaks",
    "find_peaks": "peaks",
    "half_power_damping": "peaks",
    "log_decrement": "peaks",
    "Spectrogram": "spectrogram",
    "order_lines": "spectrogram",
    "ridge": "spectrogram",
    "spectrogram": "spectrogram",
    "WINDOWS": "spectrum",
    "Spectrum": "spectrum",
    "spectrum": "spectrum",
    "window": "spectrum",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """This package, whose names ``spectrum`` and ``spectrogram`` stay the functions: importing a
    submodule sets the package's attribute of its name to the module, which would hide the function
    of that name (the eager imports this replaced set the function after the module)."""

    def __setattr__(self, name, value):
        if isinstance(value, types.ModuleType) and name in _EXPORTS:
            return  # the submodule stays reachable as sys.modules[f"{__name__}.{name}"]
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package

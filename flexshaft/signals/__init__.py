"""Signal analysis for simulated and measured drivetrain signals (flange torque, speed).

The same analysis for both: amplitude-correct spectra with Welch averaging
(:func:`spectrum`), peaks with their half-power damping (:func:`find_peaks`), the damping of a
free decay in time (:func:`log_decrement`) and in frequency (:func:`decay_damping`), and
spectrograms of run-ups with order lines (:func:`spectrogram`, :func:`order_lines`,
:func:`ridge`), and the modes of one or more measured runs by covariance-driven stochastic subspace
identification with their spread (:func:`identify_modes`). SI throughout: seconds, hertz, the
signal's own unit; speeds for order lines in rpm. Only numpy and scipy.
"""

from .identified import Identification, IdentifiedMode, RunSummary, Stabilisation
from .identify import Run, identify_modes
from .peaks import Decay, DecayPeak, Peak, decay_damping, find_peaks, half_power_damping, log_decrement
from .spectrogram import Spectrogram, order_lines, ridge, spectrogram
from .spectrum import WINDOWS, Spectrum, spectrum, window

__all__ = [
    "WINDOWS",
    "Decay",
    "DecayPeak",
    "Identification",
    "IdentifiedMode",
    "Peak",
    "Run",
    "RunSummary",
    "Stabilisation",
    "Spectrogram",
    "Spectrum",
    "decay_damping",
    "find_peaks",
    "half_power_damping",
    "identify_modes",
    "log_decrement",
    "order_lines",
    "ridge",
    "spectrogram",
    "spectrum",
    "window",
]

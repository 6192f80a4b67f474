"""Signal analysis for simulated and measured drivetrain signals (flange torque, speed).

The same analysis for both: amplitude-correct spectra with Welch averaging
(:func:`spectrum`), peaks with their half-power damping (:func:`find_peaks`), the damping of a
free decay in time (:func:`log_decrement`) and in frequency (:func:`decay_damping`), and
spectrograms of run-ups with order lines (:func:`spectrogram`, :func:`order_lines`,
:func:`ridge`). SI throughout: seconds, hertz, the signal's own unit; speeds for order lines in rpm.
Only numpy and scipy.
"""

from .peaks import Decay, DecayPeak, Peak, decay_damping, find_peaks, half_power_damping, log_decrement
from .spectrogram import Spectrogram, order_lines, ridge, spectrogram
from .spectrum import WINDOWS, Spectrum, spectrum, window

__all__ = [
    "WINDOWS",
    "Decay",
    "DecayPeak",
    "Peak",
    "Spectrogram",
    "Spectrum",
    "decay_damping",
    "find_peaks",
    "half_power_damping",
    "log_decrement",
    "order_lines",
    "ridge",
    "spectrogram",
    "spectrum",
    "window",
]

"""Signal analysis for simulated and measured drivetrain signals (flange torque, speed).

The same analysis for both: amplitude-correct spectra with Welch averaging (:mod:`.spectrum`), peaks
with their half-power damping and the damping of a free decay in time and in frequency
(:mod:`.peaks`), spectrograms of run-ups with order lines and ridges (:mod:`.spectrogram`), and the
modes of one or more measured runs by covariance-driven stochastic subspace identification with
their spread (:mod:`.identify`, :mod:`.identified`); readers of recordings (:mod:`.signalfile`,
:mod:`.files`) and the pairing of identified modes with a model's (:mod:`.pairing`). SI throughout:
seconds, hertz, the signal's own unit; speeds for order lines in rpm. Only numpy and scipy.

Import each name from the module that defines it (the public ones also as ``flexshaft.Name``): the
package loads nothing, so a reader of signal files that needs only :mod:`.checks` (the time base, a
signal's samples) imports neither scipy.signal nor the identification (0.8 s together).
"""

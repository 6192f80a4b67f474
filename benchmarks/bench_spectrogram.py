"""Spectrogram benchmark: a 10-minute test-bench record at 1.6 kHz (960 000 samples).

What it measures
----------------
The signal: a chirp sweeping 5 -> 300 Hz (an order line on a run-up), tones at 73 and 211 Hz
(eigenfrequencies) and white noise, fixed seed. Timed in one run, best of 3, on the same data and
segment (1 s, Hann, 50 % overlap, mean removed per segment):

- ``flexshaft.measurement.spectrogram`` (strided view, FFT a block of segments at a time, amplitude
  scaling), and the peak memory it allocates (tracemalloc, in a separate untimed call);
- ``scipy.signal.spectrogram(..., scaling="spectrum", mode="psd")``, the peer, and its peak memory;
- the largest difference between the two after converting scipy's power to single-sided amplitude
  (``√(2·P)`` inside, ``√P`` at DC and Nyquist), relative to the largest amplitude.

Target: the 10-minute record in well under a second, no slower than scipy, memory bounded by the
result plus one block. Run: ``.venv/bin/python benchmarks/bench_spectrogram.py``. Timings are
printed, never asserted.
"""

from __future__ import annotations

import os
import tracemalloc

import numpy as np
import scipy.signal
from timing import best

from flexshaft.measurement.spectrogram import spectrogram

RATE = 1600.0
MINUTES = 10
SEGMENT = 1.0


def peak_memory(fn) -> float:
    """Peak bytes allocated while ``fn`` runs (numpy reports its buffers to tracemalloc)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def signal() -> np.ndarray:
    n = int(MINUTES * 60 * RATE)
    t = np.arange(n) / RATE
    duration = n / RATE
    chirp = 2.0 * np.sin(2 * np.pi * (5.0 * t + (300.0 - 5.0) / (2 * duration) * t**2))
    tones = 0.5 * np.sin(2 * np.pi * 73.0 * t) + 0.2 * np.sin(2 * np.pi * 211.0 * t + 1.0)
    return 480.0 + chirp + tones + np.random.default_rng(20261122).normal(0.0, 0.3, n)


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    x = signal()
    nper = int(SEGMENT * RATE)
    print(f"record: {x.size} samples ({x.size / RATE / 60:g} min at {RATE:g} Hz), segment {nper} samples")

    def ours():
        return spectrogram(x, RATE, segment=SEGMENT, overlap=0.5, window="hann")

    def theirs():
        return scipy.signal.spectrogram(
            x,
            RATE,
            window="hann",
            nperseg=nper,
            noverlap=nper // 2,
            detrend="constant",
            scaling="spectrum",
            mode="psd",
        )

    t_ours, s = best(ours)
    t_scipy, (f, times, power) = best(theirs)
    amp = np.sqrt(2.0 * power)
    amp[0] = np.sqrt(power[0])
    if nper % 2 == 0:
        amp[-1] = np.sqrt(power[-1])
    same_grid = np.array_equal(f, s.frequencies_hz) and np.allclose(times, s.times_s, rtol=1e-15, atol=0)
    err = np.max(np.abs(s.amplitude - amp)) / amp.max()
    m_ours, m_scipy = peak_memory(ours), peak_memory(theirs)
    print(
        f"result: {s.amplitude.shape[0]} frequencies x {s.amplitude.shape[1]} segments"
        f" ({s.amplitude.nbytes / 1e6:.1f} MB)"
    )
    print(f"flexshaft spectrogram: {t_ours:.3f} s   peak memory {m_ours / 1e6:.1f} MB")
    print(f"scipy.signal.spectrogram: {t_scipy:.3f} s   peak memory {m_scipy / 1e6:.1f} MB")
    print(f"ratio flexshaft/scipy: time {t_ours / t_scipy:.2f}, memory {m_ours / m_scipy:.2f}")
    print(f"same frequencies and times: {same_grid}; amplitudes agree to {err:.1e} (relative to the largest)")


if __name__ == "__main__":
    main()

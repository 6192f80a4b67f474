"""Results are numbers: a speed loop unstable at its rate, drive torques whose response leaves floating
point, inputs above the Nyquist frequency, runs of a sample or two, the time column taken for a signal
and order lists that are not positive numbers are each refused in one line; valid runs give finite
results and nothing on stderr.

The simulations are short (0.05-0.5 s of Customer 1 at 1 kHz: a second each) and the signal files
are written with numpy, or with flexshaft's own simulate in Python, in the case's setup.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.conftest import EXAMPLES
from tests.flexshaft.catalogue import Case

C1 = str(EXAMPLES / "customer1.toml")
SIM = ["simulate", C1, "--measure", "speed:motor", "--measure", "torque:part 3"]
STEP = [*SIM, "--scenario", "step", "--torque", "100", "--duration", "0.2"]
RAMP = [*SIM, "--scenario", "ramp", "--end-speed", "100", "--ramp-time", "0.2", "--duration", "0.3"]


def _history(d: Path, torque, rate: float = 1000.0, name: str = "h.csv") -> str:
    """A drive-torque history of 0.5 s at ``rate``: ``torque(t)`` in N·m."""
    t = np.arange(int(0.5 * rate) + 1) / rate
    rows = "\n".join(f"{a!r},{b!r}" for a, b in zip(t.tolist(), np.broadcast_to(torque(t), t.shape).tolist()))
    (d / name).write_text("time [s],drive [N·m]\n" + rows + "\n")
    return name


def _csv(d: Path, torque, rate: float = 1000.0) -> list[str]:
    return [*SIM, "--scenario", "csv", "--series", _history(d, torque, rate), "--column", "drive"]


def _signals(d: Path) -> str:
    """A 2 s record at 1 kHz: a 50 Hz torque and a slowly rising speed."""
    t = np.arange(2000) / 1000.0
    rows = "\n".join(
        f"{a!r},{b!r},{c!r}"
        for a, b, c in zip(t.tolist(), np.sin(2 * np.pi * 50 * t).tolist(), (100.0 + 10.0 * t).tolist())
    )
    (d / "s.csv").write_text("time [s],torque [N·m],speed [rpm]\n" + rows + "\n")
    return "s.csv"


def _huge(d: Path, torque: float, speed: float) -> str:
    """A 2 s record whose torque alternates ±``torque`` N·m and whose speed is ``speed`` rad/s."""
    rows = "\n".join(f"{k / 1000.0!r},{torque * (-1) ** k!r},{speed!r}" for k in range(2000))
    (d / "big.csv").write_text("time [s],torque [N·m],speed [rad/s]\n" + rows + "\n")
    return "big.csv"


def _decay(d: Path) -> str:
    """The found case: Customer 1's coast stop simulated for 1 s (in Python, nothing on stdout) - too
    short a record for the half-power points of most peaks, and for the window's damping of mode 1."""
    import flexshaft as fs
    from flexshaft.analysis.simulate import Scenario, simulate

    result = fs.modal_analysis(fs.load_model(C1))
    run = simulate(result, Scenario.coast(1000.0), ["torque:part 1"], duration=1.0)
    fs.write_signals(d / "decay.csv", run.time, {"torque:part 1": (run.outputs["torque:part 1"], "N·m")})
    return "decay.csv"


def _orders(command: str, text: str) -> Case:
    def setup(d: Path) -> list[str]:
        head = ["campbell", C1] if command == "campbell" else ["spectrum", _signals(d), "--column", "torque"]
        return [*head, f"--orders={text}"]

    return Case(setup, says=("--orders", "valid"))


CASES = {
    # an unstable speed loop: the found case (bandwidth 1e6 Hz: kp 4e8, ki 5e14) and gains given
    "simulate ramp --bandwidth 1e6 -o run.csv": Case(
        lambda d: [*RAMP, "--bandwidth", "1e6", "-o", "run.csv"],
        says=("--bandwidth", "unstable", "valid", "Hz"),
    ),
    "simulate ramp --kp 1e6 (unstable without ki)": Case(
        lambda d: [*RAMP, "--kp", "1e6", "--ki", "1"], says=("--kp", "unstable", "valid")
    ),
    "simulate ramp --ki 1e9 (unstable with this kp)": Case(
        lambda d: [*RAMP, "--kp", "100", "--ki", "1e9"], says=("--ki", "unstable", "valid")
    ),
    "simulate ramp --kp 1e308 --ki 1e308": Case(
        lambda d: [*RAMP, "--kp", "1e308", "--ki", "1e308"], says=("--kp", "valid")
    ),
    # amplitudes whose response leaves floating point
    "simulate step --torque 1e308": Case(lambda d: [*STEP, "--torque", "1e308"], says=("--torque", "valid")),
    "simulate step --torque nan": Case(lambda d: [*STEP, "--torque", "nan"], says=("--torque", "valid")),
    "simulate step --load-torque -1e308": Case(
        lambda d: [*STEP, "--load-torque=-1e308"], says=("--load-torque", "valid")
    ),
    "simulate coast --speed 1e300": Case(
        lambda d: [*SIM, "--scenario", "coast", "--torque", "1", "--speed", "1e300", "--duration", "0.2"],
        says=("--speed", "valid"),
    ),
    "simulate csv: a torque of 1e308 in the history": Case(
        lambda d: _csv(d, lambda t: np.where(t > 0.1, 1e308, 0.0)), says=("--series", "1e+308", "valid")
    ),
    "simulate csv --column time": Case(
        lambda d: [*_csv(d, lambda t: 0 * t)[:-1], "time"], says=("--column", "time column", "valid")
    ),
    # inputs above the Nyquist frequency of the rate
    "simulate sine --frequency 5000 at --rate 1000": Case(
        lambda d: [*SIM, "--scenario", "sine", "--frequency", "5000", "--torque", "1", "--rate", "1000"],
        says=("--frequency", "Nyquist", "valid", "500 Hz"),
    ),
    "simulate sine --frequency 500 (on Nyquist: all samples zero)": Case(
        lambda d: [*SIM, "--scenario", "sine", "--frequency", "500", "--torque", "1", "--duration", "0.2"],
        says=("--frequency", "Nyquist"),
    ),
    "simulate csv: a 10 kHz history at --rate 1000": Case(
        lambda d: _csv(d, lambda t: np.sin(2 * np.pi * 3000 * t), rate=10_000.0),
        says=("--series", "valid", "10000"),
    ),
    # runs of a sample or two
    "simulate --duration 1e-9 (one sample)": Case(
        lambda d: [*STEP[:-2], "--duration", "1e-9"], says=("--duration", "samples", "valid")
    ),
    "simulate --rate 0.001 (one sample in 10 s)": Case(
        lambda d: [*STEP[:-2], "--rate", "0.001"], says=("--rate", "samples", "valid")
    ),
    "simulate --duration 1e305 --rate 1e6": Case(
        lambda d: [*STEP[:-2], "--duration", "1e305", "--rate", "1e6"], says=("--duration", "valid")
    ),
    # the time column is not a signal
    "spectrum --column time": Case(
        lambda d: ["spectrum", _signals(d), "--column", "time"], says=("--column", "time")
    ),
    "spectrum --column 'time [s]'": Case(
        lambda d: ["spectrum", _signals(d), "--column", "time [s]"], says=("--column", "time column")
    ),
    "spectrum --speed-column time": Case(
        lambda d: ["spectrum", _signals(d), "--column", "torque", "--speed-column", "time"],
        says=("--speed-column", "time column"),
    ),
    "spectrum --speed-column = --column": Case(
        lambda d: ["spectrum", _signals(d), "--column", "torque", "--speed-column", "torque [N·m]"],
        says=("--speed-column", "valid"),
    ),
    # signals whose spectrum's sums, or order lines, would leave floating point
    "spectrum: a torque of ±1e150 N·m": Case(
        lambda d: ["spectrum", _huge(d, 1e150, 10.0), "--column", "torque"],
        says=("--column", "1e+100", "valid"),
    ),
    "spectrum: a speed column of 1e308 rad/s": Case(
        lambda d: ["spectrum", _huge(d, 1.0, 1e308), "--column", "torque", "--speed-column", "speed"],
        says=("--speed-column", "valid"),
    ),
    "campbell --speed 0:1e308 (order lines beyond 1e9 Hz)": Case(
        lambda d: ["campbell", C1, "--speed", "0:1e308", "--plot", "c.png"],
        says=("--speed", "valid"),
    ),
    # order lists are positive finite numbers
    **{
        f"{c} --orders={o!r}": _orders(c, o) for c in ("campbell", "spectrum") for o in ("nan", "-1", "0", "")
    },
    "campbell --orders 1,,2": _orders("campbell", "1,,2"),
    "campbell --orders 1e308": _orders("campbell", "1e308"),
    "spectrum --orders inf": _orders("spectrum", "inf"),
    # nearby: a forced response beyond floating point
    "forced --torque 1e308": Case(
        lambda d: ["forced", C1, "--at", "motor", "--torque", "1e308"], says=("--torque", "valid")
    ),
    # valid inputs: finite results, nothing on stderr
    "simulate step -o run.csv (valid)": Case(lambda d: [*STEP, "-o", "run.csv"], exit=0),
    "simulate ramp, tuned gains (valid)": Case(lambda d: RAMP, exit=0),
    "simulate ramp --bandwidth 50 (valid)": Case(lambda d: [*RAMP, "--bandwidth", "50"], exit=0),
    "simulate sine --frequency 100 (valid)": Case(
        lambda d: [*SIM, "--scenario", "sine", "--frequency", "100", "--torque", "1", "--duration", "0.2"],
        exit=0,
    ),
    "simulate step --torque 1e12 (the ceiling, valid)": Case(lambda d: [*STEP, "--torque", "1e12"], exit=0),
    "simulate csv at the history's rate (valid)": Case(
        lambda d: _csv(d, lambda t: 100.0 * np.sin(2 * np.pi * 20 * t)), exit=0
    ),
    "simulate --duration 0.007 (8 samples, valid)": Case(
        lambda d: [*STEP[:-2], "--duration", "0.007"], exit=0
    ),
    "spectrum --decay on a simulated 1 s decay (valid, no NaN row)": Case(
        lambda d: ["spectrum", _decay(d), "--column", "torque:part 1", "--decay"], exit=0
    ),
    "spectrum --decay --json on a simulated 1 s decay (valid)": Case(
        lambda d: ["spectrum", _decay(d), "--column", "torque:part 1", "--decay", "--json"], exit=0
    ),
    "spectrum --speed-column --orders 0.5,6 --plot (valid)": Case(
        lambda d: [
            "spectrum",
            _signals(d),
            "--column",
            "torque",
            "--speed-column",
            "speed",
            "--orders",
            "0.5,6",
            "--plot",
            "sg.png",
        ],
        exit=0,
    ),
    "campbell --orders 0.5,1,6 (valid)": Case(lambda d: ["campbell", C1, "--orders", "0.5,1,6"], exit=0),
    # stations named by their options (both were "input" from the state space)
    "simulate --at nowhere": Case(
        lambda d: [*SIM, "--scenario", "step", "--duration", "0.1", "--at", "nowhere"],
        says=("--at = 'nowhere'", "no such station", "valid: motor"),
    ),
    "simulate --load-at nowhere": Case(
        lambda d: [*SIM, "--scenario", "step", "--duration", "0.1", "--load-at", "nowhere"],
        says=("--load-at = 'nowhere'", "no such station", "valid: motor"),
    ),
}

"""The runs :func:`~flexshaft.measurement.identify.identify_modes` takes, checked: their channels, units,
the model orders and the reference channels, each refused with the argument named."""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..validation import check_int, check_name
from .checks import as_signal, uniform_rate

__all__ = ["Run", "as_runs", "model_orders", "reference_rows", "run_channels", "run_rates", "run_units"]

#: The highest model order by default (orders 2, 4, ..., this): room for the modes below the Nyquist
#: frequency, the drift's filter and the noise, several times over.
DEFAULT_MAX_ORDER = 60
#: The highest model order accepted: a stabilisation diagram of up to 200 modes, far more than a
#: drivetrain's band holds; the Toeplitz matrix's SVD grows with its cube.
MAX_ORDER = 400


@dataclass(frozen=True)
class Run:
    """One measured run: samples of the channels on a uniform time base.

    A :class:`flexshaft.measurement.signalfile.SignalTable` has the same fields and is accepted as it is.

    Attributes
    ----------
    time : ndarray, shape (n,)
        Sample times, s (increasing, uniformly spaced).
    columns : dict of str to ndarray
        Each channel's samples, in its SI unit.
    units : dict of str to str
        Each channel's SI unit (``N·m``, ``rad/s``, ``rad``).
    source : str
        Where it came from (a file), for the record.
    """

    time: np.ndarray
    columns: dict
    units: dict
    source: str = ""


# --- inputs ----------------------------------------------------------------------------------------


def as_run(item, k: int) -> Run:
    """One run from a Run, a SignalTable (or anything with time, columns, units) or a tuple."""
    where = f"runs[{k}]"
    valid = "a Run, a SignalTable or a tuple (time s, {name: samples}, {name: unit})"
    if all(hasattr(item, a) for a in ("time", "columns", "units")):
        time, columns, units = item.time, item.columns, item.units
        source = str(getattr(item, "source", "") or "")
    elif isinstance(item, tuple | list) and len(item) == 3:
        time, columns, units = item
        source = ""
    else:
        raise ModelError("is not a run", field=where, valid=valid, has_value=False)
    if not isinstance(columns, dict) or not columns:
        raise ModelError(
            "has no channels", field=f"{where}.columns", valid="a non-empty dict name -> samples"
        )
    if not isinstance(units, dict):
        raise ModelError("is not a dict", field=f"{where}.units", valid="a dict name -> SI unit")
    return Run(time=time, columns=columns, units=units, source=source)


def as_runs(runs) -> list[Run]:
    if all(hasattr(runs, a) for a in ("time", "columns", "units")):
        runs = [runs]  # one run given alone
    if isinstance(runs, str | bytes | dict) or not hasattr(runs, "__len__"):
        raise ModelError(
            "is not a sequence of runs",
            field="runs",
            valid="a list of Run, SignalTable or (time, columns, units) tuples",
            has_value=False,
        )
    if len(runs) == 0:
        raise ModelError("is empty", field="runs", valid="at least one run", has_value=False)
    return [as_run(r, k) for k, r in enumerate(runs)]


def run_rates(runs) -> list[float]:
    """Each run's sampling rate, Hz (the runs as :func:`identify_modes` takes them; their time bases
    checked as it checks them)."""
    rates = []
    for k, run in enumerate(as_runs(runs)):
        time = as_signal(run.time, f"runs[{k}].time", "s", min_samples=2)
        rates.append(uniform_rate(time, f"runs[{k}].time"))
    return rates


def run_channels(runs: list[Run], channels) -> tuple[str, ...]:
    first = list(runs[0].columns)
    if channels is None:
        names = tuple(first)
        for k, run in enumerate(runs[1:], start=1):
            if set(run.columns) != set(names):
                raise ModelError(
                    "has other channels than runs[0]",
                    field=f"runs[{k}].columns",
                    value=sorted(run.columns),
                    valid=f"the same channels in every run: {sorted(names)} (or name them: channels=)",
                )
        return names
    if isinstance(channels, str):
        channels = [channels]
    try:
        names = tuple(check_name(c, "channels") for c in channels)
    except TypeError:
        raise ModelError(
            "is not a list of names", field="channels", value=channels, valid="channel names"
        ) from None
    if not names:
        raise ModelError("is empty", field="channels", valid="at least one channel name", has_value=False)
    if len(set(names)) != len(names):
        raise ModelError("names a channel twice", field="channels", value=list(names), valid="distinct names")
    for k, run in enumerate(runs):
        for name in names:
            if name not in run.columns:
                raise ModelError(
                    "no such channel",
                    field="channels",
                    value=name,
                    valid=f"channels of every run; runs[{k}] has {sorted(run.columns)}",
                )
    return names


def run_units(runs: list[Run], names: tuple[str, ...]) -> dict:
    units = {}
    for name in names:
        unit = runs[0].units.get(name)
        if not isinstance(unit, str):
            raise ModelError(
                "has no unit", field=f"runs[0].units[{name!r}]", valid="the channel's SI unit, e.g. 'N·m'"
            )
        for k, run in enumerate(runs[1:], start=1):
            if run.units.get(name) != unit:
                raise ModelError(
                    f"differs from runs[0]'s {unit!r}",
                    field=f"runs[{k}].units[{name!r}]",
                    value=run.units.get(name),
                    valid="the same unit for a channel in every run",
                )
        units[name] = unit
    return units


def model_orders(orders) -> tuple[int, ...]:
    valid = "a highest model order (even, >= 4), or a list of even orders >= 2, at least two"
    if orders is None:
        return tuple(range(2, DEFAULT_MAX_ORDER + 1, 2))
    if isinstance(orders, numbers.Integral) and not isinstance(orders, bool):
        top = check_int(orders, "orders", lo=4, hi=MAX_ORDER)
        if top % 2:
            raise ModelError("is odd", field="orders", value=top, valid=valid)
        return tuple(range(2, top + 1, 2))
    try:
        out = sorted({check_int(n, "orders", lo=2, hi=MAX_ORDER) for n in orders})
    except TypeError:
        raise ModelError("is not a list of orders", field="orders", value=orders, valid=valid) from None
    if len(out) < 2 or any(n % 2 for n in out):
        raise ModelError("unusable orders", field="orders", value=list(orders), valid=valid)
    return tuple(out)


def reference_rows(references, names: tuple[str, ...]) -> np.ndarray:
    if references is None:
        return np.arange(len(names))
    if isinstance(references, str):
        references = [references]
    try:
        given = list(references)
    except TypeError:
        raise ModelError(
            "is not a list of channels", field="references", value=references, valid=f"some of {list(names)}"
        ) from None
    for r in given:
        if r not in names:
            raise ModelError(
                "is not one of the channels", field="references", value=r, valid=f"one of {list(names)}"
            )
    if not given or len(set(given)) != len(given):
        raise ModelError(
            "unusable references", field="references", value=given, valid="one or more distinct channels"
        )
    return np.array([names.index(r) for r in given])

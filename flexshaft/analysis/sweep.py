"""Parameter studies that scale out: a grid or a Latin hypercube of models, run on an executor.

Every point is a model with some parameters set (:func:`flexshaft.analysis.parameters.with_parameters`);
its frequencies and damping ratios come back in order. The executor is anything with the
``concurrent.futures.Executor`` interface: local processes by default, or a Dask cluster's
(``distributed.Client(address).get_executor()``, what ``--scheduler ADDRESS`` uses) - the same
code and the same numbers either way, to round-off (each point is one eigen-solve; on another
machine's BLAS kernels its last digits may differ).
"""

from __future__ import annotations

import math
import os
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import ModelError
from ..model.assembly import assemble
from ..model.components import Drivetrain
from ..system.limits import check_ceiling
from ..system.threads import follows_policy
from ..validation import check_int
from .modal import modal_analysis
from .parameters import find_parameter, parameter_domain, with_parameters
from .sensitivity import lowest_elastic

__all__ = [
    "SweepResult",
    "grid_points",
    "lhs_points",
    "parse_range",
    "check_values",
    "sweep",
    "run_points",
    "dask_executor",
]

#: Elastic modes per point without ``modes``: this many, or all the model has if fewer.
DEFAULT_MODES = 6

#: Points sent to a worker at a time: enough to amortise the transfer, few enough for a smooth bar.
CHUNK = 25


@dataclass(frozen=True)
class SweepResult:
    """Every point's parameter values and its modes.

    Attributes
    ----------
    names : tuple of str
        The parameters varied.
    units : tuple of str
    values : ndarray, shape (n, p)
        Each point's parameter values, SI.
    frequencies_hz : ndarray, shape (n, m)
        The lowest ``m`` elastic modes' frequencies, Hz (NaN where the point failed).
    damping_ratios : ndarray, shape (n, m)
    errors : tuple of str
        Per point, "" or why the model was refused (an out-of-range value, say).
    """

    names: tuple
    units: tuple
    values: np.ndarray
    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    errors: tuple

    def to_csv(self) -> str:
        """CSV text: one row per point, parameters then ``f1 [Hz]`` … and ``zeta1 [-]`` …"""
        m = self.frequencies_hz.shape[1]
        head = [f"{n} [{u or '-'}]" for n, u in zip(self.names, self.units)]
        head += [f"f{k + 1} [Hz]" for k in range(m)] + [f"zeta{k + 1} [-]" for k in range(m)] + ["error"]
        rows = [",".join(_csv_cell(h) for h in head)]
        for i in range(self.values.shape[0]):
            cells = [f"{v:.17g}" for v in self.values[i]]
            cells += [f"{v:.17g}" for v in self.frequencies_hz[i]] + [
                f"{v:.17g}" for v in self.damping_ratios[i]
            ]
            rows.append(",".join(cells + [_csv_cell(self.errors[i])]))
        return "\n".join(rows) + "\n"

    def to_dict(self) -> dict:
        """The ``flexshaft sweep --json`` document: frequencies (Hz) and damping ratios per point, None
        where a point was refused."""
        return {
            "parameters": [{"name": n, "unit": u} for n, u in zip(self.names, self.units)],
            "points": self.values.tolist(),
            "frequencies_hz": [
                [None if np.isnan(v) else float(v) for v in row] for row in self.frequencies_hz
            ],
            "damping_ratios": [
                [None if np.isnan(v) else float(v) for v in row] for row in self.damping_ratios
            ],
            "errors": list(self.errors),
        }

    def summary(self, *, lhs: bool = False, scheduler: str | None = None) -> str:
        """The first line of a sweep's summary: how many models, over what, how many refused, where."""
        failed = sum(1 for e in self.errors if e)
        return (
            f"{len(self.errors)} models ({'Latin hypercube' if lhs else 'grid'} over "
            + ", ".join(self.names)
            + f"), {failed} refused"
            + (f" on {scheduler}" if scheduler else "")
        )

    def table(self) -> str:
        """Each mode's lowest and highest frequency over a sweep's points, Hz."""
        lines = [f"{'mode':>4}  {'min Hz':>12}  {'max Hz':>12}"]
        for k in range(self.frequencies_hz.shape[1]):
            col = self.frequencies_hz[:, k]
            if np.all(np.isnan(col)):
                continue
            lines.append(f"{k + 1:>4}  {np.nanmin(col):12.5g}  {np.nanmax(col):12.5g}")
        return "\n".join(lines)

    def plot(self):
        """Each mode's frequency against the first parameter, a matplotlib Figure (never shown)."""
        from ..views.plots import sweep_figure

        return sweep_figure(self)


def _csv_cell(text: str) -> str:
    return '"' + text.replace('"', '""') + '"' if any(c in text for c in ',"\n') else text


def parse_range(spec: str) -> tuple[str, np.ndarray]:
    """``"part 3.stiffness=40000:70000:31"`` -> the name and 31 values from 40000 to 70000; a value
    list ``"name=1,2,5"`` works too."""
    name, sep, rng = str(spec).rpartition("=")
    if not sep or not name:
        raise ModelError(
            "not NAME=LO:HI:N or NAME=V1,V2,...",
            field="--param",
            value=spec,
            valid="e.g. 'part 3.stiffness=40000:70000:31' or 'generator.inertia=5,6.67,8'",
        )
    try:
        if ":" in rng:
            lo, hi, n = rng.split(":")
            n = int(n)
            lo, hi = float(lo), float(hi)
            if n < 1 or not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError
            check_ceiling("sweep_values", n, field="--param", value=spec, detail=f"{n} values")
            if lo > hi:
                raise ModelError(
                    "LO is above HI", field="--param", value=spec, valid="NAME=LO:HI:N with LO <= HI"
                )
            values = np.linspace(lo, hi, n)
        else:
            items = rng.split(",")
            n = len(items)
            check_ceiling("sweep_values", n, field="--param", value=spec, detail=f"{n} values")
            values = np.array([float(v) for v in items])
            if not np.all(np.isfinite(values)):
                raise ValueError
    except ModelError:
        raise
    except ValueError:
        raise ModelError(
            "not LO:HI:N (N >= 1) or V1,V2,...",
            field="--param",
            value=spec,
            valid="finite numbers: NAME=LO:HI:N with LO <= HI, or NAME=V1,V2,...",
        ) from None
    return name.strip(), values


def check_values(d: Drivetrain, name: str, values, field: str | None = None, spec: str | None = None) -> None:
    """Refuse a value the parameter cannot take (:func:`~flexshaft.analysis.parameters.parameter_domain`):
    a negative stiffness, a damping ratio of 1, a non-finite number - before any point is solved.

    Parameters
    ----------
    d : Drivetrain
    name : str
        The parameter (an unknown name is an error listing the valid ones).
    values : array_like
        Its values, SI.
    field, spec : str, optional
        The option and the text given for it (``"--param"``, ``"part 3.stiffness=-1:7e4:3"``), for
        the message; default the parameter's own name and the value.
    """
    domain = parameter_domain(d, name)
    v = np.asarray(values, dtype=float).ravel()
    bad = [float(x) for x in v if not domain.contains(x)]
    if bad:
        unit = f" {domain.unit}" if domain.unit else ""
        raise ModelError(
            f"{name} = {bad[0]:g}{unit} is not a value it can take",
            field=field or name,
            value=spec if spec is not None else bad[0],
            valid=f"{name} {domain.text}",
        )


def grid_points(ranges: dict) -> np.ndarray:
    """Every combination of the values (a full grid), shape (Π n_i, p); its size is checked against
    the ``sweep_points`` ceiling (:mod:`flexshaft.system.limits`) before it is built."""
    size = math.prod(len(v) for v in ranges.values())
    check_ceiling(
        "sweep_points",
        size,
        field="--param",
        value=" × ".join(str(len(v)) for v in ranges.values()),
        detail=f"a grid of {size} points",
        hint="fewer values, or --lhs N",
    )
    axes = np.meshgrid(*[np.asarray(v, dtype=float) for v in ranges.values()], indexing="ij")
    return np.column_stack([a.ravel() for a in axes])


def lhs_points(bounds: dict, n: int, seed: int = 0) -> np.ndarray:
    """``n`` Latin-hypercube points inside the (lo, hi) bounds, reproducible from ``seed``."""
    from scipy.stats import qmc

    n = check_ceiling("sweep_points", check_int(n, "samples", lo=1), field="samples")
    lo = np.array([b[0] for b in bounds.values()], dtype=float)
    hi = np.array([b[1] for b in bounds.values()], dtype=float)
    return lo + qmc.LatinHypercube(d=lo.size, seed=seed).random(n) * (hi - lo)


def run_points(d: Drivetrain, names, points: np.ndarray, count: int):
    """Solve the models at ``points`` (rows): frequencies, damping ratios and errors. Runs in a worker.

    Each point solves its rigid-body modes and the lowest ``count`` elastic ones (no more: a large
    model's solver default could be fewer, or far more)."""
    f = np.full((points.shape[0], count), np.nan)
    z = np.full((points.shape[0], count), np.nan)
    errors = []
    for i, row in enumerate(points):
        try:
            m = assemble(with_parameters(d, dict(zip(names, row))))
            r = modal_analysis(m, min(m.n_dof, m.rigid_basis.shape[1] + count))
            el = np.flatnonzero(~r.rigid)[:count]
            f[i, : el.size] = r.frequencies_hz[el]
            z[i, : el.size] = r.damping_ratios[el]
            errors.append("")
        except ModelError as err:
            errors.append(str(err))
    return f, z, errors


def _chunk(args):
    return run_points(*args)


def _probe(address: str) -> None:
    """Refuse a TCP address where nothing listens at once, before Dask's import and its 5 s of retries."""
    import socket
    from urllib.parse import urlsplit

    if "://" in address and not address.startswith("tcp://"):
        return  # tls://, ucx://, inproc://: Dask's own connection says
    try:
        parts = urlsplit(address if "://" in address else "tcp://" + address)
        host, port = parts.hostname, parts.port
    except ValueError:
        return  # Dask's parser words the error
    if not host or port is None:
        return
    try:
        socket.create_connection((host, port), timeout=5.0).close()
    except ConnectionRefusedError as err:
        raise _unreachable(address, err) from None
    except OSError:
        return  # unresolved, unreachable or slow: Dask tries with its own timeout and says


def dask_executor(address: str) -> Executor:
    """A ``concurrent.futures`` executor on the Dask cluster at ``address`` (``pip install
    'flexshaft[cluster]'``)."""
    _probe(address)
    try:
        from distributed import Client
    except ImportError:
        raise ModelError(
            "a Dask scheduler needs dask.distributed",
            field="--scheduler",
            valid="pip install 'flexshaft[cluster]'",
        ) from None
    try:
        client = Client(address, timeout="5s")  # a scheduler that answers does so in well under a second
    except (OSError, TimeoutError, ValueError) as err:
        raise _unreachable(address, err) from None
    return client.get_executor()


def _unreachable(address: str, err: Exception) -> ModelError:
    return ModelError(
        f"cannot reach the Dask scheduler ({type(err).__name__})",
        field="--scheduler",
        value=address,
        valid="a running scheduler, e.g. tcp://host:8786",
    )


@follows_policy
def sweep(
    drivetrain: Drivetrain,
    names,
    points,
    *,
    modes: int | None = None,
    executor: Executor | None = None,
    progress=None,
) -> SweepResult:
    """Frequencies and damping of the drivetrain at every point.

    Parameters
    ----------
    drivetrain : Drivetrain
    names : sequence of str
        The parameters (columns of ``points``).
    points : array_like, shape (n, p)
        Parameter values, SI (:func:`grid_points`, :func:`lhs_points`).
    modes : int, optional
        How many of the lowest elastic modes to keep (default :data:`DEFAULT_MODES`, or all the
        model has if fewer); more than the model has is refused.
    executor : concurrent.futures.Executor, optional
        Where to run; default a local process pool (as many workers as cores) for more than a
        few chunks of points, in-process otherwise.
    progress : callable, optional
        ``progress(done, total)`` in points.
    """
    names = list(names)
    for n in names:
        find_parameter(drivetrain, n)
    if len(set(names)) != len(names):
        raise ModelError("a parameter is listed twice", field="parameter", value=names, valid="each once")
    try:
        P = np.atleast_2d(np.asarray(points, dtype=float))
    except (TypeError, ValueError):
        raise ModelError(
            "not a table of numbers", field="points", valid=f"n × {len(names)} numbers"
        ) from None
    if P.ndim != 2 or P.shape[1] != len(names) or P.shape[0] == 0:
        raise ModelError(
            "points do not match the parameters",
            field="points",
            value=list(P.shape),
            valid=f"n × {len(names)}",
        )
    for k, n in enumerate(names):  # every value one the parameter can take, before any solve
        check_values(drivetrain, n, P[:, k])
    base = assemble(drivetrain)  # as each point is solved: a model's count of modes is its DOFs'
    if modes is None:
        modes = max(1, min(DEFAULT_MODES, base.n_dof - base.rigid_basis.shape[1]))
    modes = check_int(modes, "modes", lo=1, hi=10_000)
    modes = int(lowest_elastic(base, modes, "modes").size)
    chunks = [P[i : i + CHUNK] for i in range(0, P.shape[0], CHUNK)]
    own = None
    if executor is None and len(chunks) > 2 and (os.cpu_count() or 1) > 1:
        own = executor = ProcessPoolExecutor(max_workers=os.cpu_count())
    f = np.empty((P.shape[0], modes))
    z = np.empty((P.shape[0], modes))
    errors: list = []
    finished = False
    try:
        if executor is None:
            results = (run_points(drivetrain, names, c, modes) for c in chunks)
        else:
            results = executor.map(_chunk, [(drivetrain, names, c, modes) for c in chunks])
        done = 0
        for c, (fc, zc, ec) in zip(chunks, results):
            f[done : done + c.shape[0]], z[done : done + c.shape[0]] = fc, zc
            errors += ec
            done += c.shape[0]
            if progress is not None:
                progress(done, P.shape[0])
        finished = True
    finally:
        if own is not None:
            # Stopped midway (Ctrl-C, an error): drop the chunks not started and do not wait for the
            # running ones, so an interrupted sweep ends by itself, not only by the watchdog's kill.
            own.shutdown(wait=finished, cancel_futures=not finished)
    units = tuple(find_parameter(drivetrain, n).unit for n in names)
    return SweepResult(tuple(names), units, P, f, z, tuple(errors))

"""Ceilings: the largest count, range or size an option or a model file may ask for, and why.

Every size a user controls - frequencies of a response, frames of an animation, points of a study,
components of a chain, elements of a part, sides of a polygon, samples of a run - has a ceiling in
:data:`CEILINGS`, checked by :func:`check_ceiling` before the work starts: past it a command would
run for hours or fill the memory, so it is refused with one line naming the option or field, the
value, the ceiling and its reason. Work that grows with two sizes at once (a model's memory, a
Campbell diagram's tracking, a response with coupled damping) is estimated by the functions here
and checked the same way.

Each ceiling can be raised (or lowered) for one run by the environment variable its error names,
``FLEXSHAFT_MAX_<NAME>`` (:attr:`Ceiling.variable`), e.g. ``FLEXSHAFT_MAX_FRF_POINTS=200000``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from ..errors import ModelError

__all__ = [
    "Ceiling",
    "CEILINGS",
    "ceiling",
    "check_ceiling",
    "model_memory_bytes",
    "dense_memory_bytes",
    "check_memory",
    "dense_work",
    "DENSE_SOLVE_ORDER",
]

#: The unit of estimated dense work: one dense solve of this order (about 1e9·c flops, 0.3 to 1 s
#: on one core).
DENSE_SOLVE_ORDER = 1000


@dataclass(frozen=True)
class Ceiling:
    """One ceiling: what it limits, its default value, its unit and the reason for it.

    Attributes
    ----------
    name : str
        Its key in :data:`CEILINGS`; ``FLEXSHAFT_MAX_<NAME>`` overrides the value.
    what : str
        The option or model-file field it limits, as a user writes it (``--points``).
    value : int
        The default ceiling.
    unit : str
        What is counted (``frequencies``, ``elements per part``, ``MB``).
    why : str
        The reason, one clause for the error line and the README.
    """

    name: str
    what: str
    value: int
    unit: str
    why: str

    @property
    def variable(self) -> str:
        """The environment variable that sets another value for this ceiling."""
        return "FLEXSHAFT_MAX_" + self.name.upper()


CEILINGS: dict[str, Ceiling] = {
    c.name: c
    for c in (
        Ceiling(
            "frf_points",
            "--points",
            100_000,
            "frequencies",
            "finer than any analyser's spectrum of at most 51 200 lines, and every point is a solve "
            "and a row of output",
        ),
        Ceiling(
            "frames",
            "--frames",
            240,
            "frames",
            "8 times the default 30 a period, and every frame is a rendered picture of about 2.5 MB "
            "held until the GIF is written",
        ),
        Ceiling(
            "speed_rpm",
            "--speed",
            1_000_000,
            "rpm",
            "beyond the fastest rotating machinery, spindles and turbochargers below 500 000 rpm: "
            "above it every order line runs past every mode",
        ),
        Ceiling(
            "orders",
            "--orders",
            100,
            "orders",
            "more order lines than a diagram can show apart, and each is tracked against every mode",
        ),
        Ceiling(
            "dense_work",
            "work",
            50,
            f"dense solves of order {DENSE_SOLVE_ORDER}",
            "a Campbell diagram of a spinning model and a response with coupled damping solve a dense "
            "problem at every speed or frequency: 50 solves of order 1000 take 15 to 50 s on one core",
        ),
        Ceiling(
            "sweep_values",
            "--param",
            100_000,
            "values per parameter",
            "finer than any parameter is known, and a grid multiplies every parameter's values",
        ),
        Ceiling(
            "sweep_points",
            "--param/--lhs",
            1_000_000,
            "points",
            "each point is a whole model solved, milliseconds for a lumped chain and seconds for a "
            "fine mesh: a million are hours of work and a 100 MB table",
        ),
        Ceiling(
            "starts",
            "--starts",
            1_000,
            "starts",
            "each start is a whole least-squares run of tens of model solves, and a thousand "
            "Latin-hypercube starts already sample every bound finely",
        ),
        Ceiling(
            "peaks",
            "--peaks",
            1_000,
            "peaks",
            "more than a spectrum has resolvable resonances, and each peak is fitted on its own",
        ),
        Ceiling(
            "components",
            "chain",
            500,
            "components",
            "the longest lumped drivetrain models, a ship's line with a V20 engine or a rolling mill, "
            "have under 100 masses and put detail along a shaft into its elements, and sensitivity "
            "re-assembles the chain for every parameter: 300 components take 20 s",
        ),
        Ceiling(
            "elements",
            "elements",
            1_000_000,
            "elements per part",
            "a uniform shaft of a million elements has its lowest frequencies within 3e-11 of the "
            "continuum, far finer than any input is known, and takes 0.5 GB and 4 s to solve",
        ),
        Ceiling(
            "full_elements",
            "max_element_length",
            100_000,
            "elements per 6-DOF part",
            "600 006 DOFs and 1.8 GB to solve, where a 6-DOF Timoshenko mesh converges at a few "
            "hundred elements a part",
        ),
        Ceiling(
            "segments",
            "segments",
            1_000,
            "segments per shaft",
            "a drawn shaft has tens of diameter steps, and each segment is at least one element",
        ),
        Ceiling(
            "cad_segments",
            "segments",
            100,
            "segments per part",
            "a turned part has tens of diameter steps, and slicing time grows with the square of "
            "their number: 200 steps take 5 s",
        ),
        Ceiling(
            "sides",
            "sides",
            100,
            "sides",
            "a regular polygon of 100 sides is within 0.07 % of its circle's area, so a round "
            "segment serves beyond it, and every side is a face to slice and mesh",
        ),
        Ceiling(
            "teeth",
            "teeth",
            200,
            "teeth",
            "splines to ISO 14, ISO 4156 or DIN 5480 have at most about 100 teeth, and every tooth "
            "adds four faces to slice and mesh",
        ),
        Ceiling(
            "bolt_holes",
            "bolt_count",
            200,
            "holes per circle",
            "the largest bolted flanges, wind-turbine towers, have about 150 bolts a circle, and "
            "every hole is a boolean cut of the solid",
        ),
        Ceiling(
            "memory_mb",
            "model",
            2_048,
            "MB",
            "flexshaft's estimate of what a command holds, the assembled model and its eigen-solve, "
            "a dense solve's n² or a run's samples, stays well inside a 4 GB process",
        ),
        Ceiling(
            "samples",
            "--duration",
            10_000_000,
            "samples",
            "2.8 h at 1 kHz, longer than any test run, and every output and input is held in memory "
            "at 8 bytes a sample, 80 MB each",
        ),
        Ceiling(
            "solid_dofs",
            "mesh",
            2_000_000,
            "DOFs of a solid part",
            "a million DOFs of 10-node tetrahedra take 1.6 GB to assemble and the multigrid solve some "
            "10 GB, pyamg's at 863 000 DOFs 9.4 GB: two million fill a 24 GB machine",
        ),
        Ceiling(
            "ssi_rows",
            "--min-hz",
            4_000,
            "rows of the Toeplitz matrix",
            "the identification's block Toeplitz matrix has lags over half a period of min_hz for every "
            "channel, and its SVD grows with the cube of its rows: 4000 rows are 128 MB and half a "
            "minute on one core, 2000 rows 5 s",
        ),
    )
}


def _format(n: float) -> str:
    """A plain number: an integer as its digits, anything else shortest-form."""
    if isinstance(n, int) or (isinstance(n, float) and math.isfinite(n) and n == int(n) and abs(n) < 1e16):
        return str(int(n))
    return f"{n:.4g}"


def ceiling(name: str) -> int:
    """The ceiling ``name`` in force: ``FLEXSHAFT_MAX_<NAME>`` if set, else its default.

    Raises
    ------
    ModelError
        The environment variable is set but is not a whole number >= 1.
    """
    c = CEILINGS[name]
    text = os.environ.get(c.variable)
    if text is None or not text.strip():
        return c.value
    try:
        n = int(text.strip())
    except ValueError:
        n = 0
    if n < 1:
        raise ModelError(
            "not a whole number >= 1",
            file="environment",  # the setting, not the file being read (the CLI adds a file otherwise)
            field=c.variable,
            value=text,
            valid=f"a whole number of {c.unit} (default {_format(c.value)}), or unset",
        )
    return n


def check_ceiling(
    name: str,
    amount: float,
    *,
    field: str | None = None,
    value: object = None,
    unit: str | None = None,
    detail: str = "",
    hint: str = "",
    file: str | None = None,
    component: str | None = None,
):
    """Return ``amount`` if it is within the ceiling ``name``; else refuse it, naming the ceiling and why.

    Parameters
    ----------
    name : str
        A key of :data:`CEILINGS`.
    amount : number
        What is counted (frequencies, elements, estimated work ...), in the ceiling's unit.
    field : str, optional
        The option or field the error names; default the ceiling's own :attr:`Ceiling.what`.
    value, unit : optional
        The value as the user gave it, when it is not ``amount`` itself (``--speed = '0:1e9'``,
        a ``max_element_length`` that makes too many elements); default ``amount``.
    detail : str
        How ``amount`` follows from ``value`` (``"would cut the part into 5e+06 elements"``).
    hint : str
        What brings it down, for the error's ``valid`` (``"a larger max_element_length"``).
    file, component : str, optional
        Where the value came from (a model file, a chain component).

    Raises
    ------
    ModelError
        ``amount`` is above the ceiling (or not a number).
    """
    c = CEILINGS[name]
    limit = ceiling(name)
    # numpy scalars as plain numbers: a message never shows np.float64(...)
    amount, value = (v.item() if getattr(v, "ndim", None) == 0 else v for v in (amount, value))
    if isinstance(amount, float) and math.isnan(amount):
        amount = math.inf  # not a number of anything: above every ceiling
    if amount <= limit:
        return amount
    shown, shown_unit = (amount, None) if value is None else (value, unit)  # the ceiling names its unit
    message = (f"{detail}, " if detail else "") + f"above the ceiling of {_format(limit)} {c.unit}"
    raise ModelError(
        f"{message} ({c.why})",
        file=file,
        component=component,
        field=field or c.what,
        value=shown,
        unit=shown_unit,
        has_value=True,
        valid=f"at most {_format(limit)} {c.unit}{f' ({hint})' if hint else ''}; {c.variable}=N sets "
        "another ceiling",
    )


def model_memory_bytes(n_dof: float, entries: float, modes: int = 16) -> float:
    """Estimated peak memory of assembling a model and solving its lowest modes by Lanczos, bytes.

    Measured on uniform chains (1e6 torsion DOFs: 0.5 GB; 480 000 6-DOF DOFs: 1.4 GB) and kept on
    the safe side of both: about 120 bytes for every stored entry of the stiffness matrix (K, M,
    C, their assembly triplets and owners alike) and the Lanczos workspace, ``2·ncv + modes``
    vectors of 8 bytes a DOF (``ncv = max(2·modes + 1, 20)``, ARPACK's basis).

    Parameters
    ----------
    n_dof : float
        The model's DOFs.
    entries : float
        Stored entries of its stiffness matrix: ``n_dof·(2·b + 1)`` for a band of half-width b (1
        for a torsion chain, 11 for 6-DOF beams), plus the dense blocks of flexible bodies.
    modes : int
        Modes solved for.
    """
    ncv = max(2 * int(modes) + 1, 20)
    return 120 * float(entries) + 8 * float(n_dof) * (2 * ncv + int(modes))


def dense_memory_bytes(n_dof: float, modes: int) -> float:
    """Estimated peak memory of a dense generalised eigen-solve of ``n_dof`` DOFs, bytes.

    K and M as dense arrays and LAPACK's copies of both (4·n² doubles), and the ``modes`` vectors.
    """
    n = float(n_dof)
    return 32 * n * n + 8 * n * int(modes)


def check_memory(
    estimate: float,
    *,
    field: str,
    value: object,
    unit: str | None = None,
    detail: str,
    hint: str = "",
    file: str | None = None,
    component: str | None = None,
) -> None:
    """Refuse work whose estimated memory (bytes) is above the ``memory_mb`` ceiling.

    ``detail`` says what the estimate is of; the error gives it in MB.
    """
    mb = math.ceil(estimate / 2**20) if math.isfinite(estimate) else math.inf
    check_ceiling(
        "memory_mb",
        mb,
        field=field,
        value=value,
        unit=unit,
        detail=f"{detail} would take about {mb} MB",
        hint=hint,
        file=file,
        component=component,
    )


def dense_work(solves: float, order: float) -> float:
    """The work of ``solves`` dense solves (eigen-solves or LU) of ``order``, in solves of order
    :data:`DENSE_SOLVE_ORDER` (their cost grows with the cube of the order)."""
    return float(solves) * (float(order) / DENSE_SOLVE_ORDER) ** 3

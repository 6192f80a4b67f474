"""The section table: cross-section properties along a shaft's axis.

This is the seam between CAD and mechanics. :mod:`geometry` slices a solid
into one; a shaft given by its dimensions (``segments``) gets one from the
closed forms here. Everything downstream (torsional stiffness, inertia, the
1D elements) reads only this table.

A table has ``n + 1`` axial stations ``x`` and, per interval between two
stations, constant properties. Intervals where the solid is prismatic are
exact; where it tapers (a chamfer, a fillet) the geometry side subdivides
and takes each sub-interval's mid-section.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..errors import ModelError
from ..system.inputs import SECTIONS, read_text
from ..validation import check_real

__all__ = [
    "SectionTable",
    "SectionSegment",
    "SEGMENT_RANGE_M",
    "annulus_properties",
    "cowper_shear_factor",
    "shear_definition_ratio",
    "table_from_segments",
    "tables_to_csv",
    "tables_from_csv",
    "FORMAT_VERSION",
]

FORMAT_VERSION = 1

#: Per-interval arrays, their CSV column names (units in the name) and units.
_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("area", "area_m2", "m²"),
    ("ip", "ip_m4", "m⁴"),
    ("iy", "iy_m4", "m⁴"),
    ("iz", "iz_m4", "m⁴"),
    ("iyz", "iyz_m4", "m⁴"),
    ("j", "j_m4", "m⁴"),
    ("shear_area_y", "shear_area_y_m2", "m²"),
    ("shear_area_z", "shear_area_z_m2", "m²"),
    ("yc", "yc_m", "m"),
    ("zc", "zc_m", "m"),
)
_CSV_HEADER = ("part", "x_start_m", "x_end_m") + tuple(c[1] for c in _COLUMNS) + ("method",)


def cowper_shear_factor(inner_radius_ratio: float | np.ndarray, nu: float) -> float | np.ndarray:
    """Timoshenko shear factor of a circular tube (Cowper 1966), dimensionless.

    Parameters
    ----------
    inner_radius_ratio : float or ndarray
        m = r_inner / r_outer, 0 for a solid circle.
    nu : float
        Poisson's ratio.

    Notes
    -----
    G. R. Cowper, "The shear coefficient in Timoshenko's beam theory",
    J. Appl. Mech. 33 (1966) 335-340, Table 1: hollow circle
    κ = 6 (1 + ν)(1 + m²)² / ((7 + 6ν)(1 + m²)² + (20 + 12ν) m²); m = 0 gives
    the solid circle 6 (1 + ν) / (7 + 6ν).
    """
    m2 = np.square(inner_radius_ratio)
    return 6.0 * (1.0 + nu) * (1.0 + m2) ** 2 / ((7.0 + 6.0 * nu) * (1.0 + m2) ** 2 + (20.0 + 12.0 * nu) * m2)


def shear_definition_ratio(nu: float) -> float:
    """Cowper's shear factor of a solid circle over sectionproperties' (energy-based, Pilkey), -.

    sectionproperties defines the shear area by shear strain energy; for a
    solid circle that gives κ = 6 (1 + ν)² / (7 + 14ν + 8ν²) (Pilkey,
    *Analysis and Design of Elastic Beams*, 2002), about 4 % below Cowper's.
    Its shear areas are scaled by this ratio so that a keyed or drilled
    section stays continuous with the plain circle next to it; for bored
    sections the two definitions differ by up to a further 1.7 % (thin tube).
    """
    return float(cowper_shear_factor(0.0, nu)) * (7.0 + 14.0 * nu + 8.0 * nu**2) / (6.0 * (1.0 + nu) ** 2)


@dataclass(frozen=True)
class AnnulusProperties:
    """Closed-form properties of a circle or annulus centred on the axis (SI)."""

    area: float
    ip: float
    i: float
    j: float
    shear_area: float


def annulus_properties(od: float, id: float = 0.0, *, nu: float = 0.29) -> AnnulusProperties:
    """Exact properties of a circular or annular section centred on the shaft axis.

    Parameters
    ----------
    od, id : float
        Outer and inner diameter, m (``id = 0`` for a solid circle).
    nu : float
        Poisson's ratio, for the shear area only.

    Returns
    -------
    AnnulusProperties
        area π/4 (D² − d²) m², polar moment Ip = π/32 (D⁴ − d⁴) m⁴, bending
        moment I = Ip / 2 m⁴, torsion constant J = Ip m⁴ (exact for a circle
        and a concentric annulus: the section does not warp), shear area κ·A m².
    """
    try:
        area = math.pi / 4.0 * (od**2 - id**2)
        ip = math.pi / 32.0 * (od**4 - id**4)
    except OverflowError:  # float ** past 1.8e308 raises (no inf): the diameter is off any scale
        ip = math.inf
    if not (math.isfinite(ip) and ip > 0.0):
        lo, hi = SEGMENT_RANGE_M
        raise ModelError(
            "gives section properties (π/32·d⁴) outside floating point",
            field="od",
            value=od,
            unit="m",
            valid=f"{lo:g} m <= od <= {hi:g} m, 0 <= id < od",
        )
    kappa = float(cowper_shear_factor(id / od, nu))
    return AnnulusProperties(area=area, ip=ip, i=ip / 2.0, j=ip, shear_area=kappa * area)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class SectionTable:
    """Cross-section properties per axial interval of one shaft part (SI units).

    Parameters
    ----------
    x : ndarray, shape (n + 1,)
        Axial stations, m, strictly increasing.
    area : ndarray, shape (n,)
        Cross-section area, m².
    ip : ndarray, shape (n,)
        Polar second moment of area about the shaft axis, m⁴ (ρ·Ip is the
        axial mass moment of inertia per length).
    iy, iz, iyz : ndarray, shape (n,)
        Second moments about axes through the centroid parallel to y and z,
        and the product moment, m⁴.
    j : ndarray, shape (n,)
        St-Venant torsion constant, m⁴ (G·J is the torsional rigidity).
    shear_area_y, shear_area_z : ndarray, shape (n,)
        Timoshenko shear areas κ·A for shear along y and z, m², at Poisson's
        ratio ``nu``.
    yc, zc : ndarray, shape (n,)
        Centroid offset from the shaft axis, m.
    method : tuple of str, length n
        How each interval was computed: ``"circle"``/``"annulus"`` (closed
        form), ``"warping"`` (sectionproperties on the section polygon) or
        ``"polygon"`` (a mesh section taken as a polygon).
    nu : float
        Poisson's ratio the shear areas were computed for.
    name : str
        The part's name.
    """

    x: np.ndarray
    area: np.ndarray
    ip: np.ndarray
    iy: np.ndarray
    iz: np.ndarray
    iyz: np.ndarray
    j: np.ndarray
    shear_area_y: np.ndarray
    shear_area_z: np.ndarray
    yc: np.ndarray
    zc: np.ndarray
    method: tuple[str, ...]
    nu: float = 0.29
    name: str = "part"
    meta: Mapping[str, object] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        x = _readonly(self.x)
        if x.ndim != 1 or x.size < 2:
            raise ModelError(
                "needs at least two stations",
                component=self.name,
                field="x",
                valid="a 1-D array of >= 2 stations, m",
            )
        if not np.all(np.isfinite(x)) or np.any(np.diff(x) <= 0.0):
            raise ModelError(
                "stations must be finite and strictly increasing",
                component=self.name,
                field="x",
                valid="strictly increasing finite stations, m",
            )
        object.__setattr__(self, "x", x)
        n = x.size - 1
        for name, _, unit in _COLUMNS:
            a = _readonly(getattr(self, name))
            if a.shape != (n,):
                raise ModelError(f"has shape {a.shape}, expected ({n},)", component=self.name, field=name)
            if not np.all(np.isfinite(a)):
                bad = float(a[~np.isfinite(a)][0])
                raise ModelError(
                    "must be finite",
                    component=self.name,
                    field=name,
                    value=bad,
                    unit=unit,
                    valid="finite numbers",
                )
            if name in ("area", "ip", "j", "shear_area_y", "shear_area_z") and np.any(a <= 0.0):
                bad = float(a[a <= 0.0][0])
                raise ModelError(
                    "must be positive", component=self.name, field=name, value=bad, unit=unit, valid="> 0"
                )
            object.__setattr__(self, name, a)
        method = tuple(str(m) for m in self.method)
        if len(method) != n:
            raise ModelError(f"has {len(method)} entries, expected {n}", component=self.name, field="method")
        object.__setattr__(self, "method", method)
        object.__setattr__(
            self, "nu", check_real(self.nu, "nu", "", lo=-1.0, lo_open=True, hi=0.5, hi_open=True)
        )
        object.__setattr__(self, "meta", dict(self.meta))

    # ---- geometry -------------------------------------------------------------
    @property
    def n_intervals(self) -> int:
        """Number of intervals."""
        return self.x.size - 1

    @property
    def lengths(self) -> np.ndarray:
        """Interval lengths, m."""
        return np.diff(self.x)

    @property
    def length(self) -> float:
        """Total length, m."""
        return float(self.x[-1] - self.x[0])

    @property
    def volume(self) -> float:
        """Σ A·L, m³."""
        return float(np.dot(self.area, self.lengths))

    @property
    def compliance_factor(self) -> float:
        """Σ L / J, 1/m³: the part's torsional compliance times G."""
        return float(np.sum(self.lengths / self.j))

    # ---- mechanics ------------------------------------------------------------
    def mass(self, rho: float) -> float:
        """Mass ρ·Σ A·L, kg, for density ``rho`` in kg/m³."""
        return rho * self.volume

    def axial_inertia(self, rho: float) -> float:
        """Axial mass moment of inertia ρ·Σ Ip·L about the shaft axis, kg·m²."""
        return rho * float(np.dot(self.ip, self.lengths))

    def torsional_stiffness(self, G: float) -> float:
        """End-to-end torsional stiffness 1 / Σ L/(G·J) (springs in series), N·m/rad."""
        return G / self.compliance_factor

    def merged(self, rtol: float = 1e-12) -> SectionTable:
        """A copy with neighbouring intervals of equal properties joined into one."""
        # Offsets (yc, zc, iyz) are often exactly zero: compare against the
        # column's largest magnitude so round-off noise does not split intervals.
        scale = {c: float(np.max(np.abs(getattr(self, c)))) for c, _, _ in _COLUMNS}
        keep = [0]
        for i in range(1, self.n_intervals):
            same = self.method[i] == self.method[i - 1] and all(
                abs(getattr(self, c)[i] - getattr(self, c)[i - 1]) <= rtol * scale[c] for c, _, _ in _COLUMNS
            )
            if not same:
                keep.append(i)
        keep_arr = np.array(keep)
        x = np.append(self.x[keep_arr], self.x[-1])
        cols = {c: getattr(self, c)[keep_arr] for c, _, _ in _COLUMNS}
        return replace(self, x=x, method=tuple(self.method[i] for i in keep), **cols)

    def check_inside(self, points) -> np.ndarray:
        """``points`` (m, table positions) as an array, each strictly inside the part, or a ModelError."""
        pts = np.asarray(list(points), float)
        outside = ~np.isfinite(pts) | (pts <= self.x[0]) | (pts >= self.x[-1])
        if np.any(outside):
            raise ModelError(
                "lies outside the part",
                component=self.name,
                field="stations",
                value=float(pts[outside][0]),
                unit="m",
                valid=f"a position strictly between {self.x[0]:g} and {self.x[-1]:g} m",
            )
        return pts

    def split_at(self, points) -> SectionTable:
        """A copy with extra stations at ``points`` (m, inside the part); properties unchanged.

        Used to put mesh nodes where something attaches (a bearing, a sensor).
        """
        pts = self.check_inside(points)
        if pts.size == 0:
            return self
        tol = 1e-12 * max(1.0, self.length)
        new = np.unique(np.concatenate([self.x, pts]))
        new = new[np.concatenate([[True], np.diff(new) > tol])]
        idx = np.searchsorted(self.x, 0.5 * (new[:-1] + new[1:])) - 1
        cols = {c: getattr(self, c)[idx] for c, _, _ in _COLUMNS}
        return replace(self, x=new, method=tuple(self.method[i] for i in idx), **cols)

    def shifted(self, dx: float) -> SectionTable:
        """A copy with the stations moved by ``dx`` m."""
        return replace(self, x=self.x + dx)

    def as_dict(self) -> dict:
        """A JSON-ready description with units."""
        out: dict = {
            "name": self.name,
            "nu": self.nu,
            "units": {"x": "m"} | {c: u for c, _, u in _COLUMNS},
            "x": self.x.tolist(),
        }
        for c, _, _ in _COLUMNS:
            out[c] = getattr(self, c).tolist()
        out["method"] = list(self.method)
        return out


#: The lengths and diameters a segment may have, m: a micrometre to a kilometre, generous for any
#: drivetrain. Inside it, d⁴ (the second moments) and the element matrices built from them (G·J/L,
#: ρ·Ip·L) stay far inside floating point; outside it they overflow (1e100 m) or vanish (1e-100 m).
SEGMENT_RANGE_M = (1e-6, 1e3)


@dataclass(frozen=True)
class SectionSegment:
    """A length of plain circular or tubular shaft (m).

    ``length`` and ``od`` lie in :data:`SEGMENT_RANGE_M`; ``0 <= id < od``.
    """

    length: float
    od: float
    id: float = 0.0

    def __post_init__(self) -> None:
        lo, hi = SEGMENT_RANGE_M
        length = check_real(self.length, "length", "m", lo=lo, hi=hi)
        od = check_real(self.od, "od", "m", lo=lo, hi=hi)
        id_ = check_real(self.id, "id", "m", lo=0.0)
        if id_ >= od:
            raise ModelError(
                "the bore must be smaller than the outer diameter",
                field="id",
                value=id_,
                unit="m",
                valid=f"0 <= id < od = {od:g} m",
            )
        object.__setattr__(self, "length", length)
        object.__setattr__(self, "od", od)
        object.__setattr__(self, "id", id_)


def table_from_segments(
    segments: Iterable[SectionSegment | Mapping[str, float] | Sequence[float]],
    *,
    nu: float = 0.29,
    name: str = "shaft",
    x0: float = 0.0,
) -> SectionTable:
    """The exact section table of a stepped, possibly hollow, round shaft.

    Parameters
    ----------
    segments : iterable
        :class:`SectionSegment` or mappings with ``length``, ``od`` and
        optional ``id`` (m), from the driving end.
    nu : float
        Poisson's ratio for the shear areas.
    name : str
        The part's name.
    x0 : float
        Station of the first segment's start, m.
    """
    segs = []
    for k, s in enumerate(segments):
        try:
            if isinstance(s, SectionSegment):
                segs.append(s)
            elif isinstance(s, Mapping):
                unknown = set(s) - {"length", "od", "id"}
                if unknown:
                    raise ModelError("unknown key", field=sorted(unknown)[0], valid="length, od, id (m)")
                if "length" not in s or "od" not in s:
                    missing = "length" if "length" not in s else "od"
                    raise ModelError("missing", field=missing, valid="length and od (m), optional id")
                segs.append(SectionSegment(s["length"], s["od"], s.get("id", 0.0)))
            else:
                segs.append(SectionSegment(*s))
        except ModelError as err:
            raise ModelError(
                err.message,
                field=f"segments[{k}].{err.field}",
                value=err.value,
                unit=err.unit,
                valid=err.valid,
                has_value=err.has_value,
            ) from None
    if not segs:
        raise ModelError(
            "needs at least one segment",
            component=name,
            field="segments",
            valid="a list of {length, od, id} tables",
        )
    x = x0 + np.concatenate([[0.0], np.cumsum([s.length for s in segs])])
    props = [annulus_properties(s.od, s.id, nu=nu) for s in segs]
    zeros = np.zeros(len(segs))
    return SectionTable(
        x=x,
        area=np.array([p.area for p in props]),
        ip=np.array([p.ip for p in props]),
        iy=np.array([p.i for p in props]),
        iz=np.array([p.i for p in props]),
        iyz=zeros,
        j=np.array([p.j for p in props]),
        shear_area_y=np.array([p.shear_area for p in props]),
        shear_area_z=np.array([p.shear_area for p in props]),
        yc=zeros,
        zc=zeros,
        method=tuple("annulus" if s.id > 0 else "circle" for s in segs),
        nu=nu,
        name=name,
    )


def tables_to_csv(tables: Sequence[SectionTable]) -> str:
    """Section tables as one CSV text, units in a header line and in every column name."""
    buf = io.StringIO()
    buf.write(f"# flexshaft section table, format {FORMAT_VERSION}\n")
    buf.write("# units: SI; x in m, areas in m^2, second moments in m^4\n")
    for t in tables:
        buf.write(f"# nu[{t.name}] = {t.nu!r}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(_CSV_HEADER)
    for t in tables:
        for i in range(t.n_intervals):
            w.writerow(
                [t.name, repr(float(t.x[i])), repr(float(t.x[i + 1]))]
                + [repr(float(getattr(t, c)[i])) for c, _, _ in _COLUMNS]
                + [t.method[i]]
            )
    return buf.getvalue()


def tables_from_csv(text, *, source: str = "<csv>") -> list[SectionTable]:
    """Read section tables written by :func:`tables_to_csv`, checking units and columns.

    Parameters
    ----------
    text : str or path-like
        The CSV text, or the path of a ``.csv`` file (a ``Path``, or a one-line
        string ending in ``.csv``).
    source : str
        Where the text came from, for error messages (the path when given one).
    """
    if isinstance(text, os.PathLike) or (
        isinstance(text, str) and "\n" not in text and text.strip().lower().endswith(".csv")
    ):
        path = Path(text)
        source = str(path)
        text = read_text(path, SECTIONS)  # a regular file within the section table's ceiling
    lines = text.splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    if not comments or not comments[0].startswith("# flexshaft section table"):
        raise ModelError(
            "not a flexshaft section table", file=source, valid="a CSV written by 'flexshaft sections -o'"
        )
    nus: dict[str, float] = {}
    for ln in comments:
        if ln.startswith("# nu["):
            key, _, val = ln[5:].partition("] = ")
            try:
                nus[key] = float(val)
            except ValueError:
                raise ModelError(
                    "Poisson's ratio is not a number",
                    file=source,
                    field=f"nu[{key}]",
                    value=val,
                    has_value=True,
                    valid="a number, as 'flexshaft sections -o' writes it",
                ) from None
    try:
        rows = list(csv.reader([ln for ln in lines if ln and not ln.startswith("#")]))
    except csv.Error as err:
        raise ModelError(f"is not readable CSV ({err})", file=source) from None
    if not rows or tuple(rows[0]) != _CSV_HEADER:
        got = ",".join(rows[0]) if rows else ""
        raise ModelError(
            "columns or units do not match",
            file=source,
            field="header",
            value=got,
            valid=",".join(_CSV_HEADER),
        )
    parts: dict[str, list[list[str]]] = {}
    for r in rows[1:]:
        if len(r) != len(_CSV_HEADER):
            raise ModelError(f"row has {len(r)} fields", file=source, valid=f"{len(_CSV_HEADER)} fields")
        parts.setdefault(r[0], []).append(r)
    out = []
    for name, rs in parts.items():
        try:
            x0 = np.array([float(r[1]) for r in rs])
            x1 = np.array([float(r[2]) for r in rs])
            vals = {c: np.array([float(r[3 + k]) for r in rs]) for k, (c, _, _) in enumerate(_COLUMNS)}
        except ValueError as err:
            raise ModelError(f"a value is not a number ({err})", file=source, component=name) from None
        if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(x1))):
            raise ModelError("stations are not finite", file=source, component=name, field="x_start_m")
        if np.any(np.abs(x1[:-1] - x0[1:]) > 1e-12 * max(1.0, float(np.max(np.abs(x1))))):
            raise ModelError("intervals are not contiguous", file=source, component=name, field="x_start_m")
        try:
            out.append(
                SectionTable(
                    x=np.append(x0, x1[-1]),
                    method=tuple(r[-1] for r in rs),
                    nu=nus.get(name, 0.29),
                    name=name,
                    **vals,
                )
            )
        except ModelError as err:
            raise err.located(file=source) from None
    return out

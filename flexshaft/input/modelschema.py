"""The model file's schema: every table and key a model file may have, with its unit, range, default
and meaning (:mod:`flexshaft.input.schema`). :mod:`flexshaft.input.modelfile` reads by it, and the
documentation's model-file reference (``docs/reference/model-file.md``)
is rendered from it (``tools/schema_docs.py``).
"""

from __future__ import annotations

from dataclasses import replace

from ..elements.materials import E_RANGE_PA, RHO_MAX
from ..errors import ModelError
from ..model.components import FE_KINDS, INERTIA_MODELS, INERTIA_SPLITS
from ..model.nonlinear import GAP, TORQUE
from ..system.limits import check_ceiling
from ..validation import (
    DAMPER,
    FRACTION,
    GEAR_RATIO,
    INERTIA,
    LENGTH,
    MASS,
    POSITIVE_FREQUENCY,
    POSITIVE_INERTIA,
    RAYLEIGH_ALPHA,
    RAYLEIGH_BETA,
    STIFFNESS,
    Domain,
)
from .schema import REQUIRED, Field, Table, read, top_level

__all__ = ["MODEL_FILE", "MODEL_TABLE", "MATERIAL", "BEARING", "COMPONENTS", "SEGMENT", "REDUCE", "RAYLEIGH"]

SHAFT_FORMS = "either stiffness (N·m/rad) and inertia (kg·m²), or material and segments (m)"
RAYLEIGH_FORMS = "{alpha = 1/s, beta = s} or {frequencies_hz = [f1, f2], damping_ratios = [z1, z2]}"
REDUCE_FORMS = "{modes = n} or {cutoff_hz = f} (Hz)"
#: Keys that set a flexible body's damping per mode (only with ``reduce``).
FLEX_DAMPING_KEYS = ("damping_bands", "rayleigh")

GEOMETRY = "../guide/02-geometry-and-sections.md"
FLEXIBLE = "../guide/04-flexible-bodies-and-exports.md"


def _gear_ratio(value, key):
    """A gear ratio as a number: given as one, or as an exact fraction ``"1/97"`` (driving / driven
    speed), in :data:`~flexshaft.validation.GEAR_RATIO`."""
    if isinstance(value, str):
        num, slash, den = value.partition("/")
        try:
            if not slash:
                raise ValueError
            value = float(num) / float(den)
        except (ValueError, ZeroDivisionError):
            raise ModelError(
                "is not a number or a fraction",
                field=key,
                value=value,
                has_value=True,
                valid='driving-side speed / driven-side speed, as a number or a string "a/b" such as "1/97"',
            ) from None
    return GEAR_RATIO.check(value, key)


def _stations(value, key):
    """``((name, position m), ...)``: named nodes inside a part, each position > 0 (its unit converted)."""
    return tuple(
        (str(k), LENGTH.check(read_quantity(v, f"{key}.{k}", "m"), f"{key}.{k}")) for k, v in value.items()
    )


def read_quantity(value, key: str, unit: str):
    """``value`` with its unit converted to ``unit`` (SI), the one way a file's quantity is read."""
    return Field(key, kind="quantity", unit=unit).value(value, key)


def _segments(value, key):
    """The segments of a shaft, counted against their ceiling before each one is read; each a table
    of lengths (units converted; their sizes are the section table's to check)."""
    if not isinstance(value, list) or not value:
        raise ModelError(
            "missing or empty",
            field=key,
            value=value,
            has_value=True,
            valid="a list of {length, od, id} tables in m",
        )
    check_ceiling("segments", len(value), field=key)
    for k, seg in enumerate(value):
        if not isinstance(seg, dict):
            raise ModelError(
                "must be a table",
                field=f"{key}[{k}]",
                value=seg,
                has_value=True,
                valid="{length = m, od = m, id = m}",
            )
    return [read(seg, SEGMENT, field=f"{key}[{k}]", prefix=f"{key}[{k}].") for k, seg in enumerate(value)]


def _rayleigh(value, key):
    """A ``rayleigh`` table in either form; a key of neither is named with the forms."""
    if set(value) - set(RAYLEIGH.keys):
        raise ModelError("unknown keys " + ", ".join(sorted(value)), field=key, valid=RAYLEIGH_FORMS)
    return read(value, RAYLEIGH, field=key, prefix=f"{key}.")


def _elements(value, key):
    return check_ceiling("elements", value)


SEGMENT = Table(
    "segments",
    (
        Field("length", kind="quantity", unit="m", help="axial length"),
        Field("od", kind="quantity", unit="m", help="outer diameter"),
        Field("id", kind="quantity", unit="m", help="bore, 0 for a solid segment"),
    ),
    forms="length, od, id (m)",
)

REDUCE = Table(
    "reduce",
    (
        Field("modes", kind="integer", count=(0, 100_000), help="fixed-interface modes kept"),
        Field("cutoff_hz", domain=POSITIVE_FREQUENCY, help="keep every fixed-interface mode below it"),
    ),
    forms=REDUCE_FORMS,
)

RAYLEIGH = Table(
    "rayleigh",
    (
        Field("alpha", domain=RAYLEIGH_ALPHA, help="inertia-proportional coefficient"),
        Field("beta", domain=RAYLEIGH_BETA, help="stiffness-proportional coefficient"),
        Field("frequencies_hz", kind="any", help="[f1, f2], Hz: the two frequencies of the ratios"),
        Field("damping_ratios", kind="any", help="[z1, z2]: the ratios there (fractions)"),
    ),
    forms=RAYLEIGH_FORMS,
)

_E = Domain(E_RANGE_PA[0], False, E_RANGE_PA[1], False, "Pa")
_NU = Domain(-1.0, True, 0.5, True)
_RHO = Domain(0.0, True, RHO_MAX, False, "kg/m³")
MATERIAL = Table(
    "[materials.NAME]",
    (
        Field(
            "E",
            kind="quantity",
            unit="Pa",
            default=REQUIRED,
            shown_default=f"required, {_E.bounds}",
            help="Young's modulus",
        ),
        Field(
            "nu",
            kind="quantity",
            default=REQUIRED,
            shown_default=f"required, {_NU.bounds}",
            help="Poisson's ratio",
        ),
        Field(
            "rho",
            kind="quantity",
            unit="kg/m³",
            default=REQUIRED,
            shown_default=f"required, {_RHO.bounds}",
            help="density",
        ),
    ),
    help="a material of your own, named by the parts' `material`; its values are checked as the built-in "
    "`steel`'s (see [Numbers with units](../guide/11-threads-limits-and-safety.md#numbers-with-units) "
    "for why these bounds)",
)

MODEL_TABLE = Table(
    "[model]",
    (
        Field("name", kind="name", shown_default="file stem", help="model name in reports"),
        Field("description", kind="string", help="free text"),
        Field(
            "inertia_model",
            kind="choice",
            choices=INERTIA_MODELS,
            default="consistent",
            help="how a shaft's inertia is spread over its nodes: j·[[1/3,1/6],[1/6,1/3]] per element, "
            "or half on each end",
        ),
        Field(
            "rayleigh",
            kind="table",
            check=_rayleigh,
            expects=RAYLEIGH_FORMS,
            help="model-wide Rayleigh damping C = αJ + βK, added to the components' damping, on the "
            "deformation only (a free chain's rigid rotation feels no αJ drag: see Damped modes); the "
            "second form fits α, β to two target ratios (ξ = α/(2ω) + βω/2); α <= 1e6 1/s, β <= 1 s",
        ),
        Field(
            "dofs",
            kind="choice",
            choices=("torsion", "full"),
            default="torsion",
            help="θx per node, or 6 DOFs per node with Timoshenko shafts (every shaft from sections; see "
            "[Full 6-DOF drivetrain](../guide/01-model-files.md#six-dofs-per-node))",
        ),
        Field(
            "max_hz",
            domain=POSITIVE_FREQUENCY,
            expects='Hz, > 0 (a number, or a string with a unit: `"2 kHz"`)',
            help="the frequency range of interest: every shaft and CAD part whose mesh the file does not "
            "fix (no `elements`, no `max_element_length`) is meshed so each mode below it is within 1 % - "
            "a wavelength rule (elements short enough for linear elements' dispersion error (κh)²/24 at "
            '`max_hz`, torsional and, with `dofs = "full"`, Timoshenko bending waves), then the mesh '
            "check (every element cut into 2 and 4, Richardson extrapolation) on every mode below it, "
            "refining until it holds or a resource ceiling stops it (then said); `modes` lists the modes "
            "up to it. Without it the mesh is as the chain gives it and `modes` lists the lowest 20. "
            "Library: `flexshaft.analysis.convergence.mesh_for_range(drivetrain)`",
        ),
    ),
    help="optional",
)

BEARING = Table(
    "[[bearings]]",
    (
        Field(
            "station",
            kind="any",
            default=REQUIRED,
            expects="a station name, e.g. 'part 1/part 2'",
            help="where the spring acts",
        ),
        Field(
            "stiffness",
            domain=Domain(0.0, True, unit="N/m"),
            default=REQUIRED,
            shown_default="required",
            help="an isotropic lateral spring",
        ),
    ),
    help='only with `dofs = "full"`',
)

# --- the components' keys, each written once and shared by the types that have it -------------------

_NAME = Field(
    "name",
    kind="name",
    default=REQUIRED,
    expects="a unique name for the component",
    help="unique in the chain",
)
_TYPE = Field("type", kind="any", default=REQUIRED, help="the component's type")
_DAMPER = Field(
    "damping", domain=DAMPER, default=0.0, help="discrete damper end to end, in parallel with the stiffness"
)
_ELEMENTS = Field(
    "elements",
    kind="integer",
    default=1,
    check=_elements,
    help="equal sub-elements (each `elements`·stiffness, inertia/`elements`); for a part from sections, "
    "also caps the element length at length / `elements`",
)
_RATIO = Field(
    "damping_ratio",
    kind="any",
    expects=f"fraction, {FRACTION.bounds}",
    default=0.0,
    help="modal damping on every elastic mode of the shaft's own free-free model, as a multibody tool sets "
    "it on a flexible part (needs inertia > 0; up to 2000 elements); with `reduce` the body's, 0.0053 by "
    "default, or a list (one per elastic mode)",
)
_MAX_LENGTH = Field(
    "max_element_length",
    domain=LENGTH,
    shown_default="one element per section interval",
    help="longest element of the part's mesh",
)
_STATIONS = Field(
    "stations",
    kind="table",
    check=_stations,
    expects="{name = position in m from the part's driving end, ...}",
    shown_default="none",
    help='named nodes inside the part (position from its driving end), station `"<part>: name"` for the '
    "twist test and bearings",
)
_REDUCE = Field(
    "reduce",
    kind="table",
    table=REDUCE,
    expects="`{modes = n}` or `{cutoff_hz = Hz}`",
    shown_default="none",
    help=f"enter the chain as a Craig–Bampton flexible body; see [Flexible parts]({FLEXIBLE})",
)
_BANDS = Field(
    "damping_bands",
    kind="any",
    expects="[[f_lo Hz, f_hi Hz, ratio], ...]",
    shown_default="none",
    help="a flexible body's damping ratios by frequency band (with `reduce`)",
)
_BODY_RAYLEIGH = Field(
    "rayleigh",
    kind="table",
    check=_rayleigh,
    expects=RAYLEIGH_FORMS,
    shown_default="none",
    help="a flexible body's own Rayleigh damping (with `reduce`)",
)
_FE = Field(
    "fe",
    kind="choice",
    choices=FE_KINDS,
    default="1d",
    help='`"solid"`: the part\'s solid, meshed into 10-node tetrahedra, is its finite-element model (see '
    "[Solid parts](../guide/03-solid-parts.md)); needs the `solid` extra",
)
_MESH_SIZE = Field(
    "mesh_size",
    domain=LENGTH,
    shown_default="V/S of the part",
    help='the solid mesh\'s global element size (`fe = "solid"`, `sections --compare-solid`)',
)
_INTERFACE = Field(
    "interface",
    kind="any",
    expects='`"rigid"` \\| `"average"` \\| `{start = ..., end = ...}`',
    default="rigid",
    help="how a solid part's end faces are tied to its master nodes: rigidly (RBE2) or by averaging "
    '(RBE3) (`fe = "solid"` only)',
)
_MATERIAL = Field(
    "material", kind="any", expects="a material name", help="`steel` or a `[materials.NAME]` table"
)


#: The keys a part from sections (a shaft by segments, a cad part) ends with: as a flexible body, as a
#: solid.
_FLEXIBLE_AND_SOLID = (_REDUCE, _BANDS, _BODY_RAYLEIGH, _FE, _MESH_SIZE, _INTERFACE)


def _required(field: Field, ctype: str) -> Field:
    """``field`` as a key the component type ``ctype`` must have."""
    return replace(field, default=REQUIRED, missing=f"missing key for a {ctype}", shown_default="required")


RIGID = Table(
    "rigid",
    (
        _NAME,
        _TYPE,
        _required(
            Field(
                "inertia",
                domain=POSITIVE_INERTIA,
                help="point inertia on the current station (motor, generator, flywheel)",
            ),
            "rigid",
        ),
        Field(
            "mass",
            domain=MASS,
            default=0.0,
            help="6-DOF models only: its mass on the translations of its node",
        ),
        Field(
            "diametral_inertia",
            domain=INERTIA,
            default=0.0,
            help="6-DOF models only: its inertia about a "
            "diameter on the tilts of its node (a disc); spinning, its polar `inertia` gives the gyroscopic "
            "moment",
        ),
    ),
)
SHAFT = Table(
    "shaft",
    (
        _NAME,
        _TYPE,
        Field(
            "stiffness",
            domain=STIFFNESS,
            shown_default="required, or `material` and `segments`",
            help="torsional stiffness end to end",
        ),
        Field(
            "inertia",
            domain=INERTIA,
            shown_default="required, or `material` and `segments`",
            help="axial inertia, spread by `inertia_model`",
        ),
        _ELEMENTS,
        _RATIO,
        _DAMPER,
        _MATERIAL,
        Field(
            "segments",
            kind="any",
            check=_segments,
            expects="[{length = m, od = m, id = m}, ...]",
            shown_default="instead of `stiffness`, `inertia`",
            help=f"a shaft given by its dimensions from the driving end, `id` 0 for solid, `length` and `od` "
            "1e-6 … 1000 m; see [Stiffness "
            f"from geometry]({GEOMETRY})",
        ),
        _MAX_LENGTH,
        _STATIONS,
    )
    + _FLEXIBLE_AND_SOLID,
)
CAD = Table(
    "cad",
    (
        _NAME,
        _TYPE,
        Field(
            "geometry",
            kind="any",
            default=REQUIRED,
            missing="missing key for a cad",
            shown_default="required",
            expects="'module:function' or a path to a STEP/BREP/STL/OBJ/PLY file",
            shown_type="string",
            help='`"module:function"` returning a build123d part (flexshaft\'s `geometry.parts` / '
            "`geometry.parts.testbench`; your own `name.py` beside the model file or an installed "
            "package's only with `--allow-code`), or a STEP/BREP/STL/OBJ/PLY path relative to the model "
            "file",
        ),
        Field(
            "params",
            kind="table",
            expects="{key = value, ...} keyword parameters of the part function, SI units",
            shown_type="`{key = value, ...}`",
            shown_default="`{}`",
            help="keyword parameters of the part function, SI",
        ),
        _required(_MATERIAL, "cad"),
        Field(
            "unit",
            kind="string",
            expects="m, mm, cm, in",
            shown_type="string",
            shown_default="required for meshes without a recorded unit",
            help="`m`, `mm`, `cm` or `in`; only for mesh files",
        ),
        Field(
            "axis",
            kind="quantity",
            unit="m",
            expects="{origin = [x, y, z], direction = [dx, dy, dz]} (m)",
            shown_default="found",
            help="the part's axis of rotation",
        ),
        _MAX_LENGTH,
        _STATIONS,
        _ELEMENTS,
        _RATIO,
        _DAMPER,
    )
    + _FLEXIBLE_AND_SOLID,
)
#: The keys a coupling and a gear mesh share for a spring that is not linear (time runs only).
_NONLINEAR_SPRING = (
    Field(
        "backlash",
        domain=GAP,
        shown_default="none",
        help="total free play, centred: the spring and damper act only in contact (time runs only; "
        "linear analyses use the element in contact)",
    ),
    Field(
        "stiffness_curve",
        kind="any",
        expects="[[torque, stiffness], ...] (N·m, N·m/rad)",
        shown_type="list of [N·m, N·m/rad] pairs",
        shown_default="none",
        help="tangent stiffness against transmitted torque, torques increasing, linear between them "
        "(all >= 0: mirrored); the linear analyses use its tangent at zero torque",
    ),
    Field(
        "torque_curve",
        kind="any",
        expects="[[angle, torque], ...] (rad, N·m)",
        shown_type="list of [rad, N·m] pairs",
        shown_default="none",
        help="torque against twist as a manufacturer gives it, both increasing, through [0, 0] (all "
        "angles > 0: mirrored), linear between the points",
    ),
)
COUPLING = Table(
    "coupling",
    (
        _NAME,
        _TYPE,
        Field(
            "stiffness",
            domain=STIFFNESS,
            shown_default="required, unless a curve gives it",
            help="the coupling's spring (with a curve: its tangent at zero torque, taken from the curve)",
        ),
        Field(
            "inertia",
            domain=INERTIA,
            default=0.0,
            help="total inertia, spread like a shaft element's by "
            "`inertia_model` (consistent j·[[1/3,1/6],[1/6,1/3]], lumped j/2 each end), as the study's "
            "matrix "
            "models treat the coupling",
        ),
        replace(_DAMPER, help="damper in parallel with the spring"),
        Field(
            "inertia_split",
            kind="choice",
            choices=INERTIA_SPLITS,
            default="model",
            help='`"halves"`: two '
            "rigid halves, j/2 on each end whatever `inertia_model` - for a coupling whose mass sits in two "
            "hubs (a multibody model's rigid halves)",
        ),
        Field(
            "slip_torque",
            domain=TORQUE,
            shown_default="none (never slips)",
            help="a friction face in series with the spring: it sticks below this torque and slips "
            "above it (time runs only; linear analyses use the stuck coupling)",
        ),
        Field(
            "slip_kinetic_torque",
            domain=TORQUE,
            shown_default="`slip_torque`",
            help="the torque transmitted while slipping, <= `slip_torque`",
        ),
        Field(
            "slip_damping", domain=DAMPER, default=0.0, help="viscous torque per slip speed while slipping"
        ),
    )
    + _NONLINEAR_SPRING,
)
GEAR = Table(
    "gear",
    (
        _NAME,
        _TYPE,
        Field(
            "ratio",
            kind="any",
            check=_gear_ratio,
            default=REQUIRED,
            missing="missing key for a gear",
            expects="a number",
            shown_type='number, or a fraction `"a/b"`',
            shown_default=f"required, {GEAR_RATIO.bounds}",
            help='driving-side speed / driven-side speed, a number or an exact fraction string (`"1/97"`: '
            "the rotor drives a 97:1 speed-increasing stage)",
        ),
        Field("inertia_in", domain=INERTIA, default=0.0, help="the driving wheel, about its own shaft"),
        Field(
            "inertia_out",
            domain=INERTIA,
            default=0.0,
            help="the driven wheel, about its own shaft (not reflected)",
        ),
        Field(
            "mesh_stiffness",
            domain=STIFFNESS,
            shown_default="none (rigid mesh)",
            help="tooth-mesh "
            "stiffness referred to the driving side: it carries k·(θ_in − n·θ_out); from a linear mesh "
            "stiffness k_m (N/m) on the driving wheel's base radius r_b (m), k_m·r_b²",
        ),
        Field(
            "mesh_damping",
            domain=DAMPER,
            default=0.0,
            help="damper across the mesh, referred to the driving side (needs `mesh_stiffness`)",
        ),
    )
    + _NONLINEAR_SPRING,
)
#: Each component type's keys.
COMPONENTS = {t.name: t for t in (RIGID, SHAFT, CAD, COUPLING, GEAR)}

#: The file's top level.
MODEL_FILE = top_level(
    "model file", {"model": "table", "materials": "table", "chain": "tables", "bearings": "tables"}
)

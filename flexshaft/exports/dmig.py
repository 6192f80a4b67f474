"""Nastran DMIG punch of a Craig–Bampton flexible body: write and read back.

A Nastran user takes the superelement by including the punch in the Bulk Data
and selecting its matrices in the Case Control::

    K2GG = KAAX
    M2GG = MAAX
    B2GG = BAAX        $ only if the body has damping (the punch then holds BAAX)
    BEGIN BULK
    INCLUDE 'part.pch'

The punch holds, all in the consistent SI set N, m, kg, s (the deck must be in
it too, with ``PARAM,WTMASS,1.0``, the default):

- a ``GRID`` per boundary node at its x along the basic X axis (CD basic, so
  components 1-6 are ux, uy, uz, θx, θy, θz - flexshaft's DOF order). A
  torsion body couples component 4 (θx) only; its grids' other components get
  no stiffness from the body, so constrain them (SPC, PS) or leave them to
  AUTOSPC unless the rest of the deck carries them.
- a ``SPOINT`` per modal coordinate (fixed-interface mode), after the grids -
  the reduced coordinates are ``[u_b; q]`` as in
  :class:`flexshaft.reduction.FlexibleBody`.
- ``DMIG`` matrices KAAX, MAAX and BAAX (viscous damping, written only when
  nonzero): symmetric (IFO = 6), real double precision input (TIN = 2), output
  precision left to the machine (TOUT = 0, as the QRG recommends), each
  off-diagonal term once (lower triangle, rows at or below the column), as
  QRG DMIG remark 4 requires; large-field (``DMIG*``) column entries.
- ``$`` comment lines, which Nastran ignores: a readable summary, and the
  machine-readable header (``$ flexshaft:`` lines, JSON) with the format,
  version, units (as :data:`flexshaft.exports.bodies.UNITS`), part name, material,
  DOF order, boundary nodes and x, the ids used, fixed-interface and free-free
  frequencies and damping ratios. :func:`parse_dmig` reads it and refuses a
  text without it or in other units.

Precision: a large field is 16 characters (we fill 15, keeping a blank
between fields) and double precision needs a ``D`` exponent, so a value
carries 12 significant digits at best, 11 when negative, at least 9 for any
``1e-99 < |value| < 1e99``: a relative round-off of 5e-12 on typical entries, of
5e-9 at worst - far below anything a dynamic analysis resolves, but not the
17 digits that make a double exact, which no 16-character field holds.
Values whose shortest decimal form fits (``1.D0``, ``.29D0``) are exact.
The sidecar that :func:`flexshaft.exports.bodies.write_flexible_body` writes with
a ``.pch`` keeps T, the free-free basis and the metadata exactly.

Why DMIG punch text written here, and not through pyNastran: the format is a
handful of fixed-width cards, plain text a user can read and diff, and it
adds no dependency; pyyeti's ``rddmig`` reads it as an independent check
(optional test). The whole file is ASCII, every line at most 80 columns.
"""

from __future__ import annotations

import json
import re

import numpy as np

from ..errors import ModelError
from ..reduction.craig_bampton import FlexibleBody
from .bodyformat import FORMAT, MAX_ENTRIES, VERSION, check_metadata, metadata

__all__ = ["dmig_text", "parse_dmig", "HEADER_PREFIX"]

#: Prefix of the machine-readable header lines (JSON, wrapped over lines).
HEADER_PREFIX = "$ flexshaft: "
_WIDTH = 80  # Nastran reads 80 columns; comments are kept inside them too
_COMPONENTS = {"torsion": (4,), "full": (1, 2, 3, 4, 5, 6)}
_MAX_ID = 99_999_999  # Nastran ids have at most 8 digits
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9]{0,7}")
# A value uses 15 of its field's 16 characters: the leading blank keeps fields apart for the eye and for
# readers that split on blanks, at the cost of one digit.
_DIGITS_ROOM = 15
#: Relative rounding of a value read from a punch: at least 9 significant digits for any
#: 1e-99 < |value| < 1e99 (the module notes), a half unit in the ninth. The reader's physics checks
#: (:func:`flexshaft.exports.bodyformat.check_physics`) allow for it.
ROUNDING = 5e-9


# --- numbers in 16-character fields -------------------------------------------------------------


def _placements(digits: str, exp10: int, sign: str, letter: str):
    """Ways to write ``d1.d2… × 10^exp10`` with the point moved; yields (text, distance from d1.d2…)."""
    for k in range(len(digits) + 1):
        e = exp10 - (k - 1)
        body = f"{sign}{digits[:k]}.{digits[k:]}"
        yield f"{body}{letter}{e}", abs(k - 1)
        if e == 0 and letter == "E":  # an ordinary real needs no exponent
            yield body, abs(k - 1)


def real16(value: float, letter: str = "D") -> str:
    """The most precise form of ``value`` in a 16-character Nastran real field (15 used).

    Parameters
    ----------
    value : float
        A finite number.
    letter : {"D", "E"}
        Exponent letter: ``D`` for double-precision input (DMIG with TIN = 2,
        where Nastran requires it), ``E`` for ordinary real fields (GRID
        coordinates, written without an exponent where none is needed).

    Returns
    -------
    str
        Right-justified to 16 characters, the first blank. The value itself
        when its shortest decimal form fits, else rounded to the most
        significant digits that fit: 12 at best (``1.23456789012D5``), at
        least 9 for 1e-99 < |value| < 1e99. The point moves where that saves
        exponent characters (``1234.56789012D9``, ``.123456789012D-9``); ties
        keep the scientific ``d.ddd``.
    """
    if not np.isfinite(value):
        raise ModelError("is not a finite number", field="value", value=value, valid="a finite number")
    if value == 0.0:
        return f"{'0.':>16s}"
    sign = "-" if value < 0 else ""
    # The shortest decimal that reads back as this double first (exact), then ever fewer digits.
    mant, exp = np.format_float_scientific(abs(value), unique=True).split("e")
    tries = [(mant, exp)] + [tuple(f"{abs(value):.{p - 1}e}".split("e")) for p in range(12, 0, -1)]
    for mant, exp in tries:
        digits = mant.replace(".", "").rstrip("0") or "0"
        best = min(_placements(digits, int(exp), sign, letter), key=lambda t: (len(t[0]), t[1]))[0]
        if len(best) <= _DIGITS_ROOM:
            return f"{best:>16s}"
    raise AssertionError("unreachable: one digit always fits")  # pragma: no cover


def _read_real(field: str) -> float:
    """A Nastran real field: ``D``/``E`` exponent, or the shorthand ``1.5-3``."""
    s = field.strip().upper().replace("D", "E")
    try:
        return float(s)
    except ValueError:
        # Nastran's shorthand: the exponent sign without a letter.
        return float(re.sub(r"(?<=[0-9.])([+-])", r"E\1", s, count=1))


# --- writing ----------------------------------------------------------------------------------


def _check_name(name: str, field: str) -> str:
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ModelError(
            "is not a Nastran matrix name",
            field=field,
            value=name,
            has_value=True,
            valid="1 to 8 letters or digits, the first a letter",
        )
    return name.upper()


def _ids(offset: int, count: int, field: str) -> list[int]:
    if not isinstance(offset, (int, np.integer)) or isinstance(offset, bool) or offset < 0:
        raise ModelError("must be an integer >= 0", field=field, value=offset, valid="an integer >= 0")
    if offset + count > _MAX_ID:
        raise ModelError(
            f"leaves no room for {count} ids",
            field=field,
            value=offset,
            valid=f"an integer with {field} + {count} <= {_MAX_ID}",
        )
    return [int(offset) + k + 1 for k in range(count)]


def _symmetric(A: np.ndarray, label: str) -> np.ndarray:
    """The matrix to write; refused if not symmetric (only one triangle goes into the punch)."""
    if not np.all(np.isfinite(A)):
        raise ModelError("has non-finite entries", field=label, valid="finite numbers")
    scale = float(np.max(np.abs(A))) if A.size else 0.0
    asym = float(np.max(np.abs(A - A.T))) if A.size else 0.0
    if asym > 1e-12 * scale:
        raise ModelError(
            f"is not symmetric (largest |A - Aᵀ| = {asym:.3g}, {asym / scale:.3g} of max |A|)",
            field=label,
            valid="a symmetric matrix (IFO = 6), as craig_bampton gives",
        )
    return 0.5 * (A + A.T)


def _dmig_cards(name: str, A: np.ndarray, labels: list[tuple[int, int]]) -> list[str]:
    """Header (small field) and one large-field column entry per column with nonzeros, lower triangle."""
    lines = [f"{'DMIG':<8s}{name:<8s}{0:>8d}{6:>8d}{2:>8d}{0:>8d}"]
    for j, (gj, cj) in enumerate(labels):
        rows = j + np.flatnonzero(A[j:, j])
        if rows.size == 0:
            continue
        lines.append(f"{'DMIG*':<8s}{name:<16s}{gj:>16d}{cj:>16d}")
        lines.extend(f"{'*':<8s}{labels[i][0]:>16d}{labels[i][1]:>16d}{real16(A[i, j])}" for i in rows)
    return lines


def _grid_cards(grids: list[int], x: np.ndarray) -> list[str]:
    # GRID*: ID CP X1 X2 / X3 CD PS SEID - basic system, on the X axis.
    zero = real16(0.0, "E")
    return [
        line
        for g, xi in zip(grids, x)
        for line in (f"{'GRID*':<8s}{g:>16d}{'':16s}{real16(float(xi), 'E')}{zero}", f"{'*':<8s}{zero}")
    ]


def _spoint_cards(spoints: list[int]) -> list[str]:
    if not spoints:
        return []
    if len(spoints) == 1:
        return [f"{'SPOINT':<8s}{spoints[0]:>8d}"]
    return [f"{'SPOINT':<8s}{spoints[0]:>8d}{'THRU':>8s}{spoints[-1]:>8d}"]


def _wrap_json(doc: dict) -> list[str]:
    """The header as JSON over ``$ flexshaft:`` lines, each at most 80 columns.

    Broken after a comma where one is in reach (so a unit string such as
    ``"length": "m"`` stays on one line and lines never end in a blank an
    editor might trim); the reader joins the pieces exactly.
    """
    text = json.dumps(doc, ensure_ascii=True)  # ASCII: a deck is no place for UTF-8
    room = _WIDTH - len(HEADER_PREFIX)
    out = []
    while text:
        cut = len(text) if len(text) <= room else text.rfind(", ", 0, room) + 1
        if cut <= 0:  # no comma in reach: a plain cut
            cut = room
        out.append(HEADER_PREFIX + text[:cut])
        text = text[cut:]
    return out


def _summary(body: FlexibleBody, meta: dict, names: dict, grids, spoints) -> list[str]:
    """Readable ``$`` lines: what the punch is, its units, and what to put in the deck."""
    comps = "component 4 (RX, torsion)" if body.dofs == "torsion" else "components 1-6"
    mat = meta["material"]
    lines = [
        f"flexshaft flexible body {json.dumps(body.name)}: Craig-Bampton superelement as DMIG",
        f"format {FORMAT} version {VERSION}, as a Nastran DMIG punch; the",
        f"'{HEADER_PREFIX.strip()}' lines below are its machine-readable header (JSON): keep them",
        "units: SI - length m, angle rad, mass kg, time s, force N, frequency Hz;",
        "  K in N/m, N/rad, N*m/m, N*m/rad; M in kg, kg*m, kg*m^2;",
        "  B in N*s/m, N*m*s/rad (by DOF pair) - for a deck in N, m, kg, s",
        "  with PARAM,WTMASS,1.0 (the default)",
        "material: "
        + (
            "not recorded"
            if mat is None
            else f"{json.dumps(mat['name'])}, E = {mat['E']:.6g} Pa, nu = {mat['nu']:.6g}, "
            f"rho = {mat['rho']:.6g} kg/m^3"
        ),
        "Case Control: "
        + ", ".join(
            f"{cc} = {names[k]}" for cc, k in (("K2GG", "K"), ("M2GG", "M"), ("B2GG", "C")) if names[k]
        ),
        f"boundary nodes: GRID on the basic X axis, {comps}:",
        *(
            f"  GRID {g}: part node {n} at x = {x:.9g} m"
            for g, n, x in zip(grids, body.boundary_nodes, body.boundary_x)
        ),
        f"modal coordinates: {len(spoints)} SPOINT (fixed-interface modes):",
        *(
            f"  SPOINT {s}: mode {k + 1}, {f:.9g} Hz"
            for k, (s, f) in enumerate(zip(spoints, body.fixed_interface_hz))
        ),
        "free-free modes of the reduced part (Hz, damping ratio):",
        *(
            f"  {k + 1}: {f:.9g} Hz, {z:.6g}"
            for k, (f, z) in enumerate(zip(body.free_hz, body.damping_ratios))
        ),
    ]
    # ASCII and 80 columns whatever the part is called; the header below has the name exactly.
    return [("$ " + line.encode("ascii", "backslashreplace").decode("ascii"))[:_WIDTH] for line in lines]


def dmig_text(
    body: FlexibleBody,
    *,
    material=None,
    grid_offset: int = 1000,
    spoint_offset: int = 9000,
    k_name: str = "KAAX",
    m_name: str = "MAAX",
    b_name: str = "BAAX",
) -> str:
    """Nastran DMIG punch text of a flexible body (SI: N, m, kg, s).

    Parameters
    ----------
    body : FlexibleBody
        From :func:`flexshaft.reduction.craig_bampton`.
    material : Material, optional
        Recorded in the header.
    grid_offset : int
        Boundary node ``k`` (0-based, in ``body.boundary_nodes`` order) becomes
        GRID ``grid_offset + k + 1``.
    spoint_offset : int
        Modal coordinate ``k`` becomes SPOINT ``spoint_offset + k + 1``. Grid
        and SPOINT ids share Nastran's id space and must not overlap; give each
        body its own offsets (and names) to put several in one deck.
    k_name, m_name, b_name : str
        DMIG names of stiffness, mass and viscous damping (1-8 characters).

    Returns
    -------
    str
        The punch, ASCII, lines of at most 80 columns; see the module notes.
    """
    names = {"K": _check_name(k_name, "k_name"), "M": _check_name(m_name, "m_name")}
    names["C"] = _check_name(b_name, "b_name") if np.any(body.C) else None
    if len({v for v in names.values() if v}) < len([v for v in names.values() if v]):
        raise ModelError(
            "must differ", field="k_name, m_name, b_name", value=names, valid="three distinct names"
        )
    comps = _COMPONENTS[body.dofs]
    grids = _ids(grid_offset, body.boundary_nodes.size, "grid_offset")
    spoints = _ids(spoint_offset, body.n_modes, "spoint_offset")
    if set(grids) & set(spoints):
        raise ModelError(
            f"GRID ids {grids[0]}-{grids[-1]} overlap SPOINT ids {spoints[0]}-{spoints[-1]}",
            field="spoint_offset",
            value=spoint_offset,
            valid=f"an offset with SPOINT ids outside {grids[0]}-{grids[-1]} (they share one id space)",
        )
    labels = [(g, c) for g in grids for c in comps] + [(s, 0) for s in spoints]
    meta = metadata(body, material) | {
        "boundary_nodes": body.boundary_nodes.tolist(),
        "boundary_x": np.asarray(body.boundary_x, float).tolist(),
        "fixed_interface_hz": np.asarray(body.fixed_interface_hz, float).tolist(),
        "free_hz": np.asarray(body.free_hz, float).tolist(),
        "damping_ratios": np.asarray(body.damping_ratios, float).tolist(),
        "dmig": names | {"grids": grids, "components": list(comps), "spoints": spoints},
    }
    lines = _summary(body, meta, names, grids, spoints) + _wrap_json(meta)
    lines += _grid_cards(grids, body.boundary_x) + _spoint_cards(spoints)
    for key in ("K", "M", "C"):
        if names[key]:
            lines += _dmig_cards(names[key], _symmetric(np.asarray(getattr(body, key), float), key), labels)
    return "\n".join(lines) + "\n"


# --- reading ----------------------------------------------------------------------------------


def _header(text: str, source: str) -> dict:
    pieces = [line[len(HEADER_PREFIX) :] for line in text.splitlines() if line.startswith(HEADER_PREFIX)]
    if not pieces:
        first = next((line for line in text.splitlines() if line.strip()), "")
        raise ModelError(
            "has no flexshaft header",
            file=source,
            field="header",
            value=first[:40].rstrip(),
            has_value=True,
            valid=f"a punch written by flexshaft (its '{HEADER_PREFIX.strip()}' comment lines)",
        )
    from ..system.nesting import json_document

    try:
        meta = json_document("".join(pieces), source)
    except ModelError:
        raise
    except ValueError as err:
        raise ModelError(f"header is not readable JSON ({err})", file=source, field="header") from None
    check_metadata(meta, source)
    if not isinstance(meta.get("dmig"), dict):
        raise ModelError("header has no DMIG ids", file=source, field="dmig", valid="as dmig_text writes it")
    return meta


def _cards(text: str):
    """Bulk-data cards as (name, fields 2…), fixed small or large field; comments and blanks dropped."""
    card = None
    for raw in text.splitlines():
        line = raw.split("$", 1)[0].rstrip()
        if not line:
            continue
        if line[0] in "*+ ":
            if card is not None:
                card[1].extend(_split(line, card[2]))
            continue
        if card is not None:
            yield card[0], card[1]
        head = line[:8].strip()
        large = head.endswith("*")
        card = (head.rstrip("*").upper(), _split(line, 16 if large else 8), 16 if large else 8)
    if card is not None:
        yield card[0], card[1]


def _split(line: str, width: int) -> list[str]:
    line = line[:72].ljust(72)
    return [line[j : j + width].strip() for j in range(8, 72, width)]


def _index(meta: dict) -> dict[tuple[int, int], int]:
    d = meta["dmig"]
    labels = [(int(g), int(c)) for g in d["grids"] for c in d["components"]] + [
        (int(s), 0) for s in d["spoints"]
    ]
    return {lab: k for k, lab in enumerate(labels)}


def _fill(name: str, fields: list[str], A: np.ndarray, index: dict, seen: set, source: str) -> None:
    """Put one column entry's terms into ``A`` (both triangles), refusing what Nastran refuses."""

    def where(g: str, c: str, role: str) -> int:
        key = (int(g), int(c or 0))
        if key not in index:
            raise ModelError(
                f"{role} {key[0]} component {key[1]} is not a coordinate of this body",
                file=source,
                field=name,
                valid="its GRID components and SPOINTs (see the header)",
            )
        return index[key]

    j = where(fields[0], fields[1], "column")
    for k in range(3, len(fields) - 2, 4):
        if not fields[k]:
            continue
        i = where(fields[k], fields[k + 1], "row")
        pair = (min(i, j), max(i, j))
        if pair in seen:
            raise ModelError(
                f"term ({i + 1}, {j + 1}) is given twice",
                file=source,
                field=name,
                valid="each term of a symmetric (IFO = 6) DMIG once (QRG DMIG remark 4)",
            )
        seen.add(pair)
        A[i, j] = A[j, i] = _read_real(fields[k + 2])


def _check_form(name: str, fields: list[str], source: str) -> None:
    if fields[2] != "6" or fields[3] not in ("1", "2"):
        raise ModelError(
            f"has IFO = {fields[2] or 'blank'}, TIN = {fields[3] or 'blank'}",
            file=source,
            field=name,
            valid="IFO = 6 (symmetric), TIN = 1 or 2 (real)",
        )


def parse_dmig(text: str, *, source: str = "<dmig>") -> dict:
    """Read a punch written by :func:`dmig_text`, checking its header and units.

    Parameters
    ----------
    text : str
        The punch.
    source : str
        Named in error messages (the file).

    Returns
    -------
    dict
        ``"K"``, ``"M"``, ``"C"``: dense symmetric arrays in flexshaft's reduced
        coordinates (boundary DOFs node-major, then modal coordinates; ``C`` is
        zero when the punch has no damping matrix), SI; ``"metadata"``: the
        header (format, units, name, material, DOF order, boundary nodes and x
        in m, frequencies in Hz, damping ratios, DMIG names and ids).

    Raises
    ------
    ModelError
        No flexshaft header, other units or version, or DMIG entries that do
        not fit it.
    """
    meta = _header(text, source)
    index = _index(meta)
    n = len(index)
    if n * n > MAX_ENTRIES:
        raise ModelError(
            f"header claims {n} coordinates",
            file=source,
            field="dof_order",
            valid=f"at most {MAX_ENTRIES:,} matrix entries",
        )
    wanted = {v: k for k, v in ((k, meta["dmig"].get(k)) for k in ("K", "M", "C")) if v}
    mats: dict[str, np.ndarray] = {}
    seen: dict[str, set] = {}
    try:
        for card, fields in _cards(text):
            if card != "DMIG" or fields[0].upper() not in wanted:
                continue
            name = fields[0].upper()
            if fields[1] == "0":  # header entry: NAME "0" IFO TIN TOUT
                _check_form(name, fields, source)
                mats[name], seen[name] = np.zeros((n, n)), set()
            elif name not in mats:
                raise ModelError("column entry before its header entry", file=source, field=name)
            else:
                _fill(name, fields[1:], mats[name], index, seen[name], source)
    except ModelError:
        raise
    except (ValueError, IndexError) as err:
        raise ModelError(f"is not readable DMIG text ({type(err).__name__}: {err})", file=source) from None
    for name, key in wanted.items():
        if name not in mats and key != "C":
            raise ModelError(
                "matrix is missing", file=source, field=name, valid=f"a DMIG {name} (the header names it)"
            )
    out = {key: mats.get(name, np.zeros((n, n))) for name, key in wanted.items()}
    out.setdefault("C", np.zeros((n, n)))
    return out | {"metadata": meta}

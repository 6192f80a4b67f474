"""The surface of a drivetrain deformed by a mode: points, faces and colours, in plain numpy.

Each shaft made from sections is drawn as the surface of revolution of its section table (the
equivalent annulus of each interval: the outer radius that gives its area and polar moment), a CAD
part as its own tessellated surface, a solid part (``fe = "solid"``) as its mesh's surface, each
point turned by its own tangential displacement in the mode (a flange's rim lagging its hub shows);
a shaft given by numbers or a coupling has no geometry and is drawn as a thin schematic
cylinder. Every surface point is turned about the axis by the mode's twist, interpolated at its
axial position within its own component (a coupling's jump stays a jump), times the visual
scale; 6-DOF modes also move it by the lateral displacement. Rendering is
:mod:`flexshaft.views.render`; this module is what the tests check against closed forms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..validation import check_choice, check_int, check_real

__all__ = [
    "ModeSurface",
    "mode_surface",
    "twist_surface",
    "generator_segments",
    "COLOURS",
    "STRESS_AMPLITUDE",
]

COLOURS = ("twist", "stress", "energy")
#: The peak station rotation the stress and energy colours are given for, rad (1 mrad).
STRESS_AMPLITUDE = 1e-3
_SEGMENTS = 48  # points around the circumference


@dataclass(frozen=True)
class ModeSurface:
    """A deformed surface ready to draw (SI; x along the shaft axis).

    Attributes
    ----------
    points, deformed : ndarray, shape (n, 3)
        Undeformed and deformed surface points, m.
    faces : ndarray of int, shape (k, 4)
        Quadrilaterals (point indices) of the surfaces of revolution.
    triangles : ndarray of int, shape (t, 3)
        Triangles (point indices) of parts drawn from their own CAD surface.
    theta : ndarray, shape (n,)
        The mode's twist at each point, rad, the mode scaled so that its largest station
        rotation is ``amplitude``.
    scalars : ndarray, shape (n,)
        The colour: twist (mrad), shear stress τ = G·r·dθ/dx (MPa) or strain-energy density
        τ²/(2G) (J/m³), at ``amplitude``.
    colour, unit : str
        What ``scalars`` are and their unit.
    scale : float
        Visual twist of the largest station rotation, rad (the picture's exaggeration).
    amplitude : float
        The peak station rotation the colours are given for, rad.
    phi : ndarray, shape (n,)
        The visual twist of each point, rad (``scale`` times the normalised mode).
    lateral : ndarray, shape (n, 2)
        The visual lateral displacement (y, z) of each point, m (0 in a torsion model).
    discs : tuple of (name, x m, radius m)
        Rigid inertias, drawn as discs (radius grows with the inertia's fourth root).
    labels : tuple of (text, (x, y, z))
        Part and station names and where to write them.
    disc_phi : ndarray, shape (len(discs),)
        The visual twist of each disc, rad (``scale`` times the normalised mode at its node).
    fields : dict
        Every colour at once, ``{"twist" | "stress" | "energy": (scalars, unit)}``; ``scalars`` is
        ``fields[colour][0]``.
    stations : tuple of (name, x m)
        The model's stations (part ends, named nodes) on the drawing's axis.
    station_phi : ndarray, shape (len(stations),)
        The visual twist of each station, rad (``scale`` times the normalised mode at its node): a
        viewer draws it as a hand turning about the axis, visible however slender the shaft.
    has_length : bool
        Whether the drawing's x is a length (m): False for a chain given by numbers only, drawn
        schematically (one unit per node) - no length scale belongs on it.
    """

    points: np.ndarray
    deformed: np.ndarray
    faces: np.ndarray
    triangles: np.ndarray
    theta: np.ndarray
    scalars: np.ndarray
    colour: str
    unit: str
    scale: float
    amplitude: float
    phi: np.ndarray
    lateral: np.ndarray
    discs: tuple
    labels: tuple
    disc_phi: np.ndarray
    fields: dict
    stations: tuple = ()
    station_phi: np.ndarray = field(default_factory=lambda: np.zeros(0))
    has_length: bool = True

    def at(self, factor: float) -> np.ndarray:
        """The points deformed by ``factor`` times the mode (1: ``deformed``; sin(ωt) animates it)."""
        return _deform(self.points, factor * self.phi, factor * self.lateral)


def generator_segments(surface: ModeSurface) -> np.ndarray:
    """Point pairs of the lines along the axis at 0°, 90°, 180° and 270° of every ring, shape (k, 2).

    A round shaft turned about its axis looks the same; these four lines, straight before, show the
    twist as they turn into helices. A face's angle is read from its first point (rings are at
    multiples of 360°/48), so it does not matter where a component's points start.
    """
    if not surface.faces.size:
        return np.zeros((0, 2), dtype=np.int64)
    first = surface.points[surface.faces[:, 0]]
    step = np.rint(np.arctan2(first[:, 2], first[:, 1]) / (2 * np.pi / _SEGMENTS)).astype(int) % _SEGMENTS
    along = surface.faces[np.isin(step, [0, _SEGMENTS // 4, _SEGMENTS // 2, 3 * _SEGMENTS // 4])]
    return along[:, [0, 3]]


def _deform(P: np.ndarray, phi: np.ndarray, lateral: np.ndarray) -> np.ndarray:
    """Points turned about the x axis by ``phi`` (rad) and moved by ``lateral`` (y, z), m."""
    D = P.copy()
    D[:, 1] = P[:, 1] * np.cos(phi) - P[:, 2] * np.sin(phi) + lateral[:, 0]
    D[:, 2] = P[:, 1] * np.sin(phi) + P[:, 2] * np.cos(phi) + lateral[:, 1]
    return D


def _profile(comp, x0: float, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(x, r, interval) of the outer profile of a shaft made from sections, a ring at every mesh node.

    ``nodes`` are the component's node positions (m, on the drawing's axis). Each table interval
    gets a ring at every node inside it, its two ends included, so a diameter step is a radial
    face and the twist is sampled where the mode is known.
    """
    t = getattr(comp, "sections", None)
    if t is None:
        return None
    # Equivalent annulus: π(ro² − ri²) = A and π/2 (ro⁴ − ri⁴) = Ip give ro² = Ip/A + A/(2π).
    ro = np.sqrt(t.ip / t.area + t.area / (2 * np.pi))
    edges = t.x - t.x[0] + x0
    tol = 1e-9 * max(1.0, float(edges[-1] - edges[0]))
    xs, rs, ks = [], [], []
    for k in range(t.n_intervals):
        inside = nodes[(nodes >= edges[k] - tol) & (nodes <= edges[k + 1] + tol)]
        xs.append(inside)
        rs.append(np.full(inside.size, ro[k]))
        ks.append(np.full(inside.size, k))
    return np.concatenate(xs), np.concatenate(rs), np.concatenate(ks)


def _slopes(px: np.ndarray, interval: np.ndarray, xs: np.ndarray, th: np.ndarray) -> np.ndarray:
    """dθ/dx at each profile point: the mean of its elements' slopes within the same interval."""
    if xs.size < 2:
        return np.zeros(px.size)
    dx = np.diff(xs)
    el = np.where(dx > 0, np.diff(th) / np.where(dx > 0, dx, 1.0), 0.0)
    out = np.zeros(px.size)
    for j, (x, k) in enumerate(zip(px, interval)):
        left = int(np.searchsorted(xs, x, "left")) - 1  # the element ending at x
        right = int(np.searchsorted(xs, x, "right")) - 1  # the element starting at x
        same = interval == k
        first, last = px[same].min(), px[same].max()
        use = []
        if x > first and 0 <= left < el.size:
            use.append(el[left])
        if x < last and 0 <= right < el.size:
            use.append(el[right])
        out[j] = float(np.mean(use)) if use else 0.0
    return out


def mode_surface(result, mode: int, *, colour: str = "twist", scale: float = 0.3) -> ModeSurface:
    """The model's surface deformed by one mode.

    Parameters
    ----------
    result : ModalResult
    mode : int
        As ``flexshaft modes`` numbers them.
    colour : {"twist", "stress", "energy"}
        The colour of the surface (see :class:`ModeSurface`), given at 1 mrad peak station rotation.
    scale : float
        Visual twist of the largest station rotation, rad (0.3 rad ≈ 17°).
    """
    check_choice(colour, "colour", COLOURS)
    mode = check_int(mode, "mode", lo=0, hi=result.count - 1)
    scale = check_real(scale, "scale", "rad", lo=0.0, lo_open=True, hi=np.pi)
    model = result.model
    if result.rigid[mode] and model.dofs == "torsion":
        raise ModelError(
            "is a rigid-body mode (the whole line turns): nothing deforms",
            field="mode",
            value=mode,
            valid=f"an elastic mode, {int(result.rigid.sum())} … {result.count - 1}",
        )
    theta_n = result.dof_shapes("θx")[:, mode]
    peak = float(np.max(np.abs(theta_n[model.station_nodes]))) or float(np.max(np.abs(theta_n))) or 1.0
    lateral = None
    if model.dofs == "full":
        lateral = (result.dof_shapes("uy")[:, mode] / peak, result.dof_shapes("uz")[:, mode] / peak)
    # a solid part's own surface moves as its solid does: its displacement per reduced coordinate
    solid = {}
    for body in model.bodies:
        shapes = getattr(body.body, "solid", None)
        if shapes is not None:
            q = result.shapes[body.columns, mode] * body.scale
            solid[body.component] = (shapes, (shapes.U @ q).reshape(-1, 3) / peak)
    return _surface(model, theta_n / peak, lateral, colour, scale, STRESS_AMPLITUDE, solid)


def twist_surface(drivetrain, twist, *, colour: str = "stress", scale: float = 0.3) -> ModeSurface:
    """The drivetrain's surface as the twist test turns it, coloured at the test's own torque.

    ``twist`` is :func:`flexshaft.analysis.twist.twist_test`'s result for ``drivetrain``; the
    colours are the real twist (mrad), shear stress τ = G·r·dθ/dx (MPa) or energy density at
    its torque, and the largest rotation is drawn as ``scale`` rad.
    """
    from ..model.assembly import assemble

    check_choice(colour, "colour", COLOURS)
    scale = check_real(scale, "scale", "rad", lo=0.0, lo_open=True, hi=np.pi)
    model = assemble(drivetrain, reduce=False, dofs="torsion", statics=True)  # the twist test's own model
    theta = np.asarray(twist.theta, dtype=float)
    peak = float(np.max(np.abs(theta))) or 1.0
    return _surface(model, theta / peak, None, colour, scale, peak)


def _solid_points(shapes, u: np.ndarray, x0: float, xs_c: np.ndarray, th_c: np.ndarray):
    """A solid part's surface points (on the drawing's axis from ``x0``), each point's own turn about
    the axis (its tangential displacement over its radius; on the axis the line's) and the line's
    slope dθ/dx at its x."""
    local = shapes.mesh.nodes[shapes.nodes]
    x = local[:, 0] - shapes.mesh.nodes[:, 0].min() + x0
    r = np.hypot(local[:, 1], local[:, 2])
    on = r > 1e-9 * max(float(r.max()), 1e-300)
    tangential = -local[:, 2] * u[:, 1] + local[:, 1] * u[:, 2]
    turn = np.where(on, tangential / np.where(on, r * r, 1.0), np.interp(x, xs_c, th_c))
    d_x = np.diff(xs_c)
    el = np.where(d_x > 0, np.diff(th_c) / np.where(d_x > 0, d_x, 1.0), 0.0)
    k = np.clip(np.searchsorted(xs_c, x, "right") - 1, 0, max(el.size - 1, 0))
    return np.column_stack([x, local[:, 1], local[:, 2]]), turn, (el[k] if el.size else np.zeros(x.size)), r


def _own_surface_points(local, x, xs_c, th_c):
    """A part's own surface (its CAD, tessellated; ``local`` points in the part's frame, ``x`` their
    axial positions in the drivetrain's): the points, each one's twist at its x, its slope, its radius."""
    d_x = np.diff(xs_c)
    el = np.where(d_x > 0, np.diff(th_c) / np.where(d_x > 0, d_x, 1.0), 0.0)
    k = np.clip(np.searchsorted(xs_c, x, "right") - 1, 0, max(el.size - 1, 0))
    slope = el[k] if el.size else np.zeros(x.size)
    points = np.column_stack([x, local[:, 1], local[:, 2]])
    return points, np.interp(x, xs_c, th_c), slope, np.hypot(local[:, 1], local[:, 2])


def _surface(model, theta_n, lateral, colour: str, scale: float, amp: float, solid=None) -> ModeSurface:
    """The surface of ``model`` turned by ``theta_n`` (largest 1) times ``scale``; colours at ``amp`` rad.

    ``solid``: {component: (SolidShapes, (k, 3) displacement of its surface nodes, normalised as
    ``theta_n``)} for solid parts drawn from their own surface as their solid moves."""
    solid = solid or {}
    has_length = model.x[-1] > model.x[0]
    xn = model.x if has_length else np.arange(model.n_nodes, dtype=float)
    length = float(xn[-1] - xn[0]) or 1.0
    schematic_r = 0.04 * length
    angles = np.linspace(0.0, 2 * np.pi, _SEGMENTS, endpoint=False)
    pts, theta, dthdx, radius, shear_mod, faces, labels, discs = [], [], [], [], [], [], [], []
    triangles, disc_theta = [], []
    count = 0
    for ci, comp in enumerate(model.drivetrain.components):
        s, e = int(model.start_node[ci]), int(model.end_node[ci])
        if comp.type in ("rigid", "gear"):
            # A gear stage is drawn as a disc as well: its two wheels sit on other axes in the real box.
            j = comp.inertia if comp.type == "rigid" else comp.inertia_in + comp.inertia_out
            size = schematic_r * 1.5 * (1 + np.log10(1 + j)) ** 0.5  # grows slowly with J
            discs.append((comp.name, float(xn[s]), size))
            disc_theta.append(float(theta_n[s]))
            continue
        xs_c, th_c = xn[s : e + 1], theta_n[s : e + 1]
        if ci in solid and has_length:
            shapes, u = solid[ci]
            P_c, turn, slope, r = _solid_points(shapes, u, float(xn[s]), xs_c, th_c)
            pts.append(P_c)
            theta.append(turn)
            dthdx.append(slope)
            radius.append(r)
            shear_mod.append(np.full(r.size, comp.material.G))
            triangles.append(np.asarray(shapes.triangles, dtype=np.int64) + count)
            count += r.size
            labels.append((comp.name, (float(0.5 * (P_c[:, 0].min() + P_c[:, 0].max())), 0.0, 1.3 * r.max())))
            continue
        own = getattr(getattr(comp, "sections", None), "meta", {}).get("surface") if has_length else None
        if own is not None:
            # the part's own surface (its CAD): each point turns with the twist at its x
            x = own[0][:, 0] - comp.sections.x[0] + xn[s]
            P_c, turn, slope, r = _own_surface_points(own[0], x, xs_c, th_c)
            pts.append(P_c)
            theta.append(turn)
            dthdx.append(slope)
            radius.append(r)
            shear_mod.append(np.full(r.size, comp.material.G))
            triangles.append(np.asarray(own[1], dtype=np.int64) + count)
            count += r.size
            labels.append((comp.name, (float(0.5 * (P_c[:, 0].min() + P_c[:, 0].max())), 0.0, 1.3 * r.max())))
            continue
        prof = _profile(comp, float(xn[s]), xs_c) if has_length else None
        if prof is None:  # no geometry: a thin schematic cylinder over the component's nodes
            px = xs_c.astype(float)
            if px[-1] <= px[0]:  # a coupling: a short ring where the line jumps
                px = np.array([px[0], px[0] + 0.02 * length])
                xs_c, th_c = px, np.array([theta_n[s], theta_n[e]])
            pr, interval = np.full(px.size, schematic_r * 0.6), np.zeros(px.size, dtype=int)
        else:
            px, pr, interval = prof
        # The twist within this component only: its own nodes (a coupling's jump stays a jump).
        th = np.interp(px, xs_c, th_c)
        sl = _slopes(px, interval, xs_c, th_c)
        G = comp.material.G if getattr(comp, "material", None) is not None else 0.0
        n_ring = px.size
        for j in range(n_ring):
            ring = [np.full(_SEGMENTS, px[j]), pr[j] * np.cos(angles), pr[j] * np.sin(angles)]
            pts.append(np.column_stack(ring))
            theta.append(np.full(_SEGMENTS, th[j]))
            dthdx.append(np.full(_SEGMENTS, sl[j]))
            radius.append(np.full(_SEGMENTS, pr[j]))
            shear_mod.append(np.full(_SEGMENTS, G))
        for j in range(n_ring - 1):
            a = count + j * _SEGMENTS + np.arange(_SEGMENTS)
            b = a + _SEGMENTS
            faces.append(np.column_stack([a, np.roll(a, -1), np.roll(b, -1), b]))
        count += n_ring * _SEGMENTS
        labels.append((comp.name, (float(0.5 * (px[0] + px[-1])), 0.0, float(pr.max()) * 1.3)))
    r_top = max((p[2] for _, p in labels), default=schematic_r)
    for st in model.stations:
        if ": " in st.name:  # a named node inside a part (a journal, a torque flange): under the shaft
            labels.append((st.name, (float(xn[st.node]), 0.0, -r_top)))
    if not pts:
        raise ModelError("has no shaft or coupling to draw", field="model", valid="flexible parts")
    P = np.vstack(pts)
    th = np.concatenate(theta)
    phi = scale * th  # the visual twist
    lat = np.zeros((P.shape[0], 2))
    if lateral is not None:
        # Lateral motion drawn at the same exaggeration: the largest lateral excursion three times
        # the visual twist's arc at the largest radius.
        r_max = float(np.max(np.hypot(P[:, 1], P[:, 2])))
        u_max = float(np.max(np.abs(np.concatenate(lateral)))) or 1.0
        for c in (0, 1):
            lat[:, c] = np.interp(P[:, 0], xn, lateral[c]) / u_max * scale * r_max * 3
    D = _deform(P, phi, lat)
    tau = np.concatenate(shear_mod) * np.concatenate(radius) * np.concatenate(dthdx) * amp
    G = np.concatenate(shear_mod)
    fields = {
        "twist": (th * amp * 1e3, "mrad"),
        "stress": (tau / 1e6, "MPa"),
        "energy": (np.where(G > 0, tau**2 / (2 * np.where(G > 0, G, 1.0)), 0.0), "J/m³"),
    }
    scalars, unit = fields[colour]
    return ModeSurface(
        points=P,
        deformed=D,
        faces=np.vstack(faces) if faces else np.zeros((0, 4), dtype=np.int64),
        triangles=np.vstack(triangles) if triangles else np.zeros((0, 3), dtype=np.int64),
        theta=th * amp,
        scalars=scalars,
        colour=colour,
        unit=unit,
        scale=scale,
        amplitude=amp,
        phi=phi,
        lateral=lat,
        discs=tuple(discs),
        labels=tuple(labels),
        disc_phi=scale * np.asarray(disc_theta, dtype=float),
        fields=fields,
        stations=tuple((st.name, float(xn[st.node])) for st in model.stations),
        station_phi=scale * np.array([theta_n[st.node] for st in model.stations], dtype=float),
        has_length=bool(has_length),
    )

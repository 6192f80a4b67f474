"""Section-table benchmark: the test-bench PTSS from parameters to section tables.

What it measures
----------------
PTSS parts 1, 2 and 4 of ``geometry.parts.testbench`` (bolted flanges with 12- and 16-hole
bolt circles, the torque-measuring flange in part 2, shoulder fillets), from keyword
parameters to one section table each, in one process, after the imports. Stages:

1. imports (build123d, geometry, sectionproperties) - reported, not counted;
2. build the three build123d solids from their parameters;
3. slice them: B-rep breakpoints, planar sections, closed forms, mass check;
4. warping analyses (sectionproperties) of the distinct non-circular shapes.

Stage 3 and 4 run together inside ``geometry.slicing.sections``; the time of stage 4
is the sum of the analyses' own wall times, stage 3 is the rest. The target from the
issue: stages 2-4 under 5 s, with sectionproperties called once per distinct shape
(the script prints the count of analyses and of distinct shapes).

Peer: the by-hand route - the same sections (one mid-slice per B-rep interval, the
same polygons) each sent to sectionproperties directly (``Geometry`` → ``create_mesh``
→ geometric + warping analysis) with no closed forms and no cache, the way one would
script sectionproperties alone. Its mesh uses the same maximum triangle area as
flexshaft's default (section area / 200) but none of flexshaft's corner grading.
``--no-peer`` skips it (it takes ~10-30 s).

How to run (from the repository root)
-------------------------------------
    .venv/bin/python benchmarks/bench_sections.py
    .venv/bin/python benchmarks/bench_sections.py --no-peer

Timings are printed, never asserted.
"""

from __future__ import annotations

import argparse
import os
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--no-peer", action="store_true", help="skip the plain sectionproperties route")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")

    t0 = time.perf_counter()
    import build123d  # noqa: F401
    import sectionproperties  # noqa: F401

    from flexshaft import STEEL
    from geometry.parts import testbench
    from geometry.slicing import brep, sections, warping

    warping.preload()  # sectionproperties' analysis modules pull in matplotlib: an import, not work
    t_import = time.perf_counter() - t0

    warping.clear_cache()
    t1 = time.perf_counter()
    parts = testbench.ptss()
    t_build = time.perf_counter() - t1

    spent = []
    real = warping.warping_properties

    def timed(*a, **k):
        r = real(*a, **k)
        spent.append(r.seconds)
        return r

    warping.warping_properties = timed  # count the analyses' own time, nothing else changes
    try:
        t2 = time.perf_counter()
        tables = {name: sections(p, name=name, nu=STEEL.nu) for name, p in parts.items()}
        t_slice_total = time.perf_counter() - t2
    finally:
        warping.warping_properties = real
    t_warping = sum(spent)
    n_analyses = warping.analysis_count()
    n_warping_sections = sum(t.method.count("warping") for t in tables.values())

    print(f"\n{'stage':<44} {'s':>7}")
    print(f"{'imports (not counted)':<44} {t_import:7.2f}")
    print(f"{'build parts 1, 2, 4 from parameters':<44} {t_build:7.2f}")
    print(f"{'slice: breakpoints, sections, closed forms':<44} {t_slice_total - t_warping:7.2f}")
    print(f"{'warping analyses (sectionproperties)':<44} {t_warping:7.2f}")
    total = t_build + t_slice_total
    print(f"{'total after imports':<44} {total:7.2f}   target < 5 s: {'met' if total < 5 else 'NOT met'}")
    print(f"\nsectionproperties analyses: {n_analyses} for {n_warping_sections} non-circular intervals")
    print(
        f"\n{'part':<8} {'intervals':>9} {'stiffness N·m/rad':>18} {'inertia kg·m²':>14} {'volume err':>11} "
        f"{'inertia err':>11}"
    )
    for name, t in tables.items():
        c = t.meta["mass_check"]
        print(
            f"{name:<8} {t.n_intervals:9d} {t.torsional_stiffness(STEEL.G):18.6e} "
            f"{t.axial_inertia(STEEL.rho):14.5f} {c.volume_error:+11.1e} {c.axial_moment_error:+11.1e}"
        )

    if args.no_peer:
        return
    # ---- peer: every breakpoint interval's section straight to sectionproperties ------------
    from sectionproperties.analysis.section import Section
    from sectionproperties.pre.geometry import Geometry
    from shapely.geometry import Polygon

    from geometry.slicing.solid import find_axis
    from geometry.units import from_cad, to_cad

    t3 = time.perf_counter()
    n_peer = 0
    j_peer = {}
    for name, p in parts.items():
        solid = brep.as_solid(p)
        ax = find_axis(solid)
        import numpy as np

        local = brep.aligned(solid, to_cad(np.asarray(ax.origin)), np.asarray(ax.direction))
        bb = local.bounding_box()
        stations = brep.breakpoints(local, 1e-7 * bb.size.X)
        compliance = 0.0
        for a, b in zip(stations[:-1], stations[1:]):
            face = brep.section_faces(local, 0.5 * (a + b))[0]
            ext, holes = brep.face_rings(face, 128)
            poly = Polygon(from_cad(ext), [from_cad(h) for h in holes])
            geom = Geometry(poly)
            geom.create_mesh(mesh_sizes=poly.area / 200)
            sec = Section(geom)
            sec.calculate_geometric_properties()
            sec.calculate_warping_properties()
            compliance += from_cad(b - a) / sec.get_j()
            n_peer += 1
        j_peer[name] = STEEL.G / compliance
    t_peer = time.perf_counter() - t3
    ours = t_slice_total
    print(
        f"\npeer (sectionproperties on every interval, no closed forms, no cache): {n_peer} analyses, "
        f"{t_peer:.2f} s"
    )
    print(f"flexshaft slicing + warping: {ours:.2f} s  ->  flexshaft / peer = {ours / t_peer:.3f}")
    for name, t in tables.items():
        k = t.torsional_stiffness(STEEL.G)
        print(
            f"  {name}: stiffness flexshaft {k:.6e}, peer {j_peer[name]:.6e} (ratio {k / j_peer[name]:.5f}; "
            "the peer has no fillet subdivision and a faceted J)"
        )


if __name__ == "__main__":
    main()

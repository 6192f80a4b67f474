"""The commands about a model itself: ``modes``, ``demo``, ``twist``, ``sections``, ``report``, ``view``
and ``body`` (an exported flexible body read back)."""

from __future__ import annotations

import argparse
import json

from ...errors import ModelError
from ..console import emit, write_plot
from ..loadmodel import DEMO_MODEL, demo_file, demo_model, load
from ..options import (
    force_option,
    hz,
    json_option,
    output_option,
    plot_option,
    renamed,
    table_options,
    table_output_option,
    whole,
)
from ..registry import PLOT, TABLE, UFF, Command, Written

__all__ = [
    "COMMANDS",
    "MESH_CHECK_AUTO_DOFS",
    "mesh_check",
    "modes",
    "twist",
    "report",
    "write_report",
    "view",
    "sections",
    "body",
]

#: What ``view -o`` writes, by suffix.
VIEW_FILES = {".png": "a picture", ".gif": "an animation", ".html": "the viewer to turn in a browser"}
MESH_CHECK_AUTO_DOFS = 20_000  # the check doubles the solve; above this it runs only when asked


def mesh_check(result, asked: bool | None):
    """The mesh-convergence estimate: when asked, or by default on models up to MESH_CHECK_AUTO_DOFS."""
    if asked is False or (asked is None and result.model.n_dof > MESH_CHECK_AUTO_DOFS):
        return None
    from ...analysis.convergence import mesh_convergence

    try:
        return mesh_convergence(result)
    except ModelError:
        if asked:
            raise  # asked for explicitly: say why it cannot be done
        return None  # the doubled mesh is over a budget or a guard: the modes themselves stand


def modes(drivetrain, args) -> str:
    from ...analysis.modal import listing_modes
    from ...validation import check_real

    count = getattr(args, "count", None)
    max_hz = getattr(args, "max_hz", None)
    if max_hz is not None:
        max_hz = check_real(max_hz, "--max-hz", "Hz", lo=0.0, lo_open=True)
    else:
        max_hz = drivetrain.max_hz  # the model file's range of interest lists its modes
    try:
        # --modes N, else the modes up to max_hz, else the lowest 20: never every mode of a fine mesh
        result = listing_modes(drivetrain, count, max_hz, inertia_model=getattr(args, "inertia", None))
    except ModelError as err:
        if count is None or err.field != "count":
            raise
        # named as the option (as sensitivity and sweep name --modes)
        raise ModelError(err.message, field="--modes", value=err.value, valid=err.valid) from None
    mesh = mesh_check(result, getattr(args, "mesh_check", None))
    if getattr(args, "plot", None):
        write_plot(args.plot, result.plot(), args.force)
    written = ""
    if getattr(args, "uff", None):
        from ...exports.universalfile import write_modes_uff

        try:
            path = write_modes_uff(result, args.uff, overwrite=args.force)
        except ModelError as err:
            raise (err.replaced(field="--uff") if err.field in ("uff", "path") else err) from None
        written = f"\nuff: {path} (units 164, stations 2411, {result.count} modes 55)"
    if args.json:
        doc = result.to_dict(max_hz=max_hz, mesh=mesh, count=count)
        return json.dumps(doc, indent=1, ensure_ascii=False) + written
    return result.table(max_hz=max_hz, mesh=mesh, count=count) + written


def twist(args) -> str:
    from ...analysis.twist import stiffness_target, twist_test

    drivetrain = load(args, args.model)
    try:
        result = twist_test(drivetrain, args.torque, clamp=args.clamp, load=args.at)
    except ModelError as err:  # the library names its arguments, the command line its options
        option = {"load": "--at"}.get(err.field)
        raise (err.replaced(field=option) if option and err.file is None else err) from None
    targets = []
    for spec in args.target:
        name, sep, value = spec.rpartition("=")
        try:
            k = float(value)
        except ValueError:
            k = None
        if not sep or not name or k is None:
            raise ModelError(
                "is not PART=STIFFNESS",
                field="--target",
                value=spec,
                valid="a component name, '=', a stiffness in N·m/rad",
            )
        targets.append((name, stiffness_target(drivetrain.component(name), k)))
    if args.plot:
        from ...views.plots import twist_figure

        write_plot(args.plot, twist_figure(result), args.force)
    if args.view:
        from ...views.render import twist_png

        twist_png(drivetrain, result, args.view, overwrite=args.force)
    if args.json:
        doc = result.to_dict()
        doc["targets"] = [{"name": n} | t.to_dict() for n, t in targets]
        return json.dumps(doc, indent=1, ensure_ascii=False)
    return result.table() + "".join(f"\n\n{n}: {t.table()}" for n, t in targets)


def report(args) -> str:
    return write_report(args.model, args.output, args.force, args)


def write_report(model, out, force: bool, args) -> str:
    """``flexshaft report``: the model file's study with the default plan, its report in ``out``."""
    from ...study import run_report
    from ...views.progress import ProgressBar

    run = run_report(
        model,
        out,
        force=force,
        allow_code=getattr(args, "allow_code", False),
        use_cache=not getattr(args, "no_cache", False),
        slicing=ProgressBar,
    )
    if run.failed:  # the report stands, with the failure in it; the exit status says so
        emit(f"report: {run.folder / 'index.html'}")
        s = run.failed[0]
        raise ModelError(f"{s.title}: {s.status} ({s.error})")
    return f"report: {run.folder / 'index.html'}"


def view(args) -> str:
    from ...analysis.modal import default_count, modal_analysis
    from ...model.assembly import assemble
    from ...views import render

    model = assemble(load(args, args.model))
    if args.mode >= model.n_dof:
        raise ModelError("no such mode", field="--mode", value=args.mode, valid=f"0 … {model.n_dof - 1}")
    result = modal_analysis(model, min(max(args.mode + 1, default_count(model)), model.n_dof))
    out = args.output
    if out.lower().endswith(".gif"):
        path = render.mode_gif(
            result,
            args.mode,
            out,
            frames=args.frames,
            colour=args.color,
            scale=args.scale,
            overwrite=args.force,
        )
    elif out.lower().endswith(".png"):
        path = render.mode_png(
            result, args.mode, out, colour=args.color, scale=args.scale, overwrite=args.force
        )
    elif out.lower().endswith(".html"):
        from ...views.webview import mode_html

        path = mode_html(result, args.mode, out, colour=args.color, scale=args.scale, overwrite=args.force)
    else:
        raise ModelError(
            "unknown picture type", field="-o", value=out, valid="FILE.png, FILE.gif or FILE.html"
        )
    f = result.frequencies_hz[args.mode]
    return f"mode {args.mode} ({f:.4g} Hz), coloured by {args.color}: {path}"


def section_parts(args) -> list:
    """The shafts with section tables named by ``flexshaft sections SOURCE``."""
    from pathlib import Path

    from ...elements.materials import BUILTIN_MATERIALS
    from ...model.components import Shaft
    from ...views.progress import ProgressBar

    source = Path(args.source)
    if source.suffix.lower() == ".toml":
        if args.unit is not None:
            raise ModelError(
                "a model file gives each mesh part its own unit",
                field="--unit",
                value=args.unit,
                valid="unit = ... on the [[chain]] entry",
            )
        drivetrain = load(args, source, mesh_solids=bool(getattr(args, "compare_solid", False)))
        parts = [c for c in drivetrain.components if isinstance(c, Shaft) and c.sections is not None]
        if not parts:
            raise ModelError(
                "no part is given by its geometry",
                file=str(source),
                field="chain",
                valid="a model with type = 'cad' parts or shafts given by segments",
            )
        return parts
    if args.material not in BUILTIN_MATERIALS:
        raise ModelError(
            "unknown material",
            field="--material",
            value=args.material,
            valid=", ".join(BUILTIN_MATERIALS) + " (define others in a model file)",
        )
    from ...input.cad import cad_sections

    material = BUILTIN_MATERIALS[args.material]
    table = cad_sections(
        str(source),
        use_cache=not args.no_cache,
        unit=args.unit,
        nu=material.nu,
        name=source.stem,
        progress=ProgressBar(f"slicing {source.name}"),
    )
    return [Shaft.from_sections(source.stem, table, material, geometry=str(source))]


def sections(args) -> str:
    from dataclasses import replace

    from ...model.describe import sections_document, sections_table
    from ...sections.table import tables_to_csv

    if args.compare_solid:
        return _compare_solid(args)
    parts = section_parts(args)
    if args.merge:
        parts = [replace(p, sections=replace(p.sections.merged(), meta=p.sections.meta)) for p in parts]
    if args.output and args.output.lower().endswith(".csv"):
        return tables_to_csv([p.sections for p in parts]).rstrip("\n")
    if args.json:
        return json.dumps(sections_document(parts), indent=1, ensure_ascii=False)
    return sections_table(parts)


def _one_tie(part) -> str:
    """The part's one kind of end-face tie, which the solid twist test compares with (both alike)."""
    start, end = part.interface
    if start != end:
        raise ModelError(
            "compares a solid tied alike at both end faces",
            field="interface",
            value=f"start {start}, end {end}",
            valid='"rigid" or "average" for both faces with --compare-solid',
        )
    return start


def _compare_solid(args) -> str:
    """``sections MODEL --compare-solid``: each part's 1D model against its solid; ``-o FILE.csv`` the
    tables corrected to the solids' torsional stiffness."""
    from pathlib import Path

    from ...analysis.solidcompare import compare_solid
    from ...sections.table import tables_to_csv

    if Path(args.source).suffix.lower() != ".toml":
        raise ModelError(
            "compares the parts of a model file",
            field="--compare-solid",
            value=str(args.source),
            valid="a TOML model file (its parts' materials and geometry)",
        )
    results = [
        compare_solid(
            p.sections,
            p.solid_mesh,
            p.material,
            interface=_one_tie(p),
            modes=args.solid_modes,
            cache=p.solid_cache,
        )
        for p in section_parts(args)
    ]
    if args.output and args.output.lower().endswith(".csv"):
        return tables_to_csv([r.corrected_table() for r in results]).rstrip("\n")
    if args.json:
        return json.dumps([r.to_dict() for r in results], indent=1, ensure_ascii=False)
    return "\n\n".join(r.text() for r in results)


def body(args) -> str:
    """``flexshaft body FILE``: read an exported body with every check the reader makes; what it holds."""
    import json

    from ...exports.bodies import read_flexible_body

    got = read_flexible_body(args.file)
    b, meta = got.body, got.metadata
    doc = {
        "file": str(got.path),
        "format": meta.get("format"),
        "version": meta.get("version"),
        "name": b.name,
        "dofs": b.dofs,
        "boundary_x_m": [float(x) for x in b.boundary_x],
        "coordinates": int(b.K.shape[0]),
        "fixed_interface_modes": int(b.fixed_interface_hz.size - b.n_residual),
        "residual_vectors": int(b.n_residual),
        "free_hz": [float(f) for f in b.free_hz],
        "damping_ratios": [float(z) for z in b.damping_ratios],
        "material": got.material,
        "checks": "checksums match; K, M, C symmetric; M positive definite; K and C positive "
        "semidefinite with the body's rigid-body modes; free_hz those of K and M",
    }
    if args.json:
        return json.dumps(doc, indent=2)
    material = got.material["name"] if got.material else "not recorded"
    return "\n".join(
        [
            f"{got.path}: flexible body {b.name!r} ({b.dofs}), format version {meta.get('version')}",
            f"boundary nodes at x = {', '.join(f'{x:g}' for x in b.boundary_x)} m; "
            f"{doc['coordinates']} coordinates: {doc['fixed_interface_modes']} fixed-interface modes, "
            f"{b.n_residual} residual vectors; material {material}",
            "free-free modes, Hz: " + " ".join(f"{f:.2f}" for f in b.free_hz),
            "damping ratio per free-free mode, %: " + " ".join(f"{100 * z:.3f}" for z in b.damping_ratios),
            f"checks: {doc['checks']}",
        ]
    )


def _modes_options(p) -> None:
    # the library's numbers as written here (analysis.modal.DEFAULT_LISTED, analysis.convergence.REFINEMENTS:
    # tests/flexshaft/test_cli_help.py holds them equal): the parser is built without numpy
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--mesh-check",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="estimate each mode's distance from mesh convergence: the shaft elements each cut into 2 and "
        f"into 4, solved again and extrapolated (Richardson) (default: on up to {MESH_CHECK_AUTO_DOFS} DOFs)",
    )
    p.add_argument(
        "--inertia",
        choices=("consistent", "lumped"),
        help="how shaft inertia is spread (overrides the model file)",
    )
    p.add_argument(
        "--modes",
        dest="count",
        type=whole("--modes", 1),
        metavar="N",
        help="how many of the lowest modes, rigid-body modes included (default: those up to --max-hz or "
        "the model file's [model] max_hz, else the lowest 20)",
    )
    renamed(p, "--count", "--modes", "count", type=whole("--count", 1))
    p.add_argument(
        "--max-hz", type=hz("--max-hz", positive=True), metavar="F", help="list only the modes up to F Hz"
    )
    plot_option(p, "draw the shapes of the lowest elastic modes listed (at most six) to FILE")
    p.add_argument(
        "--uff",
        metavar="FILE",
        help="also write the modes listed as a universal file (FILE.uff or .unv: units 164, the stations"
        " as nodes 2411, each mode 55) for modal-test software (the uff extra)",
    )
    table_options(p, "the table of modes")


def _demo_options(p) -> None:
    plot_option(p, "draw the shapes of the lowest elastic modes (at most six) to FILE")
    json_option(p)
    table_output_option(
        p,
        "the test bench's table of modes",
        "; or a folder, -o DIR/ (a trailing /): the test bench's HTML report",
    )
    force_option(p, "allow -o to replace an existing file (or report)")


def _run_modes(args) -> str:
    return modes(load(args, args.model), args)


def _run_demo(args):
    from ..outputs import to_folder

    source = f"<built-in {DEMO_MODEL}>"
    if to_folder(args):  # demo -o DIR/: the report of the built-in test bench
        with demo_file() as model:
            return Written(write_report(model, args.output, args.force, args))
    return modes(demo_model(source), args)


def _twist_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--torque", type=float, default=1000.0, help="torque at the --at station, N·m (default 1000)"
    )
    p.add_argument("--clamp", metavar="STATION", help="station clamped (default: the driving end)")
    p.add_argument("--at", metavar="STATION", help="station the torque is applied at (default: the far end)")
    renamed(p, "--load", "--at", "at")
    p.add_argument(
        "--target",
        action="append",
        default=[],
        metavar="PART=N·m/rad",
        help="also give the Young's modulus (or dimension scale) that makes PART this stiff; repeatable",
    )
    plot_option(p, "write the twist-along-the-shaft plot to FILE")
    p.add_argument(
        "--view",
        metavar="FILE.png",
        help="write the twisted shaft in 3D, coloured by shear stress, to this PNG",
    )
    table_options(p, "the twist-test table (stiffness per part, twist per station)")


def _sections_options(p) -> None:
    p.add_argument("source", help="TOML model file, or a part file")
    p.add_argument(
        "--material",
        default="steel",
        help="material of a part file (built-in: steel; for others use a model file)",
    )
    p.add_argument("--unit", help="length unit of a mesh file: m, mm, cm or in")
    p.add_argument("--merge", action="store_true", help="join neighbouring intervals with equal sections")
    p.add_argument(
        "--compare-solid",
        action="store_true",
        help="each part's 1D model against its solid mesh: stiffness, free-free modes, the extra length "
        "each diameter step implies (the solid extra); -o FILE.csv writes the tables corrected to the "
        "solids' torsional stiffness",
    )
    p.add_argument(
        "--modes",
        dest="solid_modes",
        type=whole("--modes", 0),
        default=4,
        metavar="N",
        help="free-free modes compared with --compare-solid (default 4; 0: stiffness only)",
    )
    renamed(p, "--solid-modes", "--modes", "solid_modes", type=whole("--solid-modes", 0))
    table_options(p, "the sections table", "; PATH.csv the section tables as CSV")


def _report_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    output_option(
        p,
        "DIR",
        "the report's folder: index.html and results.json (new, empty, or this model's earlier report, "
        "with --force)",
        required=True,
    )
    force_option(p, "allow replacing an existing report in DIR")


def _view_options(p) -> None:
    p.add_argument("model", help="TOML model file")
    p.add_argument(
        "--mode", type=whole("--mode", 0), required=True, help="the mode, as `flexshaft modes` numbers it"
    )
    p.add_argument(
        "--color",
        choices=("twist", "stress", "energy"),
        default="twist",
        help="surface colour: twist (mrad), shear stress (MPa) or strain-energy density, at 1 mrad",
    )
    p.add_argument(
        "--scale", type=float, default=0.3, help="drawn twist of the largest station rotation (rad)"
    )
    p.add_argument(
        "--frames", type=whole("--frames", 2, "frames"), default=30, help="GIF frames per period (30)"
    )
    output_option(
        p,
        "FILE",
        "write the mode's view: " + ", ".join(f"FILE{s} {w}" for s, w in VIEW_FILES.items()),
        required=True,
    )
    force_option(p, "allow -o to replace an existing file")


def _body_options(p) -> None:
    p.add_argument("file", help="PART.npz|.json|.mat|.op4|.pch, as `flexshaft reduce` writes it")
    json_option(p, "a summary")
    p.set_defaults(output=None, force=False)


COMMANDS = (
    Command(
        "modes",
        "natural frequencies, damping and mode shapes of a model file",
        _modes_options,
        _run_modes,
        files={"-o": TABLE, "--plot": PLOT, "--uff": UFF},
        table=True,
    ),
    Command(
        "demo",
        "modes of the built-in Customer 1 test bench",
        _demo_options,
        _run_demo,
        files={"-o": TABLE, "--plot": PLOT},  # -o: or a folder, DIR/: the report
        source=None,
        table=True,
        reads_model=False,
    ),
    Command(
        "twist",
        "applied-torque twist test: each part's torsional stiffness and the twist along the shaft",
        _twist_options,
        twist,
        files={"-o": TABLE, "--plot": PLOT, "--view": {".png": "PNG only: the 3D view is a raster picture"}},
        table=True,
    ),
    Command(
        "sections",
        "section table, torsional stiffness and inertia of CAD and "
        "dimensioned parts (a model file) or of one STEP/BREP/STL/OBJ/PLY file",
        _sections_options,
        sections,
        files={"-o": TABLE | {".csv": "the section tables as CSV"}},
        source="source",
        locate=False,  # its errors name the part file themselves
        table=True,
    ),
    Command(
        "report",
        "one self-contained HTML report of a model: parts, modes, pictures",
        _report_options,
        report,
    ),
    Command(
        "view",
        "one mode in 3D on the drivetrain's surface: a PNG, an animated GIF, or an HTML page to turn "
        "in a browser",
        _view_options,
        view,
        files={"-o": VIEW_FILES},
    ),
    Command(
        "body",
        "check an exported flexible body (checksums, physics) and summarise it",
        _body_options,
        body,
        source="file",
        locate=False,  # the reader's errors name the body file (or its sidecar)
        table=True,
        reads_model=False,
    ),
)

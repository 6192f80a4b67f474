"""The commands about a model itself: ``modes``, ``demo``, ``twist``, ``sections``, ``report``, ``view``
and ``body`` (an exported flexible body read back)."""

from __future__ import annotations

import json
from importlib import resources

from ..errors import ModelError
from .common import DEMO_MODEL, MESH_CHECK_AUTO_DOFS, emit, load, write_plot

__all__ = [
    "mesh_check",
    "modes",
    "twist",
    "report",
    "write_report",
    "demo_file",
    "demo_model",
    "view",
    "sections",
    "body",
]


def mesh_check(result, asked: bool | None):
    """The mesh-convergence estimate: when asked, or by default on models up to MESH_CHECK_AUTO_DOFS."""
    if asked is False or (asked is None and result.model.n_dof > MESH_CHECK_AUTO_DOFS):
        return None
    from ..analysis.convergence import mesh_convergence

    try:
        return mesh_convergence(result)
    except ModelError:
        if asked:
            raise  # asked for explicitly: say why it cannot be done
        return None  # the doubled mesh is over a budget or a guard: the modes themselves stand


def modes(drivetrain, args) -> str:
    from ..analysis.modal import listing_modes
    from ..validation import check_real

    count = getattr(args, "count", None)
    max_hz = getattr(args, "max_hz", None)
    if max_hz is not None:
        max_hz = check_real(max_hz, "--max-hz", "Hz", lo=0.0, lo_open=True)
    else:
        max_hz = drivetrain.max_hz  # the model file's range of interest lists its modes
    try:
        # --count N, else the modes up to max_hz, else the lowest 20: never every mode of a fine mesh
        result = listing_modes(drivetrain, count, max_hz, inertia_model=getattr(args, "inertia", None))
    except ModelError as err:
        if count is None or err.field != "count":
            raise
        # named as the option (as sensitivity and sweep name --modes)
        raise ModelError(err.message, field="--count", value=err.value, valid=err.valid) from None
    mesh = mesh_check(result, getattr(args, "mesh_check", None))
    if args.json:
        doc = result.to_dict(max_hz=max_hz, mesh=mesh, count=count)
        return json.dumps(doc, indent=1, ensure_ascii=False)
    return result.table(max_hz=max_hz, mesh=mesh, count=count)


def twist(args) -> str:
    from ..analysis.twist import stiffness_target, twist_test

    drivetrain = load(args, args.model)
    result = twist_test(drivetrain, args.torque, clamp=args.clamp, load=args.load)
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
        from ..views.plots import twist_figure

        write_plot(args.plot, twist_figure(result), args.force)
    if args.view:
        from ..views.render import twist_png

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
    from ..study import run_report
    from ..views.progress import ProgressBar

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


def demo_file():
    """The built-in test bench's model file (a context manager: a real file while it is open)."""
    return resources.as_file(resources.files("flexshaft.data").joinpath(DEMO_MODEL))


def demo_model(source: str):
    from ..input.modelfile import loads_model

    text = resources.files("flexshaft.data").joinpath(DEMO_MODEL).read_text(encoding="utf-8")
    return loads_model(text, source=source)


def view(args) -> str:
    from ..analysis.modal import default_count, modal_analysis
    from ..model.assembly import assemble
    from ..views import render

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
        from ..views.webview import mode_html

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

    from ..elements.materials import BUILTIN_MATERIALS
    from ..model.components import Shaft
    from ..views.progress import ProgressBar

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
    from ..input.cad import cad_sections

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

    from ..model.describe import sections_document, sections_table
    from ..sections.table import tables_to_csv

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

    from ..analysis.solidcompare import compare_solid
    from ..sections.table import tables_to_csv

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

    from ..exports.bodies import read_flexible_body

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

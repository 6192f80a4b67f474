"""The package layout holds: flexshaft's stages import only earlier ones, nothing imports in a cycle,
no module reaches for another's private names, geometry uses only flexshaft's seam, and the cheap
imports (``import flexshaft``, ``import geometry.slicing``) stay cheap.

The import graph is read from the source with ``ast`` (nothing is imported), so every import counts,
also those inside functions. An edge goes to the module named: ``import a.b`` -> ``a.b``;
``from a import b`` -> ``a.b`` when that is a module, else ``a`` (a package's ``__init__``);
``from flexshaft import Name`` (the lazy facade) -> the module ``flexshaft._EXPORTS`` maps Name to.
The implicit import of parent packages is not an edge (it runs no code of the importer's stage).
"""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from dataclasses import dataclass
from functools import cache

import pytest

from tests.conftest import ROOT

PACKAGES = ("flexshaft", "geometry")

# flexshaft's stages in data-flow order (flexshaft/__init__.py); a module may import its own stage,
# earlier ones, and the base (stage 0) from anywhere.
STAGES = {
    "flexshaft.errors": 0,
    "flexshaft.validation": 0,
    "flexshaft.version": 0,
    "flexshaft.data": 0,  # package data only (the demo model files), no code
    "flexshaft.system": 0,  # OS-facing safety: inputs, limits, nesting, atomic writes, isolation, threads
    "flexshaft.sections": 1,
    "flexshaft.linalg": 1,
    "flexshaft.elements": 2,
    "flexshaft.parts": 3,
    "flexshaft.reduction": 4,
    "flexshaft.model": 5,
    "flexshaft.input": 5.5,  # model files, units, CAD and caches: builds the model, runs no analysis
    "flexshaft.measurement": 6,  # recordings, spectra, SSI/FDD identification, pairing with a model's modes
    "flexshaft.views": 6.5,  # draw what they are given (model and measurement types); import no analysis
    "flexshaft.analysis": 7,  # every result: to_dict(), table(), plot() drawing through views
    "flexshaft.exports": 8,  # flexible bodies and linear systems for other tools
    "flexshaft.study": 8.5,  # the whole study: calls every stage's functions, writes one report
    "flexshaft.cli": 9,
    "flexshaft.__main__": 9,  # python -m flexshaft: the CLI
}
# geometry is the CAD side; of flexshaft it may use only these (and their submodules).
GEOMETRY_MAY_IMPORT = (
    "flexshaft.errors",
    "flexshaft.validation",
    "flexshaft.sections",
    "flexshaft.elements.tetmesh",  # the tet mesh type the mesher returns
    "flexshaft.system.atomic",
    "flexshaft.system.inputs",
    "flexshaft.system.limits",
    "flexshaft.system.isolate",  # gmsh runs in a forked child, as the measured-file readers' libraries do
)
# geometry sits after the section table: only stages after flexshaft.sections may import it.
GEOMETRY_STAGE = 1.5


@dataclass(frozen=True)
class Import:
    importer: str  # dotted module name
    path: str  # file, relative to the repository
    line: int
    target: str  # dotted module name (internal modules resolved as described above)
    names: tuple[str, ...]  # the names of a `from ... import`, else ()

    def where(self) -> str:
        return f"{self.path}:{self.line} ({self.importer} -> {self.target})"


def _module_name(path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@cache
def modules() -> dict[str, object]:
    """Every module of flexshaft/ and geometry/: dotted name -> path."""
    return {_module_name(p): p for pkg in PACKAGES for p in sorted((ROOT / pkg).rglob("*.py"))}


@cache
def facade_exports() -> dict[str, str]:
    """flexshaft/__init__.py's lazy map: public name -> defining module (dotted)."""
    tree = ast.parse((ROOT / "flexshaft" / "__init__.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "_EXPORTS" for t in targets):
                return {k: f"flexshaft.{v}" for k, v in ast.literal_eval(node.value).items()}
    raise AssertionError("flexshaft/__init__.py has no _EXPORTS map")


def _is_package(name: str) -> bool:
    return modules()[name].name == "__init__.py"


def _resolve_from(importer: str, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module
    base = importer.split(".")
    if not _is_package(importer):
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


@cache
def imports() -> tuple[Import, ...]:
    found = []
    mods = modules()
    for name, path in mods.items():
        rel = str(path.relative_to(ROOT))
        for node in ast.walk(ast.parse(path.read_text(), filename=rel)):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    found.append(Import(name, rel, node.lineno, alias.name, ()))
            elif isinstance(node, ast.ImportFrom):
                base = _resolve_from(name, node)
                if base == "flexshaft" and name != "flexshaft":
                    # the lazy facade: the edge goes where the name really comes from
                    exports = facade_exports()
                    for alias in node.names:
                        target = exports.get(alias.name, "flexshaft")
                        found.append(Import(name, rel, node.lineno, target, (alias.name,)))
                    continue
                submodules = [a.name for a in node.names if f"{base}.{a.name}" in mods]
                others = tuple(a.name for a in node.names if f"{base}.{a.name}" not in mods)
                for sub in submodules:
                    found.append(Import(name, rel, node.lineno, f"{base}.{sub}", ()))
                if others or not submodules:
                    found.append(Import(name, rel, node.lineno, base, others))
    return tuple(found)


def internal(imp: Import) -> bool:
    return imp.target in modules()


def stage(module: str) -> float | None:
    if module.split(".")[0] == "geometry":
        return GEOMETRY_STAGE
    for prefix, s in STAGES.items():
        if module == prefix or module.startswith(prefix + "."):
            return s
    return None


# --- the rules: each returns its violations as readable strings --------------------------------------


def cycles() -> list[str]:
    """Strongly connected components of the internal import graph (Tarjan), each with its edges."""
    graph: dict[str, dict[str, Import]] = {m: {} for m in modules()}
    for imp in imports():
        if internal(imp) and imp.target != imp.importer:
            graph[imp.importer].setdefault(imp.target, imp)
    index, low, on_stack, stack, sccs = {}, {}, set(), [], []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                sccs.append(sorted(scc))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    out = []
    for scc in sorted(sccs):
        members = set(scc)
        # a shortest cycle through the first member, by breadth-first search inside the component
        start, paths = scc[0], {scc[0]: []}
        queue, cycle = [start], None
        while queue and cycle is None:
            v = queue.pop(0)
            for w, imp in sorted(graph[v].items()):
                if w == start:
                    cycle = paths[v] + [imp]
                    break
                if w in members and w not in paths:
                    paths[w] = paths[v] + [imp]
                    queue.append(w)
        steps = " -> ".join(f"{imp.target} ({imp.path}:{imp.line})" for imp in cycle)
        out.append(f"cycle among {len(scc)} modules ({', '.join(scc)}): {start} -> {steps}")
    return out


def stage_violations() -> list[str]:
    out = []
    for imp in imports():
        if imp.importer == "flexshaft" or not internal(imp):
            continue  # the facade only maps names lazily
        if imp.importer.split(".")[0] == "geometry" and imp.target.split(".")[0] == "flexshaft":
            continue  # geometry -> flexshaft is its own rule
        src, dst = stage(imp.importer), stage(imp.target)
        if imp.target == "flexshaft":
            out.append(f"{imp.where()}: imports the lazy facade; import from the defining module")
        elif src is not None and dst is not None and dst > src:
            out.append(f"{imp.where()}: stage {src:g} imports the later stage {dst:g}")
    return out


def private_imports() -> list[str]:
    out = []
    for imp in imports():
        for n in imp.names:
            if n.startswith("_") and not (n.startswith("__") and n.endswith("__")):
                out.append(f"{imp.where()}: imports the private name {n!r} of another module")
    return out


def geometry_imports() -> list[str]:
    out = []
    for imp in imports():
        if imp.importer.split(".")[0] != "geometry" or imp.target.split(".")[0] != "flexshaft":
            continue
        if not any(imp.target == m or imp.target.startswith(m + ".") for m in GEOMETRY_MAY_IMPORT):
            out.append(f"{imp.where()}: geometry may import only {', '.join(GEOMETRY_MAY_IMPORT)}")
    return out


RULES = {
    "no cycles": cycles,
    "stages import only earlier stages": stage_violations,
    "no private names across modules": private_imports,
    "geometry imports only flexshaft's seam": geometry_imports,
}

# Violations in the code as it stands, each pinned by the text its rule reports (strict xfail below:
# once the code is mended the test says so, and the entry goes).
KNOWN: dict[str, dict[str, str]] = {rule: {} for rule in RULES}


def _unnumbered(violation: str) -> str:
    """A violation without its line number: a known one stays known while its file changes around it."""
    return re.sub(r"(\.py):\d+ \(", r"\1 (", violation)


@pytest.mark.parametrize("rule", RULES)
def test_import_rule(rule):
    unexpected = [v for v in RULES[rule]() if _unnumbered(v) not in KNOWN[rule]]
    assert not unexpected, f"{rule}:\n  " + "\n  ".join(unexpected)


KNOWN_CASES = [
    pytest.param(rule, text, marks=pytest.mark.xfail(strict=True, reason=reason), id=f"{rule}: {text}")
    for rule, cases in KNOWN.items()
    for text, reason in cases.items()
]

if KNOWN_CASES:  # (a parametrize over nothing would report a skip)

    @pytest.mark.parametrize("rule, violation", KNOWN_CASES)
    def test_known_violation_is_gone(rule, violation):
        assert violation not in [_unnumbered(v) for v in RULES[rule]()]


def test_the_graph_is_read():
    """Guards the rules against passing vacuously: the reader sees the modules and their imports."""
    mods = modules()
    expected = {"flexshaft", "flexshaft.cli", "flexshaft.reduction.craig_bampton", "geometry.slicing.solid"}
    assert expected <= mods.keys()
    unstaged = [m for m in mods if m != "flexshaft" and stage(m) is None]
    assert not unstaged, f"modules in no stage (add them to STAGES): {unstaged}"
    targets = {(i.importer, i.target) for i in imports()}
    assert ("flexshaft.reduction", "flexshaft.reduction.craig_bampton") in targets  # relative, from .x
    assert ("flexshaft.input.cad", "geometry.slicing") in targets  # inside a function
    assert set(facade_exports().values()) <= set(mods)


# --- what a cheap import loads (fresh interpreters) ---------------------------------------------------


def _loaded_after(statement: str) -> set[str]:
    code = f"import sys, json; {statement}; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    return set(json.loads(out.stdout))


def test_geometry_slicing_loads_no_solver_stage():
    loaded = _loaded_after("import geometry.slicing")
    stages = ("flexshaft.analysis", "flexshaft.model", "flexshaft.reduction")
    solver = sorted(m for m in loaded if any(m == p or m.startswith(p + ".") for p in stages))
    assert not solver, f"import geometry.slicing loaded {solver}"


def test_import_flexshaft_loads_nothing_heavy():
    """The structural cause of a fast ``import flexshaft`` (timed in benchmarks/bench_import.py, target
    0.3 s): it loads none of its submodules but the one-line version module, and neither numpy nor
    scipy."""
    loaded = _loaded_after("import flexshaft")
    ours = sorted(m for m in loaded if m.startswith("flexshaft.") and m != "flexshaft.version")
    heavy_packages = {"numpy", "scipy", "matplotlib", "build123d", "trimesh"}
    heavy = sorted(m for m in loaded if m.split(".")[0] in heavy_packages)
    assert not ours, f"import flexshaft loaded its submodules {ours}"
    assert not heavy, f"import flexshaft loaded {heavy}"


# --- sizes: small modules, small functions ------------------------------------------------------------

#: A module holds one stage's one job: at most this many lines.
MAX_MODULE_LINES = 900
#: A function does one thing: at most about 120 lines (docstring included; a few lines of grace so a
#: longer docstring does not force a split).
MAX_FUNCTION_LINES = 125


def test_modules_and_functions_stay_small():
    too_long = []
    for name, path in modules().items():
        text = path.read_text()
        lines = len(text.splitlines())
        if lines > MAX_MODULE_LINES:
            too_long.append(f"{name}: {lines} lines (at most {MAX_MODULE_LINES})")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    too_long.append(f"{name}.{node.name}: {length} lines (at most {MAX_FUNCTION_LINES})")
    assert not too_long, "split these:\n  " + "\n  ".join(too_long)


def test_file_names_say_one_thing():
    """No two modules of flexshaft/ and geometry/ share a file name (a second common.py or solid.py says
    nothing of what it holds); packages' __init__/__main__ aside."""
    seen: dict[str, list[str]] = {}
    for path in modules().values():
        if path.name not in ("__init__.py", "__main__.py"):
            seen.setdefault(path.name, []).append(str(path.relative_to(ROOT)))
    twice = {n: p for n, p in seen.items() if len(p) > 1}
    assert not twice, f"file names used twice: {twice}"

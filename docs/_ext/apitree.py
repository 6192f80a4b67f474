"""The public API of ``flexshaft`` and ``geometry`` as the reference documents it, and its aliases.

Every module of the two packages (but ``__main__``, which runs the command line when imported) gets a
page; every public name - a module's ``__all__``, or without one the names it defines that do not start
with ``_`` - is documented once, in the module that defines it: a function or class on a page of its
own, a constant on its module's page. A module that re-exports a name (``flexshaft.Drivetrain``,
``geometry.parts.keyway``) lists it with a link to that one page. :func:`public_api` computes this
from the source (``ast``, for where a constant comes from) and the imported modules.

The module pages are written here (``docs/reference/generated/MODULE.rst``, from
``docs/_templates/apimodule.rst``) before autosummary runs, which then writes the function and class
pages they list. Not autosummary's: it finds a module by its name as an attribute of its package
first, and ``flexshaft.reduction.craig_bampton`` is there the function of that name, not the module.

References to a re-exported name (``{class}`flexshaft.Drivetrain``` in a page, a docstring's
``:func:`flexshaft.modal_analysis```) are resolved to the defining page by :func:`resolve_alias`.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
from sphinx.util.rst import escape

PACKAGES = ("flexshaft", "geometry")
SKIPPED = ("__main__",)


@dataclass
class ModuleApi:
    """One module's public names, sorted by what the reference does with them."""

    name: str
    summary: str = ""  # the first paragraph of its docstring
    modules: list[str] = field(default_factory=list)  # submodules (full names)
    functions: list[str] = field(default_factory=list)  # defined here: a page each
    classes: list[str] = field(default_factory=list)
    exceptions: list[str] = field(default_factory=list)
    data: list[str] = field(default_factory=list)  # defined here: on this page
    reexported: list[tuple[str, str]] = field(default_factory=list)  # (name, documented full name)
    adopted: list[tuple[str, str]] = field(default_factory=list)  # (name, where defined): see _adopt


def _module_names(package: str) -> list[str]:
    root = importlib.import_module(package)
    names = [package]
    for info in pkgutil.walk_packages(root.__path__, f"{package}."):
        if info.name.rsplit(".", 1)[-1] not in SKIPPED:
            names.append(info.name)
    return names


def _imported_from(module) -> dict[str, str]:
    """Each name the module binds by ``from X import name``: the full name it comes from."""
    try:
        tree = ast.parse(Path(inspect.getfile(module)).read_text(encoding="utf-8"))
    except (OSError, TypeError):
        return {}
    package = module.__name__ if hasattr(module, "__path__") else module.__name__.rpartition(".")[0]
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[: len(base) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            for alias in node.names:
                found[alias.asname or alias.name] = f"{source}.{alias.name}"
    return found


def _public(module) -> list[str]:
    if hasattr(module, "__all__"):
        return list(module.__all__)
    defined = []
    for name, value in vars(module).items():
        if name.startswith("_") or inspect.ismodule(value):
            continue
        if getattr(value, "__module__", module.__name__) == module.__name__:
            defined.append(name)
    return defined


def _origin(module, name: str, value, imported: dict[str, str]) -> str | None:
    """The full name of where ``name`` is defined, when not in ``module`` itself; None when it is."""
    if (inspect.isclass(value) or inspect.isfunction(value)) and value.__module__ != module.__name__:
        return f"{value.__module__}.{value.__qualname__}"
    if name in imported or (name in getattr(module, "_EXPORTS", {})):
        if name in imported:
            source = imported[name].rpartition(".")[0]
        else:  # flexshaft's lazy table: name -> module
            source = f"{module.__name__}.{module._EXPORTS[name]}"
        return _follow(source, imported[name].rpartition(".")[2] if name in imported else name)
    return None


def _follow(module_name: str, name: str) -> str:
    """Where ``module_name.name`` is finally defined (following re-exports)."""
    try:
        module = importlib.import_module(module_name)
    except ImportError:  # ``from .pkg import submodule``
        return f"{module_name}.{name}"
    value = getattr(module, name)
    if inspect.ismodule(value):
        return value.__name__
    origin = _origin(module, name, value, _imported_from(module))
    return origin or f"{module_name}.{name}"


def _summary(module) -> str:
    """The docstring's first paragraph, on one line (whole: a cut could split its markup)."""
    return " ".join((inspect.getdoc(module) or "").split("\n\n")[0].split())


def _kind(value) -> str:
    if inspect.isclass(value):
        return "exceptions" if issubclass(value, BaseException) else "classes"
    if callable(value) and not inspect.isclass(value) and hasattr(value, "__qualname__"):
        return "functions"
    return "data"


def public_api(packages=PACKAGES) -> dict[str, ModuleApi]:
    """Every documented module's :class:`ModuleApi`, by full module name."""
    api: dict[str, ModuleApi] = {}
    for package in packages:
        for name in _module_names(package):
            module = importlib.import_module(name)
            entry = api.setdefault(name, ModuleApi(name, _summary(module)))
            parent = name.rpartition(".")[0]
            if parent in api:
                api[parent].modules.append(name)
            imported = _imported_from(module)
            for member in _public(module):
                value = getattr(module, member)
                if inspect.ismodule(value):
                    continue  # a submodule: listed as one
                origin = _origin(module, member, value, imported)
                if origin is None:
                    getattr(entry, _kind(value)).append(member)
                else:
                    entry.reexported.append((member, origin))
    _adopt(api)
    for entry in api.values():
        for names in (entry.functions, entry.classes, entry.exceptions, entry.data, entry.reexported):
            names.sort()
    return api


def _adopt(api: dict[str, ModuleApi]) -> None:
    """A name exported from a module that does not list it where it is defined (``AnnulusProperties``:
    in ``flexshaft.sections``' ``__all__``, not in ``flexshaft.sections.table``'s) is documented by the
    shallowest module that exports it; the others link there."""
    kinds = ("functions", "classes", "exceptions", "data")
    documented = {f"{m.name}.{n}" for m in api.values() for k in kinds for n in getattr(m, k)}
    home: dict[str, str] = {}
    for entry in sorted(api.values(), key=lambda m: (m.name.count("."), m.name)):
        kept = []
        for name, origin in entry.reexported:
            if origin in documented or origin in api:
                kept.append((name, origin))
            elif origin in home:
                kept.append((name, home[origin]))
            else:
                home[origin] = f"{entry.name}.{name}"
                getattr(entry, _kind(getattr(importlib.import_module(entry.name), name))).append(name)
                entry.adopted.append((name, origin))
        entry.reexported = kept


def aliases(api: dict[str, ModuleApi]) -> dict[str, str]:
    """Each re-exported full name (and each adopted name's own) and the full name it is documented as."""
    found = {f"{m.name}.{name}": origin for m in api.values() for name, origin in m.reexported}
    found.update({origin: f"{m.name}.{name}" for m in api.values() for name, origin in m.adopted})
    return found


def _underline(title: str, line: str = "=") -> str:
    return f"{title}\n{line * len(title)}"


def write_pages(app) -> None:
    """``builder-inited`` (before autosummary): each module's page, rewritten only when it changes."""
    api = public_api(app.config.api_packages)
    app.env.api_aliases = aliases(api)
    loader = jinja2.FileSystemLoader(str(Path(app.confdir) / "_templates"))
    environment = jinja2.Environment(loader=loader, keep_trailing_newline=True)
    environment.filters.update(escape=escape, underline=_underline)
    template = environment.get_template(app.config.api_template)
    folder = Path(app.confdir) / app.config.api_folder
    folder.mkdir(parents=True, exist_ok=True)
    added = False
    for name, module in api.items():
        path = folder / f"{name}.rst"
        text = template.render(fullname=name, m=module, api=api)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            added = added or not path.is_file()
            path.write_text(text, encoding="utf-8")
    # pages of a module that is gone (renamed, removed) or of a name no module defines any more: an
    # autodoc page of something that cannot be imported fails the build
    pages = set(api)
    for name, module in api.items():
        pages.update(f"{name}.{n}" for n in (*module.functions, *module.classes, *module.exceptions))
        pages.update(f"{name}.{n}" for n, _ in module.adopted)
    for page in folder.glob("*.rst"):
        if page.stem not in pages and not any(page.stem.startswith(f"{p}.") for p in pages if p not in api):
            page.unlink()
    if added:  # Sphinx listed the sources before this ran: autosummary reads that list next
        app.env.find_files(app.config, app.builder)


def resolve_alias(app, env, node, contnode):
    """``missing-reference``: a Python reference to a re-exported name resolves to its definition."""
    if node.get("refdomain") != "py":
        return None
    origin = getattr(env, "api_aliases", {}).get(node.get("reftarget", ""))
    if origin is None:
        return None
    domain = env.get_domain("py")
    for reftype in (node["reftype"], "obj"):  # {func} on a callable class instance: found as obj
        found = domain.resolve_xref(env, node["refdoc"], app.builder, reftype, origin, node, contnode)
        if found is not None:
            return found
    return None


def _bases(app, name, obj, options, bases: list) -> None:
    """``autodoc-process-bases``: a class's bases as shown, but ``object`` (every class has it)."""
    bases[:] = [b for b in bases if b is not object]


def setup(app):
    app.add_config_value("api_packages", PACKAGES, "env")
    app.add_config_value("api_folder", "reference/generated", "env")  # relative to conf.py's folder
    app.add_config_value("api_template", "apimodule.rst", "env")  # in _templates/
    app.connect("builder-inited", write_pages, priority=400)  # autosummary's runs at 500
    app.connect("missing-reference", resolve_alias)
    app.connect("autodoc-process-bases", _bases)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

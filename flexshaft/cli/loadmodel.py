"""The model a command works on: a model file read with the command line's trust, cache and progress
settings, or the built-in test bench of ``flexshaft demo``."""

from __future__ import annotations

from importlib import resources

__all__ = ["DEMO_MODEL", "load", "demo_file", "demo_model"]

DEMO_MODEL = "customer1.toml"


def load(args, path, *, mesh_solids: bool = False):
    """The model file, with the command line's trust, cache and progress settings (a solid part's
    reduction shows its progress through the bar the loader hands it).

    A model with ``[model] max_hz`` comes meshed for it (:func:`flexshaft.mesh_for_range`): each
    shaft's and CAD part's elements chosen so every mode below max_hz is within 1 %.
    """
    from ..analysis.convergence import meshed_for_own_range
    from ..input.modelfile import load_model
    from ..views.progress import ProgressBar

    # [model] max_hz: every command works on the mesh that range needs
    return meshed_for_own_range(
        load_model(
            path,
            progress=ProgressBar,
            allow_code=args.allow_code,
            use_cache=not args.no_cache,
            mesh_solids=mesh_solids,
        )
    )


def demo_file():
    """The built-in test bench's model file (a context manager: a real file while it is open)."""
    return resources.as_file(resources.files("flexshaft.data").joinpath(DEMO_MODEL))


def demo_model(source: str):
    """The built-in Customer 1 test bench, its errors located at ``source``."""
    from ..input.modelfile import loads_model

    text = resources.files("flexshaft.data").joinpath(DEMO_MODEL).read_text(encoding="utf-8")
    return loads_model(text, source=source)

"""Abuse cases of the CLI, one module per kind of finding; the error catalogue runs them all.

Each module defines ``CASES``: a dict from a readable name to a :class:`Case`. A case lays out its
files in a fresh folder (the current directory when it runs) and returns the command line. The
catalogue test (``tests/flexshaft/test_error_catalogue.py``) runs every case in-process and checks:

- the exit code (2 for a refusal, 0 where the input is valid);
- a refusal is exactly one stderr line, nothing on stdout, naming what ``says`` lists;
- a valid run prints nothing on stderr;
- no file that existed before the run changed (inputs are never touched), and no temporary file is
  left behind.

The slow test ``test_found_cases_under_a_memory_limit`` runs the same cases as separate processes
under a 4 GB address-space limit, each within its ``budget_s``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Case:
    """One command a user could type, with what must come of it.

    Parameters
    ----------
    setup : callable
        ``setup(folder) -> argv``: writes the case's files into ``folder`` (a new, empty directory,
        also the working directory) and returns the arguments after ``flexshaft``.
    exit : int
        The expected exit code: 2 (refused, one error line) or 0 (valid: results, empty stderr).
    says : tuple of str
        Substrings the error line must contain (the option or field, the word ``valid``).
    budget_s : float
        Wall-clock seconds the case may take as its own process under a 4 GB address-space limit.
    slow : bool
        Run only in the slow step (the case computes for seconds before its refusal).
    """

    setup: Callable[[Path], list[str]]
    exit: int = 2
    says: tuple[str, ...] = field(default_factory=tuple)
    budget_s: float = 30.0
    slow: bool = False


def all_cases() -> dict[str, Case]:
    """Every module's cases, named ``module: case``."""
    import importlib
    import pkgutil

    cases: dict[str, Case] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        for name, case in getattr(module, "CASES", {}).items():
            cases[f"{info.name}: {name}"] = case
    return cases

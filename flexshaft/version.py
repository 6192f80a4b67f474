"""flexshaft's version, in one place (pyproject.toml's must match it: a test checks)."""

__version__ = "0.1.0"

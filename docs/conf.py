"""Sphinx configuration of flexshaft's documentation site.

Built offline, warnings as errors (``pip install -e '.[docs]'``, then from the repository's root)::

    python -m sphinx -W --keep-going -j 1 -b html docs docs/_build/html

Pages are MyST Markdown; the API reference is generated from the docstrings (numpydoc) by autosummary
through ``_templates/autosummary/`` and ``_ext/apitree.py``; the gallery runs ``examples/`` at build
time (sphinx-gallery, settings in ``gallery_conf.py``); math is rendered by the KaTeX in
``_static/katex/`` (``_ext/katex_math.py``). Nothing is fetched at build or view time: no intersphinx,
no CDN, the theme's fonts bundled.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path[:0] = [str(DOCS / "_ext"), str(DOCS)]  # the local extensions; gallery_conf beside this file

from gallery_conf import sphinx_gallery_conf  # noqa: E402  (read by sphinx_gallery.gen_gallery)

# sphinx-gallery's computation-times pages load DataTables and jQuery from CDNs: off unless the
# gallery's settings say otherwise (the site fetches nothing; .ci/run refuses pages that would).
sphinx_gallery_conf.setdefault("write_computation_times", False)

from flexshaft.version import __version__  # noqa: E402

project = "flexshaft"
author = "flexshaft contributors"
copyright = "flexshaft contributors, MIT licence"  # noqa: A001 (Sphinx's name)
version = release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "katex_math",  # local: the vendored KaTeX renders the math (no CDN)
    "apitree",  # local: the API's module pages, and links to re-exported names
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_static", "_templates", "_ext"]
templates_path = ["_templates"]

# MyST: $...$ and $$...$$ math, ::: fences, and anchors for headings down to ### so a page can link
# [a section](other.md#its-title).
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# The API reference: one page per module (written by _ext/apitree.py into reference/generated/), per
# function and per class (autosummary, from those pages; reference/api.rst starts it).
autosummary_generate = True
autodoc_typehints = "none"  # the numpydoc Parameters sections give each type with its unit
autodoc_member_order = "bysource"
# Class pages list their methods and properties through autodoc's :members: (the class template);
# numpydoc's own member tables would repeat them.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

html_theme = "pydata_sphinx_theme"
html_title = f"flexshaft {release}"
html_static_path = ["_static"]
# Light, dark or the reader's setting: without it the theme logs an error on a first visit.
html_context = {"default_mode": "auto"}
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
}
html_css_files = ["flexshaft.css"]
html_show_sourcelink = False

"""The gallery's sphinx-gallery configuration: ``docs/conf.py`` imports ``sphinx_gallery_conf`` from here.

The gallery is the scripts of ``examples/``, run when the site is built, their printed output and their
figures shown under each block of code. The examples that take minutes are shown but not run:
:data:`NOT_EXECUTED` names them with the reason, and each says so in its own text
(``tests/test_examples.py`` checks that every example is run or named there).

This module imports nothing from Sphinx or sphinx-gallery at import time, so the tests read it without
them; the scraper below is given to sphinx-gallery by name (``"gallery_conf.scrape_figures"``), which needs
``docs/`` on ``sys.path`` (``docs/conf.py`` puts it there) and keeps the configuration picklable.
"""

import re
import shutil
from pathlib import Path

#: The examples shown with their code but not run at build time, and why.
NOT_EXECUTED = {
    "customer2_slip.py": (
        "runs some 400 stepped-sine time runs with a slipping coupling and two fits: about 50 s"
    ),
    "bench_recordings.py": (
        "writes 31 MB of recordings of the three set-ups into examples/recordings/ (about 3 s)"
    ),
    "solid_testbench.py": (
        "meshes the bench's three PTSS parts into solids (~490 000 DOFs) and reduces them: "
        "about 1.5 minutes from a cold cache"
    ),
}

#: The examples run at build time: every ``.py`` of ``examples/`` but those of :data:`NOT_EXECUTED`
#: (sphinx-gallery searches this in each example's full path).
FILENAME_PATTERN = r"[/\\](?!(?:" + "|".join(re.escape(name) for name in NOT_EXECUTED) + r")$)[^/\\]+\.py$"

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": FILENAME_PATTERN,
    # Each example's page offers its script, its notebook and its model files (:download: roles in its
    # text); a zip of every script alone would lack the model files they read.
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    # flexshaft's figures first: pyplot's are still open then (the matplotlib scraper closes them), so
    # scrape_figures knows them for pyplot's and leaves them to it.
    "image_scrapers": ("gallery_conf.scrape_figures", "matplotlib"),
    "matplotlib_animations": False,
    # An example that fails fails the build: the gallery shows only what runs.
    "abort_on_example_error": True,
    # Printed output only: the repr of a block's last expression (a written file's path, a figure)
    # says nothing the page does not show.
    "capture_repr": (),
    "show_memory": False,
    # its timing pages load jQuery and DataTables from CDNs: nothing may be fetched off the machine
    "write_computation_times": False,
}

#: What :func:`scrape_figures` has shown of the example being run: the figures (kept, so that their
#: identity stays theirs) and the pictures (path, modification time).
_SHOWN: dict = {"example": None, "figures": [], "pictures": set()}


def _candidates(values):
    """The example's variables, and the Figures in the lists, tuples and dicts among them, in order."""
    from matplotlib.figure import Figure

    for value in values:
        if isinstance(value, list | tuple | dict):
            items = value.values() if isinstance(value, dict) else value
            yield from (item for item in items if isinstance(item, Figure))
        else:
            yield value


def scrape_figures(block, block_vars, gallery_conf) -> str:
    """A sphinx-gallery image scraper for what flexshaft draws: the reST of the block's new pictures.

    flexshaft's plots are matplotlib Figures outside pyplot (the results' ``.plot()`` return them and
    never show them), which sphinx-gallery's matplotlib scraper (pyplot's open figures) does not see; its
    3D stills and browser views are PNG files. After each block this takes every Figure the example's
    variables hold, alone or in a list, tuple or dict (pyplot's own figures aside: the matplotlib scraper
    takes those), and every variable that is the path of a PNG file (a written list of paths is not
    shown again), each the first time it appears, in the order of the variables.

    Parameters
    ----------
    block : sphinx_gallery.py_source_parser.Block
        The block run (unused).
    block_vars : dict
        sphinx-gallery's: ``example_globals``, ``image_path_iterator``, ``src_file``.
    gallery_conf : dict
        sphinx-gallery's configuration (its ``src_dir``).

    Returns
    -------
    str
        The reST of the images, empty without any.
    """
    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    if _SHOWN["example"] != block_vars["src_file"]:
        _SHOWN.update(example=block_vars["src_file"], figures=[], pictures=set())
    images = []
    for value in _candidates(list(block_vars["example_globals"].values())):
        if isinstance(value, Figure):
            if any(value is f for f in _SHOWN["figures"]):
                continue
            _SHOWN["figures"].append(value)
            if value.canvas.manager is not None:  # pyplot's: the matplotlib scraper, run next, takes it
                continue
            image = block_vars["image_path_iterator"].next()
            value.savefig(image)
        elif isinstance(value, Path) and value.suffix.lower() == ".png" and value.is_file():
            key = (str(value.resolve()), value.stat().st_mtime_ns)
            if key in _SHOWN["pictures"]:
                continue
            _SHOWN["pictures"].add(key)
            image = block_vars["image_path_iterator"].next()
            shutil.copyfile(value, image)
        else:
            continue
        images.append(image)
    return figure_rst(images, gallery_conf["src_dir"]) if images else ""

"""sphinx-gallery's settings for the site (docs/conf.py imports ``sphinx_gallery_conf`` from here).

A placeholder until the gallery is written: it reads ``examples/`` but takes no script into the
gallery (``ignore_pattern`` matches every one), so the build runs nothing.
"""

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"^$",  # execute nothing
    "ignore_pattern": r"\.py$",  # and list nothing yet
    "download_all_examples": False,
}

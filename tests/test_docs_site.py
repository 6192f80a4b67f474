"""The built documentation site opens offline in a browser: no script or console error and no request
for anything off the machine, on the landing page, a gallery page and a page of KaTeX math.

The site takes minutes to build (the gallery runs its examples), so these tests read a site built
before them: CI builds it (`.ci/run` step 3) and runs this file with ``FLEXSHAFT_DOCS_HTML`` naming the
output folder; without it they skip and say so.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.browser import NO_BROWSER, page_errors

SITE = os.environ.get("FLEXSHAFT_DOCS_HTML")
pytestmark = pytest.mark.skipif(not SITE, reason="FLEXSHAFT_DOCS_HTML names no built site (.ci/run sets it)")


def _pages() -> list[Path]:
    root = Path(SITE).resolve()  # CI passes a relative folder; the browser needs a file:// address
    gallery = sorted(p for p in (root / "auto_examples").glob("*.html") if p.name != "index.html")
    math = sorted((root / "theory").glob("*.html"))
    return [root / "index.html", root / "auto_examples" / "index.html", gallery[0], *math]


def test_the_site_has_its_sections():
    root = Path(SITE)
    sections = ("getting-started/index", "guide/index", "auto_examples/index", "reference/cli")
    sections += ("theory/index",)
    for page in sections:
        assert (root / f"{page}.html").is_file(), page


@pytest.mark.parametrize("index", range(4))
def test_a_page_opens_offline_without_errors(index):
    pages = _pages()
    if index >= len(pages):
        pytest.skip("fewer pages")
    said = page_errors(pages[index], ms=3000)
    if said is None:
        pytest.skip(NO_BROWSER)
    # "errors:N ... broken:B of I remote:R": nothing failed, every image decoded, nothing off the machine
    assert said.startswith("errors:0 "), (pages[index], said)
    assert " broken:0 " in said and " remote:0" in said, (pages[index], said)

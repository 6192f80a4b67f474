"""Headless Chromium as the tests' reader of the HTML reports (Debian's chromium; CI installs it)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

NO_BROWSER = "no chromium on this machine (Debian's chromium package; CI installs it)"


def broken_images(page: Path) -> str | None:
    """Load ``page`` and count the images Chromium could not decode: ``"broken:N of M"``.

    None when no Chromium is installed. A copy of the page with a probe script beside it is loaded
    (the page itself has no script) and removed again.
    """
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        return None
    probe = page.with_name(page.stem + ".probe.html")
    probe.write_text(
        page.read_text().replace(
            "</body>",
            "<script>window.addEventListener('load', () => { document.title = 'broken:' + "
            "[...document.images].filter(i => !i.naturalWidth).length + ' of ' + document.images.length; });"
            "</script></body>",
        )
    )
    try:
        out = subprocess.run(
            [browser, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom", probe.as_uri()],
            capture_output=True,
            text=True,
            timeout=180,
        )
    finally:
        probe.unlink()
    title = re.search(r"<title>(.*?)</title>", out.stdout)
    assert title is not None, out.stderr[-500:]
    return title.group(1)

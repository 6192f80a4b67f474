"""Headless Chromium as the tests' reader of the HTML reports (Debian's chromium; CI installs it)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

NO_BROWSER = "no chromium on this machine (Debian's chromium package; CI installs it)"


def _browser() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


# Software WebGL (SwiftShader): headless Chromium on a machine without a GPU draws WebGL with it.
WEBGL = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader"]


def screenshot(page: Path, ms: int, size=(1100, 800), fragment: str = ""):
    """The page as headless Chromium draws it ``ms`` of (virtual) time after loading: an RGB array.

    None when no Chromium is installed. ``fragment`` is added to the address (``"#t=0.4"``: the mode
    viewer starts its animation 0.4 s into the period - a moment that does not depend on how long a
    busy machine takes to load the page).
    """
    browser = _browser()
    if browser is None:
        return None
    import matplotlib.image as mpimg

    shot = page.with_name(f"{page.stem}.{ms}ms.png")
    subprocess.run(
        [
            browser,
            "--headless",
            "--no-sandbox",
            *WEBGL,
            f"--window-size={size[0]},{size[1]}",
            f"--virtual-time-budget={ms}",
            f"--screenshot={shot}",
            page.resolve().as_uri() + fragment,
        ],
        capture_output=True,
        timeout=180,
        check=True,
    )
    try:
        return mpimg.imread(shot)[:, :, :3]
    finally:
        shot.unlink()


def page_errors(page: Path, ms: int = 1500, expression: str = "") -> str | None:
    """Run the page for ``ms`` of virtual time; ``"errors:N frames:F overlaps:K broken:B of I remote:R"``
    (script errors, console errors and refused requests; the first viewer's animation clock in ms;
    pairs of viewer labels overlapping on screen; images the browser could not decode, of all;
    requests the page made for anything but its own file and data: URIs - by the browser's resource
    timing, and no name resolves while it runs, so none leaves the machine).
    With ``expression`` (JavaScript) `` probe:VALUE`` follows at the end, its value as JSON (the title
    as the page has it: ``html.unescape`` it). None without a Chromium."""
    browser = _browser()
    if browser is None:
        return None
    probe = page.with_name(page.stem + ".errors.html")
    text = page.read_text()
    hook = (
        "<script>window.__errors=[];window.addEventListener('error',e=>__errors.push(String(e.message)));"
        "document.addEventListener('securitypolicyviolation',e=>__errors.push('refused '+e.blockedURI));"
        "const __ce=console.error;console.error=(...a)=>{__errors.push(a.join(' '));__ce(...a);};</script>"
    )
    # and how many pairs of the viewers' labels overlap on screen (their boxes as the browser laid them out)
    done = (
        "<script>function __overlaps(){const b=[...document.querySelectorAll('.fs-label')].map(e=>"
        "e.getBoundingClientRect());let n=0;for(let i=0;i<b.length;i++)for(let j=0;j<i;j++){"
        "const p=b[i],q=b[j];if(p.left<q.right&&q.left<p.right&&p.top<q.bottom&&q.top<p.bottom)n++;}"
        "return n;}"
        "setTimeout(()=>{const v=(window.flexshaftViewers||[])[0];document.title='errors:'+"
        "__errors.length+' frames:'+(v?Math.round(1000*v.clock):-1)+' overlaps:'+__overlaps()+' broken:'+"
        "[...document.images].filter(i=>!i.naturalWidth).length+' of '+document.images.length+' remote:'+"
        "performance.getEntriesByType('resource').filter(e=>!/^(data|blob|file):/.test(e.name)).length+' '+"
        "__errors.join('|')"
        + (f"+' probe:'+JSON.stringify({expression})" if expression else "")
        + f";}},{ms - 100});</script>"
    )
    # after the opening tag, whatever its attributes (a Sphinx page's body carries some)
    text = re.sub(r"<body[^>]*>", lambda m: m.group(0) + hook, text, count=1)
    probe.write_text(text.replace("</body>", done + "</body>"))
    try:
        out = subprocess.run(
            [
                browser,
                "--headless",
                "--no-sandbox",
                *WEBGL,
                "--window-size=1100,800",
                "--host-resolver-rules=MAP * ~NOTFOUND",  # nothing resolves: no request leaves
                f"--virtual-time-budget={ms}",
                "--dump-dom",
                probe.resolve().as_uri(),
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )
    finally:
        probe.unlink()
    title = re.search(r"<title>(.*?)</title>", out.stdout, re.S)
    assert title is not None, out.stderr[-500:]
    return title.group(1)

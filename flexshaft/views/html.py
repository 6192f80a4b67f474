"""The pieces of flexshaft's HTML reports: escaped text, tables, pictures embedded as data URIs, and
data for the page's scripts (JSON that no name can end or turn into markup)."""

from __future__ import annotations

import base64
import html
import json

__all__ = ["escape", "img", "table", "script_json"]

# Inside <script> the HTML parser looks for "</script" and, after "<!--", for "<script" (which puts
# it in the double-escaped state, where the next "</script>" no longer ends the block: the viewer's
# start line becomes data and never runs). JSON may write any character as \uXXXX, so none of
# "<", ">", "&" is left for the parser to see. These three can stand only inside JSON's strings.
_SCRIPT_SAFE = {ord(c): f"\\u{ord(c):04x}" for c in "<>&"}


def script_json(data) -> str:
    """``data`` as JSON safe anywhere in a page's ``<script>`` (a ``type="application/json"`` block or a
    JavaScript literal): ``<``, ``>``, ``&``, U+2028 and U+2029 written as ``\\u003c`` etc., so no
    name - ``</script>``, ``<!--<script>`` - can end the block or change how the page is parsed;
    ``JSON.parse`` and :func:`json.loads` give every string back as it was."""
    # ensure_ascii: everything past ASCII as \uXXXX too - U+2028/U+2029 (line ends to older
    # JavaScript), the bidirectional controls, and a lone surrogate that UTF-8 could not encode
    return json.dumps(data, separators=(",", ":")).translate(_SCRIPT_SAFE)


def escape(x) -> str:
    """``x`` as text safe in HTML."""
    return html.escape(str(x))


def img(png: bytes, alt: str) -> str:
    """A PNG embedded in the page (a data URI: nothing to fetch, no second file)."""
    data = base64.b64encode(png).decode("ascii")
    return f'<img alt="{escape(alt)}" src="data:image/png;base64,{data}">'


def table(head, rows, cls: str = "") -> str:
    """An HTML table of ``head`` and ``rows``, every cell escaped."""
    th = "".join(f"<th>{escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    c = f' class="{cls}"' if cls else ""
    return f"<table{c}><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"

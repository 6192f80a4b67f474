"""The pieces of flexshaft's HTML reports: escaped tables and pictures embedded as data URIs."""

from __future__ import annotations

import base64
import html

__all__ = ["escape", "img", "table"]


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

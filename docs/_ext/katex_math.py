"""Math in the site's pages rendered in the browser by the KaTeX vendored in ``_static/katex/``.

Sphinx writes math as its MathJax renderer does (``\\(...\\)`` inline and ``\\[...\\]`` displayed, in
elements of class ``math``, numbered equations with their anchors); this renderer reuses those
writers and links, on the pages that have math only, KaTeX, its auto-render script and
``katex_init.js``, which renders each ``.math`` element. Nothing comes from a CDN: a page with math
reads its scripts, stylesheet and fonts from the site itself. A formula KaTeX cannot parse is left
as its source and reported on the browser's console (``console.error``).
"""

from __future__ import annotations

from sphinx.ext.mathjax import html_visit_displaymath, html_visit_math

SCRIPTS = ("katex/katex.min.js", "katex/contrib/auto-render.min.js", "katex_init.js")
STYLESHEET = "katex/katex.min.css"


def _link_katex(app, pagename, templatename, context, doctree) -> None:
    if app.builder.format != "html" or app.builder.math_renderer_name != "katex":
        return
    if context.get("has_maths_elements", False):
        app.builder.add_css_file(STYLESHEET)
        for script in SCRIPTS:  # deferred: run in this order once the page is parsed
            app.builder.add_js_file(script, defer="defer")


def setup(app):
    app.add_html_math_renderer(
        "katex",
        inline_renderers=(html_visit_math, None),
        block_renderers=(html_visit_displaymath, None),
    )
    app.connect("html-page-context", _link_katex)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

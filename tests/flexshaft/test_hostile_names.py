"""Names from files are data: no name breaks a page, runs in it, or reaches a terminal raw (issue 33).

A model's, a component's, a set-up's and a study's name may hold anything TOML can: markup that
ends a script block (``</script>``) or puts the HTML parser in its double-escaped state
(``<!--<script>``), quotes, entities, bidirectional overrides (U+202E, U+2066-2069), terminal escape
sequences (ESC, BEL, the C1 CSI U+009B), NUL and DEL. References: the HTML parser itself (headless
Chromium runs the pages: the viewer starts, no injected code runs, the viewer holds the names as
written), :func:`json.loads` (the pages' data gives the names back), matplotlib's own rule for what
text is mathtext (``Text._preprocess_math``), and Unicode's categories (no control, format or
separator character left in what is printed).
"""

from __future__ import annotations

import html
import json
import re
import unicodedata

import pytest

from flexshaft.cli import main
from flexshaft.errors import CONTROLS, ModelError, shown
from tests.browser import NO_BROWSER, page_errors

# Each name is hostile in several ways at once; \u escapes below are TOML's (the file holds the
# characters themselves).
MODEL_NAME = (
    "M <!--<script> </script><script>window.__pwned=1</script> \"q' &amp; "
    "\u202eevil\u2066x\u2069 \x1b[31mred\x07 nul\x00 csi\x9b del\x7f"
)
MOTOR = "motor <!--<script>"
PART = "part 1 </script><script>window.__pwned=2</script>"
GENERATOR = "gen \u202e\u2028\u2029 &amp; \"q'\x1b]0;title\x07"
SETUP = "set-up <!--<script> \"q' &amp; \u2066x\u2069"
STUDY = "S <!--<script> </script><script>window.__pwned=3</script> \u202e\x1b[2J"


def _toml(s: str) -> str:
    """``s`` as a TOML basic string: every character outside printable ASCII as \\uXXXX."""
    return json.dumps(s)  # JSON's string escapes are TOML's (\\uXXXX, \\", \\\\)


MODEL = f"""
[model]
name = {_toml(MODEL_NAME)}

[[chain]]
name = {_toml(MOTOR)}
type = "rigid"
inertia = 58.10

[[chain]]
name = {_toml(PART)}
type = "shaft"
material = "steel"
segments = [{{length = 0.5, od = 0.1}}]

[[chain]]
name = {_toml(GENERATOR)}
type = "rigid"
inertia = 6.67
"""


@pytest.fixture
def model(tmp_path):
    path = tmp_path / "hostile.toml"
    path.write_text(MODEL)
    return path


def _raw_controls(text: str) -> set[str]:
    """The characters in ``text`` a terminal would act on or reorder by (line ends aside): Unicode's
    control (Cc), format (Cf) and line/paragraph separator (Zl, Zp) categories."""
    return {c for c in text if c != "\n" and unicodedata.category(c) in ("Cc", "Cf", "Zl", "Zp")}


def _json_blocks(page: str) -> list:
    blocks = re.findall(r'<script type="application/json"[^>]*>(.*?)</script>', page, re.S)
    for b in blocks:
        # nothing in a block the HTML parser acts on inside a script: no "<", no ">", no "&"
        assert not set(b) & set("<>&"), b[:200]
    return [json.loads(b) for b in blocks]


# --- pages ---------------------------------------------------------------------------------------------


def test_the_pages_data_gives_every_name_back(model, tmp_path):
    page = tmp_path / "view.html"
    assert main(["view", str(model), "--mode", "1", "-o", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    (data,) = _json_blocks(text)
    assert data["model"] == MODEL_NAME
    assert {d["name"] for d in data["discs"]} == {MOTOR, GENERATOR}  # the rigid inertias, drawn as discs
    assert PART in {label["text"] for label in data["labels"]}
    # the heading and the title: the name, escaped for HTML text and given back by unescaping
    heading = re.search(r"<h1[^>]*>(.*?)</h1>", text, re.S).group(1)
    assert html.unescape(heading) == f"{MODEL_NAME} - mode shapes"
    # the start line is a script of its own after the data, and only our two scripts are in the page
    assert text.count("<script>flexshaftViewer(") == 1
    assert "<script>window.__pwned" not in text  # a name's markup is nowhere markup


def _pages(model, tmp_path) -> dict:
    """The three pages a user opens, each written by the command line."""
    view, report, out = tmp_path / "view.html", tmp_path / "report", tmp_path / "study"
    assert main(["view", str(model), "--mode", "1", "-o", str(view)]) == 0
    assert main(["report", str(model), "-o", str(report)]) == 0
    study = tmp_path / "study.toml"
    study.write_text(
        f"[study]\nname = {_toml(STUDY)}\n\n[[setup]]\nname = {_toml(SETUP)}\nmodel = {_toml(str(model))}\n\n"
        f"[views]\nmodes = [1]\n"
    )
    assert main(["study", str(study), "-o", str(out)]) == 0
    return {"view": view, "report": report / "index.html", "study": out / "index.html"}


@pytest.mark.slow  # three pages written (a report's pictures, a study) and run in Chromium: ~15 s
def test_hostile_names_run_nothing_and_the_viewer_starts_in_a_browser(model, tmp_path, capsys):
    pages = _pages(model, tmp_path)
    capsys.readouterr()
    probe = (
        "[window.__pwned||0,(window.flexshaftViewers||[]).map(v=>v.data.model),"
        "[...document.querySelectorAll('.fs-label')].map(e=>e.textContent)]"
    )
    for kind, page in pages.items():
        told = page_errors(page, 1500, probe)
        if told is None:
            pytest.skip(NO_BROWSER)
        head, _, value = html.unescape(told).partition(" probe:")
        assert head.startswith("errors:0 "), (kind, head)
        frames = int(re.search(r"frames:(-?\d+)", head).group(1))
        assert frames > 0, (kind, head)  # the viewer started: its animation clock ran
        pwned, models, labels = json.loads(value)
        assert pwned == 0, kind  # no script from a name ran
        assert models == [MODEL_NAME], kind  # the viewer holds the name as written
        assert {MOTOR, PART, GENERATOR} <= set(labels), (kind, labels)  # and shows the others so


# --- terminals -----------------------------------------------------------------------------------------


def test_the_one_helper_escapes_exactly_the_controls():
    # The reference is Unicode's character database, not our table: every control (category Cc: C0,
    # DEL, C1), the line and paragraph separators (Zl, Zp), the format characters whose bidirectional
    # class embeds, overrides or isolates (UAX #9's explicit formatting characters), and the three
    # implicit marks - over the Basic Multilingual Plane, where they all are.
    import unicodedata

    explicit = {"LRE", "RLE", "PDF", "LRO", "RLO", "LRI", "RLI", "FSI", "PDI"}
    marks = ("LEFT-TO-RIGHT MARK", "RIGHT-TO-LEFT MARK", "ARABIC LETTER MARK")
    expected = {ord(unicodedata.lookup(name)) for name in marks}
    for c in range(0x10000):
        category, bidi = unicodedata.category(chr(c)), unicodedata.bidirectional(chr(c))
        if category in ("Cc", "Zl", "Zp") or (category == "Cf" and bidi in explicit):
            expected.add(c)
    assert CONTROLS == expected
    for c in map(chr, expected):
        assert shown(c) == f"\\u{ord(c):04x}"
        assert json.loads(f'"{shown(c)}"') == c  # the escape is JSON's: a document keeps its meaning
    text = "N·m² Größe 扭转 ταλάντωση"  # anything else, as it is
    assert shown(text) == text
    assert shown("a\nb\tc", keep="\n\t") == "a\nb\tc" and shown("a\nb") == "a\\u000ab"


def test_an_error_line_escapes_a_name_and_keeps_it_for_programs():
    err = ModelError("must be > 0", component=f"chain[2] {GENERATOR!s}", field="inertia", value=-1.0)
    assert not _raw_controls(str(err)) and "\\u202e" in str(err) and "\\u001b]0;title" in str(err)
    assert err.component == f"chain[2] {GENERATOR!s}"  # the attributes keep the true text
    value_err = ModelError("unknown", field="name", value=PART + "\x1b[2J\u202e")
    assert not _raw_controls(str(value_err))


def test_tables_progress_and_errors_reach_the_terminal_escaped_and_json_keeps_the_names(model, capsys):
    assert main(["modes", str(model)]) == 0
    out = capsys.readouterr().out
    assert not _raw_controls(out)
    assert "\\u202eevil\\u2066x\\u2069 \\u001b[31mred\\u0007" in out  # what the name holds, readable
    assert main(["modes", str(model), "--json"]) == 0
    out = capsys.readouterr().out
    assert not _raw_controls(out)
    doc = json.loads(out)  # still one JSON document, and it holds the names as written
    assert doc["model"] == MODEL_NAME
    assert [c["name"] for c in doc["components"]] == [MOTOR, PART, GENERATOR]
    # a refusal naming a hostile component: one line, nothing raw
    bad = model.with_name("bad.toml")
    bad.write_text(MODEL.replace("inertia = 6.67", "inertia = -6.67"))
    assert main(["modes", str(bad)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.splitlines()) == 1
    # the component as the loader names it (Python's repr: \x1b) - escaped either way, still readable
    assert not _raw_controls(captured.err) and "\\x1b]0;title\\x07" in captured.err


def test_a_progress_bar_escapes_its_label():
    import io

    from flexshaft.views.progress import ProgressBar

    stream = io.StringIO()
    bar = ProgressBar(f"slicing {PART}\x1b[2J\u202e", stream=stream, enabled=True)
    bar(1, 2)
    bar.stage("meshing \x9b31m", 0.5)
    assert not _raw_controls(stream.getvalue().replace("\r", ""))  # \r is the bar's own redraw


# --- figures ------------------------------------------------------------------------------------------


def test_a_name_with_dollars_is_drawn_as_written():
    # Two "$" make matplotlib read a text as a formula: "$x^$" is a malformed one and raised when the
    # figure was drawn, so a report of such a model failed as a whole.
    import flexshaft as fs
    from flexshaft.views.plots import energy_figure, png

    names = ["motor $x^$", "shaft \\frac{a}{$b$} \x1b", "gen $$"]
    shaft = fs.Shaft(names[1], stiffness=1e5, inertia=0.1)
    chain = [fs.Rigid(names[0], 10.0), shaft, fs.Rigid(names[2], 5.0)]
    d = fs.Drivetrain("m", chain)
    fig = energy_figure(fs.modal_analysis(d))
    assert png(fig).startswith(b"\x89PNG")
    # matplotlib's own rule: the legend's texts are not mathtext and show the names (controls escaped)
    shown_texts = [t._preprocess_math(t.get_text()) for t in fig.axes[0].get_legend().get_texts()]
    assert not any(math for _, math in shown_texts)
    assert [s for s, _ in shown_texts] == [names[1].replace("\x1b", "\\u001b")]  # the one with strain energy

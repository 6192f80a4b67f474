"""How deep a user's TOML or JSON file may nest, checked before a parser recurses into it.

Python's ``tomllib`` and ``json`` parse nested arrays and tables by recursion: a file of a few
kilobytes nested 5000 deep (``a = [[[[...]]]]``) ends in a ``RecursionError`` wherever the
interpreter's stack runs out - inside the parser, or later in any code walking the document. The
text is therefore scanned first (brackets and braces counted outside strings and comments, in one
pass of a regular expression) and refused past :data:`MAX_DEPTH` with one line naming the file, the
line and the limit. What the scan cannot see - tables nested by dotted keys and headers
(``[a.b.c...]``), which the parser builds without recursion - is measured on the parsed document
(:func:`check_depth`, without recursion either); and a parser's ``RecursionError`` that still
happens is the same error (:func:`toml_document`, :func:`json_document`).
"""

from __future__ import annotations

import re

from ..errors import ModelError

__all__ = ["MAX_DEPTH", "check_nesting", "check_depth", "toml_document", "json_document"]

#: The deepest nesting of arrays and tables a file may have. flexshaft's input files nest at most
#: 5 deep (a model's chain entry, its segments, a segment's table; a body file's metadata), a
#: study's own records about 10 (``results.json``: a set-up's run's spectra's peaks), so 64
#: refuses nothing real. It is far inside what the parsers survive: tomllib spends about three
#: stack frames a level (Python stops at 1000 frames), json's C scanner one.
MAX_DEPTH = 64

# The characters that matter; everything between them is skipped by the regular expression engine.
_TOML_MARKS = re.compile(r"[\"'#\[\]{}]")
_JSON_MARKS = re.compile(r'["\[\]{}]')
# The rest of a string after its opening quote(s), through its closing one. Each pattern is matched
# once where a string starts, and every character has one way to match: linear in the string's
# length. An unterminated string ends the scan (its parser refuses the file).
_BASIC_REST = re.compile(r'(?:[^"\\\n]|\\.)*"')
_MULTI_REST = re.compile(r'(?:[^"\\]|\\.|"(?!""))*"""(?:""?)?', re.S)  # up to two quotes end the text
_JSON_REST = re.compile(r'(?:[^"\\]|\\.)*"', re.S)


def _skip(text: str, i: int, json: bool) -> int:
    """Where the string or comment starting at ``text[i]`` ends (one past it); ``len(text)`` when it
    does not end."""
    c = text[i]
    if json:
        m = _JSON_REST.match(text, i + 1)
        return m.end() if m else len(text)
    if c == "#":
        end = text.find("\n", i)
        return len(text) if end < 0 else end
    if c == '"':
        if text.startswith('"""', i):
            m = _MULTI_REST.match(text, i + 3)
        else:
            m = _BASIC_REST.match(text, i + 1)
        return m.end() if m else len(text)
    if text.startswith("'''", i):
        close = text.find("'''", i + 3)
        if close < 0:
            return len(text)
        end = close + 3
        for _ in range(2):  # up to two quotes right before the closing ones belong to the text
            if end < len(text) and text[end] == "'":
                end += 1
        return end
    end = text.find("'", i + 1)
    line = text.find("\n", i + 1)
    if end < 0 or 0 <= line < end:  # unterminated on its line: the parser refuses the file
        return len(text) if line < 0 else line
    return end + 1


def _refused(source, depth: int, line: int | None = None) -> ModelError:
    where = f" (line {line})" if line is not None else ""
    return ModelError(
        f"nests arrays or tables {depth} deep{where}, more than any flexshaft file needs",
        file=str(source),
        valid=f"at most {MAX_DEPTH} levels of nesting",
    )


def check_nesting(text: str, source, *, kind: str = "toml") -> None:
    """Refuse ``text`` when its arrays and tables (``[``, ``{``) nest deeper than :data:`MAX_DEPTH`.

    Parameters
    ----------
    text : str
        The file's content.
    source : str or Path
        The file, for the message.
    kind : {"toml", "json"}
        The syntax: which strings and comments to skip.

    Raises
    ------
    ModelError
        Naming the file, the line where the limit is passed, and the limit.
    """
    json = kind == "json"
    marks = _JSON_MARKS if json else _TOML_MARKS
    depth = 0
    i = 0
    while (m := marks.search(text, i)) is not None:
        i = m.start()
        c = text[i]
        if c in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                raise _refused(source, depth, text.count("\n", 0, i) + 1)
        elif c in "]}":
            depth = max(depth - 1, 0)
        else:  # a string or a comment: its brackets are text
            i = _skip(text, i, json)
            continue
        i += 1


def check_depth(doc, source) -> None:
    """Refuse a parsed document (dicts and lists) nested deeper than :data:`MAX_DEPTH` (walked with a
    stack of its own, not by recursion)."""
    stack = [(doc, 0)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, dict | list):
            if depth > MAX_DEPTH:
                raise _refused(source, depth)
            children = value.values() if isinstance(value, dict) else value
            stack.extend((v, depth + 1) for v in children if isinstance(v, dict | list))


def toml_document(text: str, source) -> dict:
    """``tomllib.loads(text)`` with the nesting checked before and after; ``TOMLDecodeError`` is left
    to the caller, which says what the file should be."""
    import tomllib

    check_nesting(text, source)
    try:
        doc = tomllib.loads(text)
    except RecursionError:  # what the scan let through (it should be nothing): the same refusal
        raise _refused(source, MAX_DEPTH + 1) from None
    check_depth(doc, source)
    return doc


def json_document(text: str, source):
    """``json.loads(text)`` with the nesting checked before and after; ``ValueError`` (bad JSON) is
    left to the caller."""
    import json

    check_nesting(text, source, kind="json")
    try:
        doc = json.loads(text)
    except RecursionError:
        raise _refused(source, MAX_DEPTH + 1) from None
    check_depth(doc, source)
    return doc

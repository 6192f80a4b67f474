"""Files nested deeper than any flexshaft file needs are refused by name before a parser recurses
(issue 33: a study file nested 5000 deep was "unexpected RecursionError").

References: ``tomllib`` and ``json`` themselves (what the scan accepts they parse to the same
document; nested 5000 deep they raise RecursionError, which is what the refusal comes before), and
the limit's own value (64 levels pass, 65 do not).
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from flexshaft.cli import main
from flexshaft.errors import ModelError
from flexshaft.system.nesting import MAX_DEPTH, check_nesting, json_document, toml_document
from tests.conftest import EXAMPLES

DEEP = 5000  # the issue's study file
C1 = str(EXAMPLES / "customer1.toml")


def _nested_array(depth: int) -> str:
    return "[" * depth + "]" * depth


def test_the_parsers_themselves_cannot_take_the_issues_depth():
    # why the scan exists: Python's own parsers recurse, and 5000 levels end in RecursionError
    with pytest.raises(RecursionError):
        tomllib.loads("a = " + _nested_array(DEEP))
    with pytest.raises(RecursionError):
        json.loads(_nested_array(DEEP))


@pytest.mark.parametrize("kind", ["toml", "json"])
def test_the_limit_is_its_value(kind):
    text = ("a = " if kind == "toml" else "") + _nested_array(MAX_DEPTH)
    check_nesting(text, "f", kind=kind)
    with pytest.raises(ModelError, match=rf"f: nests arrays or tables {MAX_DEPTH + 1} deep \(line 1\)"):
        check_nesting(("a = " if kind == "toml" else "") + _nested_array(MAX_DEPTH + 1), "f", kind=kind)


def test_brackets_in_strings_and_comments_are_text():
    many = "[{" * 100
    text = (
        f'a = "{many}\\" {many}"\n'  # an escaped quote does not end the string
        f"b = '{many}'\n"
        f'c = """{many}\n{many}\\"""" \n'  # multi-line, a quote right before the closing ones
        f"d = '''{many}\n{many}''''' \n"
        f"# {many}\n"
        f'"{many}" = 1\n'  # a quoted key
        "e = [[1, 2], {x = [3]}]  # " + many + "\n"
    )
    assert toml_document(text, "f") == tomllib.loads(text)
    doc = {many: [many, {"k": "]" * 100 + '\\"'}]}
    assert json_document(json.dumps(doc), "f") == doc


def test_every_toml_file_flexshaft_ships_reads_as_tomllib_reads_it():
    for path in sorted(EXAMPLES.rglob("*.toml")):
        text = path.read_text(encoding="utf-8")
        assert toml_document(text, path) == tomllib.loads(text), path


def test_tables_nested_by_dotted_keys_are_measured_after_parsing():
    # dotted keys and headers make tables without recursion in the parser; the document is measured
    for text in ("a" + ".a" * DEEP + " = 1", "[" + ".".join(["a"] * DEEP) + "]\nx = 1"):
        with pytest.raises(ModelError, match=f"nests arrays or tables {MAX_DEPTH + 1} deep"):
            toml_document(text, "f")


def _one_line(capsys, name: str) -> str:
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert "unexpected" not in line and name in line and "nests arrays or tables" in line, line
    assert f"at most {MAX_DEPTH} levels of nesting" in line
    return line


def test_every_file_read_is_refused_by_name_through_the_cli(tmp_path, capsys):
    # a model, a study, a targets file: each nested 5000 deep, each one line naming it (exit 2)
    model = tmp_path / "model.toml"
    model.write_text('[model]\nname = "m"\nx = ' + "{a = " * DEEP + "1" + "}" * DEEP + "\n")
    assert main(["modes", str(model)]) == 2
    _one_line(capsys, str(model))
    study = tmp_path / "study.toml"
    study.write_text('[study]\nname = "deep"\nx = ' + _nested_array(DEEP) + "\n")
    assert main(["study", str(study), "-o", str(tmp_path / "out")]) == 2
    _one_line(capsys, str(study))
    targets = tmp_path / "targets.toml"
    targets.write_text("[[target]]\nmode = 1\nratio = " + _nested_array(DEEP) + "\n")
    assert main(["calibrate", C1, "--targets", str(targets)]) == 2
    _one_line(capsys, str(targets))


def test_flexible_body_files_nested_too_deep_are_refused_by_name(tmp_path, capsys):
    body = tmp_path / "part.json"
    body.write_text('{"format": ' + _nested_array(DEEP) + "}")
    assert main(["body", str(body)]) == 2
    _one_line(capsys, str(body))
    # the metadata inside an .npz body
    flex = str(EXAMPLES / "customer1_flex.toml")
    assert main(["reduce", flex, "--part", "part 1", "-o", str(tmp_path / "p.npz")]) == 0
    capsys.readouterr()
    with np.load(tmp_path / "p.npz") as data:
        arrays = {k: data[k] for k in data.files if k != "metadata"}
    np.savez(tmp_path / "deep.npz", metadata=np.array(_nested_array(DEEP)), **arrays)
    assert main(["body", str(tmp_path / "deep.npz")]) == 2
    _one_line(capsys, "deep.npz")


def test_a_study_folder_whose_manifest_is_nested_too_deep_is_no_defect(tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text(f'[[setup]]\nname = "c1"\nmodel = "{C1}"\n[views]\nsetups = []\n')
    out = tmp_path / "out"
    assert main(["study", str(study), "-o", str(out)]) == 0
    (out / ".flexshaft-study" / "manifest.json").write_text(_nested_array(DEEP))
    capsys.readouterr()
    code = main(["study", str(study), "-o", str(out)])
    captured = capsys.readouterr()
    # a record that does not parse counts as absent: every stage runs again, and the run succeeds
    assert code == 0 and "unexpected" not in captured.err and "RecursionError" not in captured.err, captured
    assert "unchanged" not in captured.out and "read from the store" not in captured.out, captured.out

"""Signal files: an exact round trip, units converted to SI, and every damaged or hostile file one
ModelError (never a foreign exception, never other data accepted)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexshaft.errors import ModelError
from flexshaft.measurement import signalfile
from flexshaft.measurement.signalfile import SignalTable, read_signals, write_signals

RATE = 1600.0
T = np.arange(3200) / RATE


def _signals():
    rng = np.random.default_rng(2)
    return {
        "torque:part 3": (500.0 + rng.normal(0.0, 37.0, T.size), "N·m"),
        "speed:generator": (157.0 + np.sin(2 * np.pi * 3 * T) * 1e-3, "rad/s"),
        "angle, with a comma": (rng.normal(size=T.size) * 1e-7, "rad"),
    }


def test_round_trip_is_exact(tmp_path):
    path = write_signals(tmp_path / "run.csv", T, _signals())
    header = path.read_text(encoding="utf-8").splitlines()[0]
    assert header == 'time [s],torque:part 3 [N·m],speed:generator [rad/s],"angle, with a comma [rad]"'
    table = read_signals(path)
    assert isinstance(table, SignalTable) and table.source == str(path)
    # each value written as the shortest decimal that reads back to it, parsed correctly rounded: same bits
    assert np.array_equal(table.time, T)
    for name, (values, unit) in _signals().items():
        assert np.array_equal(table.columns[name], values) and table.units[name] == unit
    # the rate from 3199 steps of 1/1600 written exactly: rounding of t only
    assert table.rate_hz == pytest.approx(RATE, rel=1e-12)


def test_units_are_converted_to_si(tmp_path):
    path = tmp_path / "bench.csv"
    path.write_text(
        "time [ms],speed [rpm],torque [kNm],angle [deg],tq2 [N*m],tq3\n"
        "0,3000,1.5,90,7,1\n"
        "0.625,-60,-0.002,-180,8,2\n"
        "1.25,0,0,0,9,3\n",
        encoding="utf-8",
    )
    table = read_signals(path, units={"tq3": "kN·m"})
    # closed forms, each one multiplication from the file's value: rounding (rel 1e-15)
    assert table.time == pytest.approx([0.0, 0.625e-3, 1.25e-3], rel=1e-15)
    assert table.rate_hz == pytest.approx(1600.0, rel=1e-12)
    assert table.columns["speed"] == pytest.approx([3000 * 2 * math.pi / 60, -2 * math.pi, 0.0], rel=1e-15)
    assert table.columns["torque"] == pytest.approx([1500.0, -2.0, 0.0], rel=1e-15)
    assert table.columns["angle"] == pytest.approx([math.pi / 2, -math.pi, 0.0], rel=1e-15)
    assert list(table.columns["tq2"]) == [7.0, 8.0, 9.0] and list(table.columns["tq3"]) == [1e3, 2e3, 3e3]
    assert table.units == {"speed": "rad/s", "torque": "N·m", "angle": "rad", "tq2": "N·m", "tq3": "N·m"}


def test_a_value_that_overflows_when_made_si_is_refused_without_a_warning(tmp_path):
    # 1e307 kN·m is 1e310 N·m, past the largest double (1.8e308): it would be inf in the table
    path = tmp_path / "big.csv"
    path.write_text("time [s],torque [kNm]\n0,1\n0.001,1e307\n0.002,3\n")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning would be an error here
        with pytest.raises(ModelError, match="torque: holds a value too large to convert to N·m"):
            read_signals(path)


def test_units_must_map_names_to_unit_strings(tmp_path):
    path = tmp_path / "bench.csv"
    path.write_text("time [s],tq\n0,1\n1,2\n", encoding="utf-8")
    with pytest.raises(ModelError, match="must map column names to unit strings") as e:
        read_signals(path, units={"tq": 1000})
    assert e.value.field == "units"


def test_columns_by_full_header_or_name_and_another_time_column(tmp_path):
    path = tmp_path / "c.csv"
    path.write_text("t [s],a [Nm],b [rpm]\n0,1,2\n0.5,3,4\n1.0,5,6\n", encoding="utf-8")
    table = read_signals(path, columns=["b [rpm]", "a"], time_column="t")
    assert list(table.columns) == ["b", "a"] and table.rate_hz == 2.0
    with pytest.raises(ModelError) as err:
        read_signals(path)  # no column 'time'
    assert err.value.field == "time_column" and "'t', 'a', 'b'" in str(err.value)
    with pytest.raises(ModelError) as err:
        read_signals(path, columns=["c"], time_column="t")
    assert err.value.field == "columns"
    with pytest.raises(ModelError) as err:
        read_signals(path, units={"a": "kNm"}, time_column="t")  # the header says Nm
    assert err.value.field == "a"


def _write(tmp_path, content: bytes | str):
    path = tmp_path / "bad.csv"
    path.write_bytes(content.encode("utf-8") if isinstance(content, str) else content)
    return path


GOOD = "time [s],torque [N·m]\n0,1\n0.001,2\n0.002,3\n"
DAMAGED = {
    # case: (file content, a word the message must hold)
    "empty": ("", "empty"),
    "only blank lines": ("\n\n  \n", "empty"),
    "header only": ("time [s],torque [N·m]\n", "data rows"),
    "one row": ("time [s],torque [N·m]\n0,1\n", "data rows"),
    "ragged row": (GOOD + "0.003\n", "cells"),
    "extra cell": (GOOD + "0.003,4,5\n", "cells"),
    "trailing comma": (GOOD.replace("0.001,2", "0.001,2,"), "cells"),
    "not a number": (GOOD.replace("0.001,2", "0.001,two"), "not a number"),
    "underscore number": (GOOD.replace("0.001,2", "0.001,2_0"), "not a number"),
    "arabic digits": (GOOD.replace("0.001,2", "0.001,٢"), "not a number"),
    "hex float": (GOOD.replace("0.001,2", "0.001,0x2"), "not a number"),
    "NaN": (GOOD.replace("0.001,2", "0.001,nan"), "non-finite"),
    "overflow": (GOOD.replace("0.001,2", "0.001,1e400"), "non-finite"),
    "empty cell": (GOOD.replace("0.001,2", "0.001,"), "not a number"),
    "duplicate header": ("time [s],torque [N·m],torque [kNm]\n0,1,1\n0.001,2,2\n", "both name"),
    "empty header cell": ("time [s],,torque [N·m]\n0,1,1\n0.001,2,2\n", "no name"),
    "brackets in a name": ("time [s],a[b] [N·m]\n0,1\n0.001,2\n", "name [unit]"),
    "unknown unit": ("time [s],torque [lbf*ft]\n0,1\n0.001,2\n", "unknown unit"),
    "missing unit": ("time [s],torque\n0,1\n0.001,2\n", "no unit"),
    "time not a time": ("time [rad],torque [N·m]\n0,1\n0.001,2\n", "not a time"),
    "time backwards": (GOOD.replace("0.002,3", "0.0005,3"), "does not increase"),
    "time repeated": (GOOD.replace("0.002,3", "0.001,3"), "does not increase"),
    "time not uniform": (GOOD.replace("0.002,3", "0.0021,3"), "uniformly"),
    "not UTF-8": (b"time [s],torque [N\xb7m]\n0,1\n0.001,2\n", "UTF-8"),
    "binary": (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "NUL"),
    "a huge field": ("time [s],torque [N·m]\n0," + "9" * 200_000 + "\n0.001,2\n", "non-finite"),
    "a huge quoted field": ('time [s],torque [N·m]\n0,"' + "9" * 200_000 + "\n0.001,2\n", "CSV"),
    "semicolons": ("time [s];torque [N·m]\n0;1\n0.001;2\n", "semicolons"),
    "tabs": ("time [s]\ttorque [N·m]\n0\t1\n0.001\t2\n", "tabs"),
    "a size claim in the header": ("time [s],rows [10000000000]\n0,1\n0.001,2\n", "unknown unit"),
}


@pytest.mark.parametrize("case", list(DAMAGED))
def test_damaged_files_are_one_model_error(tmp_path, case):
    content, word = DAMAGED[case]
    path = _write(tmp_path, content)
    with pytest.raises(ModelError) as err:
        read_signals(path)
    message = str(err.value)
    assert "\n" not in message and message.startswith(str(path)) and "valid: " in message, message
    assert word in message, message


def test_the_good_reference_of_the_damaged_cases_reads(tmp_path):
    """The damaged cases fail for what was changed, not for the file they were made from."""
    table = read_signals(_write(tmp_path, GOOD))
    assert list(table.columns["torque"]) == [1.0, 2.0, 3.0] and table.rate_hz == pytest.approx(1000.0)


def test_quoted_numbers_and_blank_lines_are_read(tmp_path):
    # numpy's fast parser refuses these; the cell-by-cell reader takes them
    table = read_signals(_write(tmp_path, 'time [s],"torque [N·m]"\n\n0,"1"\n0.001,2\n\n0.002,3\n\n'))
    assert list(table.columns["torque"]) == [1.0, 2.0, 3.0]


def test_a_file_above_the_size_cap_is_refused_before_reading(tmp_path):
    path = tmp_path / "huge.csv"
    with open(path, "wb") as fh:
        fh.write(GOOD.encode())
        fh.truncate(signalfile.MAX_BYTES + 1)  # sparse: nothing of it is written to disk
    with pytest.raises(ModelError, match="huge.csv: is 2048 MB .* above the 2048 MB ceiling") as err:
        read_signals(path)
    assert "FLEXSHAFT_MAX_FILE_MB" in str(err.value)


def test_missing_file_and_directory(tmp_path):
    for path, says in ((tmp_path / "nowhere.csv", "file not found"), (tmp_path, "is a directory")):
        with pytest.raises(ModelError) as err:
            read_signals(path)
        assert says in str(err.value)


@pytest.mark.parametrize("head", [b"", GOOD.encode()], ids=["first line", "after good rows"])
def test_a_line_without_end_is_refused_before_it_is_read_whole(tmp_path, head):
    """A file of one endless line (here 64 MB of NUL bytes with no line feed) is refused once the line
    passes MAX_LINE_BYTES: the reader never holds more of it than that."""
    path = tmp_path / "endless.csv"
    with open(path, "wb") as fh:
        fh.write(head)
        fh.truncate(len(head) + (64 << 20))  # sparse
    line = head.count(b"\n") + 1
    with pytest.raises(ModelError, match=f"endless.csv: line {line} is longer than 1 MB"):
        read_signals(path)


def test_a_line_at_the_line_limit_is_read(tmp_path):
    """The limit is on the line, not on the piece: a header of exactly MAX_LINE_BYTES bytes (without its
    line feed) reads, one byte more is refused."""
    n = 1000  # columns, each padded to ~1 kB (Python's csv takes a cell of at most 128 KiB)
    base = "time [s]," + ",".join(f"c{i} [N·m]" for i in range(n))
    for extra, ok in ((0, True), (1, False)):
        pad = signalfile.MAX_LINE_BYTES - len(base.encode()) + extra
        spaces = [pad // n + (i < pad % n) for i in range(n)]
        header = "time [s]," + ",".join(f"c{i}{' ' * spaces[i]} [N·m]" for i in range(n))
        assert len(header.encode()) == signalfile.MAX_LINE_BYTES + extra
        path = tmp_path / f"wide{extra}.csv"
        row = ",".join(["1"] * n)
        path.write_text(f"{header}\n0,{row}\n0.001,{row}\n", encoding="utf-8")
        if ok:
            assert list(read_signals(path, columns=["c0"]).columns["c0"]) == [1.0, 1.0]
        else:
            with pytest.raises(ModelError, match="line 1 is longer than 1 MB"):
                read_signals(path)


def test_random_damage_is_refused_or_reads_as_a_checked_table(tmp_path):
    good = write_signals(tmp_path / "good.csv", T[:50], {k: (v[:50], u) for k, (v, u) in _signals().items()})
    data = good.read_bytes()
    rng = np.random.default_rng(20261122)
    bad = tmp_path / "bad.csv"
    for trial in range(200):
        b = bytearray(data[: int(rng.uniform(0.2, 1.0) * len(data))] if trial % 4 == 0 else data)
        for _ in range(int(rng.integers(1, 6))):
            b[int(rng.integers(len(b)))] = int(rng.integers(256))
        bad.write_bytes(bytes(b))
        try:
            table = read_signals(bad)
        except ModelError as err:
            assert "\n" not in str(err)
            continue
        # accepted: then it passed every check
        assert np.all(np.isfinite(table.time)) and np.all(np.diff(table.time) > 0)
        assert all(np.all(np.isfinite(v)) and v.shape == table.time.shape for v in table.columns.values())


def test_write_refuses_to_overwrite_unless_told(tmp_path):
    path = write_signals(tmp_path / "w.csv", T, _signals())
    first = path.read_bytes()
    with pytest.raises(ModelError, match="exists"):
        write_signals(path, T, {"x": (np.zeros(T.size), "rad")})
    assert path.read_bytes() == first
    write_signals(path, T, {"x": (np.zeros(T.size), "rad")}, overwrite=True)
    assert list(read_signals(path).columns) == ["x"]


@pytest.mark.parametrize(
    "time, columns, field",
    [
        (T, {}, "columns"),
        (T, {"x": (np.zeros(3), "rad")}, "x"),
        (T, {"x": (np.full(T.size, np.nan), "rad")}, "x"),
        (T, {"x": (np.zeros(T.size), "furlong")}, "x"),
        (T, {"x": np.zeros(T.size)}, "x"),
        (T, {"a [b]": (np.zeros(T.size), "rad")}, "columns"),
        (T, {"time": (np.zeros(T.size), "s")}, "columns"),
        (T, {"": (np.zeros(T.size), "rad")}, "columns"),
        (T[::-1], {"x": (np.zeros(T.size), "rad")}, "time"),
        (np.r_[T[:5], T[5:] + 1e-5], {"x": (np.zeros(T.size), "rad")}, "time"),
        (T[:1], {"x": (np.zeros(1), "rad")}, "time"),
    ],
)
def test_write_refuses_bad_input_and_leaves_no_file(tmp_path, time, columns, field):
    path = tmp_path / "w.csv"
    with pytest.raises(ModelError) as err:
        write_signals(path, time, columns)
    assert err.value.field == field
    assert list(tmp_path.iterdir()) == []

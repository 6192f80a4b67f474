"""Opening a user's input file (flexshaft.system.inputs): regular files only, a ceiling per kind, the inputs
recorded so that no output replaces one."""

from __future__ import annotations

import os
import socket
import stat
import threading
from pathlib import Path

import pytest

from flexshaft.errors import ModelError
from flexshaft.system import inputs
from flexshaft.system.atomic import atomic_write_text


@pytest.fixture(autouse=True)
def _fresh(monkeypatch):
    """Each test with the default ceilings."""
    monkeypatch.delenv(inputs.ENV_VAR, raising=False)


@pytest.fixture
def recorded():
    """The test's reads recorded, as inside a CLI command."""
    with inputs.recording():
        yield


def _within(seconds: float, fn, unblock=None):
    """``fn()``'s result or exception, failing the test when it takes longer than ``seconds`` (a read
    that blocks on a FIFO would hang the suite; ``unblock()`` then releases the thread)."""
    out = {}

    def run():
        try:
            out["value"] = fn()
        except BaseException as err:  # noqa: BLE001 - handed to the test below
            out["error"] = err

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    if t.is_alive():
        if unblock is not None:
            unblock()
        pytest.fail(f"still blocked after {seconds} s")
    if "error" in out:
        raise out["error"]
    return out.get("value")


def _open_writer(fifo):
    """Open the FIFO's writing end (releases a reader blocked in open), then close it."""
    try:
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:
        pass


# --- the ceiling ------------------------------------------------------------------------------------


def test_default_ceilings_and_the_variable_that_sets_them_all(monkeypatch):
    assert inputs.ceiling_bytes(inputs.MODEL) == 8 * inputs.MB
    assert inputs.ceiling_bytes(inputs.SIGNALS) == 2048 * inputs.MB
    monkeypatch.setenv(inputs.ENV_VAR, "4096")
    assert {inputs.ceiling_bytes(k) for k in inputs.KINDS} == {4096 * inputs.MB}  # raised, every kind
    monkeypatch.setenv(inputs.ENV_VAR, "0.5")
    assert {inputs.ceiling_bytes(k) for k in inputs.KINDS} == {inputs.MB // 2}  # lowered, every kind
    monkeypatch.setenv(inputs.ENV_VAR, " ")
    assert inputs.ceiling_bytes(inputs.TARGETS) == inputs.MB  # blank: unset


@pytest.mark.parametrize("value", ["abc", "0", "-1", "nan", "inf", "1e400", "4 GB"])
def test_a_variable_that_is_no_size_is_refused_by_name(monkeypatch, tmp_path, value):
    (tmp_path / "m.toml").write_text("x = 1\n")
    monkeypatch.setenv(inputs.ENV_VAR, value)
    with pytest.raises(ModelError, match=f"{inputs.ENV_VAR} = .*: is not a size; valid: a number of MB > 0"):
        inputs.read_bytes(tmp_path / "m.toml", inputs.MODEL)


def test_a_file_above_its_ceiling_is_refused_naming_file_size_ceiling_and_variable(tmp_path, monkeypatch):
    big = tmp_path / "big.toml"
    with open(big, "wb") as fh:
        fh.truncate(2 << 30)  # sparse: nothing on disk
    with pytest.raises(ModelError) as err:
        inputs.read_bytes(big, inputs.MODEL)
    text = str(err.value)
    assert text.startswith(f"{big}: is 2048 MB, above the 8 MB ceiling for a model file; valid:")
    assert inputs.ENV_VAR in text
    nine = tmp_path / "nine.toml"
    with open(nine, "wb") as fh:
        fh.truncate(9 * inputs.MB)
    with pytest.raises(ModelError, match="is 9 MB, above the 8 MB ceiling"):
        inputs.read_bytes(nine, inputs.MODEL)
    monkeypatch.setenv(inputs.ENV_VAR, "16")  # raised above it: read
    assert len(inputs.read_bytes(nine, inputs.MODEL)) == 9 * inputs.MB


def test_a_size_just_above_the_ceiling_shows_its_bytes(tmp_path, monkeypatch):
    monkeypatch.setenv(inputs.ENV_VAR, "1")
    p = tmp_path / "t.toml"
    p.write_bytes(b"#" * (inputs.MB + 1))
    with pytest.raises(ModelError, match=r"is 1 MB \(1,048,577 bytes\), above the 1 MB ceiling"):
        inputs.read_bytes(p, inputs.TARGETS)
    p.write_bytes(b"#" * inputs.MB)  # at the ceiling: read
    assert len(inputs.read_bytes(p, inputs.TARGETS)) == inputs.MB


# --- what is not a regular file, refused by name before any read -------------------------------------


def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "m.toml"
    os.mkfifo(fifo)
    for read in (
        lambda: inputs.read_bytes(fifo, inputs.MODEL),
        lambda: inputs.check_path(fifo, inputs.CAD, field="geometry"),
        lambda: inputs.open_input(fifo, inputs.SIGNALS).__enter__(),
    ):
        with pytest.raises(ModelError, match="is a FIFO"):
            _within(10, read, unblock=lambda: _open_writer(fifo))


def test_a_fifo_swapped_in_after_the_stat_does_not_block_the_open(tmp_path, monkeypatch):
    """The stat said 'regular file'; the path is a FIFO when it is opened (replaced meanwhile). The
    open does not wait for a writer (O_NONBLOCK) and fstat on the descriptor refuses it."""
    regular = tmp_path / "regular.toml"
    regular.write_text("x = 1\n")
    fifo = tmp_path / "m.toml"
    os.mkfifo(fifo)
    real_stat = os.stat
    monkeypatch.setattr(inputs.os, "stat", lambda p, *a, **k: real_stat(regular))
    with pytest.raises(ModelError, match="m.toml: is a FIFO"):
        _within(10, lambda: inputs.read_bytes(fifo, inputs.MODEL), unblock=lambda: _open_writer(fifo))


@pytest.mark.parametrize(
    "device, says", [("/dev/zero", "is a character device"), ("/dev/urandom", "is a character device")]
)
def test_devices_are_refused_by_name(device, says):
    if not os.path.exists(device):
        pytest.skip(f"no {device} here")
    with pytest.raises(ModelError, match=f"{device}: {says}, not a model file; valid: a regular file"):
        _within(10, lambda: inputs.read_bytes(device, inputs.MODEL))


def test_a_directory_a_socket_and_a_missing_file_are_refused_by_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a short socket path (sockaddr_un holds ~108 bytes)
    sock = socket.socket(socket.AF_UNIX)
    sock.bind("s.csv")
    sock.close()  # the socket file stays
    Path("gone.toml").symlink_to("nowhere.toml")
    cases = {
        tmp_path: "is a directory, not a signal file",
        "s.csv": "is a socket, not a signal file",
        "nope.csv": "file not found; valid: an existing signal file",
        "gone.toml": r"file not found \(a link to a missing file\)",
    }
    for path, says in cases.items():
        with pytest.raises(ModelError, match=says):
            inputs.read_bytes(path, inputs.SIGNALS)


def test_a_field_names_the_file_as_its_value(tmp_path):
    with pytest.raises(ModelError) as err:
        inputs.check_path(tmp_path / "part.step", inputs.CAD, field="geometry")
    assert str(err.value) == (
        f"geometry = '{tmp_path / 'part.step'}': file not found; valid: an existing STEP/BREP file"
    )


def test_text_that_is_not_utf8_is_refused(tmp_path):
    p = tmp_path / "m.toml"
    p.write_bytes(b"name = '\xff'\n")
    with pytest.raises(ModelError, match=r"m.toml: not a UTF-8 text file \(byte 8\)"):
        inputs.read_text(p, inputs.MODEL)


# --- sizes are not trusted: /proc files say 0 --------------------------------------------------------


def test_a_file_that_says_size_0_is_read_to_the_ceiling_not_beyond(monkeypatch):
    maps = Path("/proc/self/maps")
    if not maps.exists() or os.stat(maps).st_size != 0:
        pytest.skip("no /proc file that claims size 0")
    data = inputs.read_bytes(maps, inputs.MODEL)  # read whole: the size said 0, the bytes came
    assert len(data) > 1024
    monkeypatch.setenv(inputs.ENV_VAR, str(1000 / inputs.MB))  # a 1000-byte ceiling
    with pytest.raises(ModelError, match=r"maps: holds more than 0\.001 MB, above the 0\.001 MB ceiling"):
        inputs.read_bytes(maps, inputs.MODEL)
    with pytest.raises(ModelError, match="holds more than"):  # streamed: the read past it refuses
        with inputs.open_input(maps, inputs.SIGNALS) as fh:
            while fh.read(100):
                pass


def test_streaming_reads_a_regular_file_whole(tmp_path):
    p = tmp_path / "s.csv"
    data = os.urandom(300_000)
    p.write_bytes(data)
    with inputs.open_input(p, inputs.SIGNALS) as fh:
        got = fh.read(1000) + fh.readline(50) + fh.read()
    assert got == data


# --- the record of inputs: an output never replaces one ----------------------------------------------


def test_every_read_is_recorded_and_links_lead_to_it(tmp_path, recorded):
    m = tmp_path / "m.toml"
    m.write_text("x = 1\n")
    inputs.read_text(m, inputs.MODEL)
    link, hard, other = tmp_path / "link.toml", tmp_path / "hard.toml", tmp_path / "other.toml"
    link.symlink_to(m)
    os.link(m, hard)
    other.write_text("x = 1\n")
    assert inputs.recorded_inputs() == (m,)
    assert inputs.same_input(m) == m and inputs.same_input(link) == m and inputs.same_input(hard) == m
    assert inputs.same_input(other) is None and inputs.same_input(tmp_path / "new.toml") is None
    inputs.forget_inputs()
    assert inputs.same_input(m) is None


def test_an_input_is_never_overwritten_force_or_not(tmp_path, recorded):
    m = tmp_path / "m.toml"
    m.write_text("keep\n")
    inputs.read_text(m, inputs.MODEL)
    link, hard = tmp_path / "link.toml", tmp_path / "hard.toml"
    link.symlink_to(m)
    os.link(m, hard)
    for target in (m, link, hard):
        for overwrite in (False, True):
            with pytest.raises(ModelError, match="an output never replaces an input, --force or not"):
                atomic_write_text(target, "table\n", overwrite=overwrite)
    assert m.read_text() == "keep\n" and link.is_symlink() and os.stat(hard).st_nlink == 2
    atomic_write_text(tmp_path / "out.txt", "table\n")  # any other path is written


def test_a_reused_inode_is_not_taken_for_the_input(tmp_path, recorded):
    """An input deleted after it was read may leave its inode number to a new file: that file is not
    the input (the recorded path must still lead to the inode)."""
    a, b = tmp_path / "a.toml", tmp_path / "b.toml"
    a.write_text("a\n")
    b.write_text("b\n")
    inputs.note_input(a, os.stat(b))  # as if a's inode were now b's: the reuse, made certain
    assert inputs.same_input(b) is None
    atomic_write_text(b, "new\n", overwrite=True)
    # the same happening for real: read, delete, create files until one gets the old inode (or not)
    inputs.forget_inputs()
    c = tmp_path / "c.toml"
    c.write_text("c\n")
    inputs.read_text(c, inputs.MODEL)
    ino = os.stat(c).st_ino
    c.unlink()
    for i in range(50):
        d = tmp_path / f"d{i}.toml"
        d.write_text("d\n")
        assert inputs.same_input(d) is None
        if os.stat(d).st_ino == ino:
            break


def test_outside_a_recording_nothing_is_recorded(tmp_path):
    """A Python session that reads a file and deliberately writes it again (overwrite=True) may."""
    m = tmp_path / "m.toml"
    m.write_text("keep\n")
    with inputs.recording():
        with inputs.recording():  # nested: one record
            inputs.read_text(m, inputs.MODEL)
        assert inputs.same_input(m) == m
    assert inputs.same_input(m) is None and inputs.recorded_inputs() == ()
    inputs.read_text(m, inputs.MODEL)
    atomic_write_text(m, "new\n", overwrite=True)
    assert m.read_text() == "new\n"


def test_check_path_reads_nothing_and_records_the_input(tmp_path, recorded):
    p = tmp_path / "part.step"
    p.write_bytes(b"ISO-10303-21;\n")
    os.chmod(p, stat.S_IWUSR)  # unreadable to a non-root user: the open would fail for them
    if os.geteuid() != 0:
        with pytest.raises(ModelError, match="cannot be read"):
            inputs.check_path(p, inputs.CAD)
        os.chmod(p, stat.S_IRUSR | stat.S_IWUSR)
    assert inputs.check_path(p, inputs.CAD) == p
    assert inputs.same_input(p) == p


def test_a_file_of_flexshafts_own_folder_is_read_without_links_and_not_as_an_input(tmp_path, recorded):
    """``own=True`` (a study's stored results): a link is refused even to a regular file - nothing is
    read from outside the folder through one - and the file is not recorded, so the run may rewrite it."""
    stored = tmp_path / "stored.json"
    stored.write_text("{}")
    assert inputs.read_text(stored, inputs.STORED, own=True) == "{}"
    assert inputs.recorded_inputs() == ()
    atomic_write_text(stored, "{ }", overwrite=True)  # not an input: replaced
    link = tmp_path / "link.json"
    link.symlink_to(stored)
    with pytest.raises(ModelError, match="is a symbolic link, not a stored study result"):
        inputs.read_bytes(link, inputs.STORED, own=True)
    assert inputs.read_text(link, inputs.STORED) == "{ }"  # an input may be a link
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(ModelError, match="is a FIFO"):
        _within(10, lambda: inputs.read_bytes(fifo, inputs.STORED, own=True), lambda: _open_writer(fifo))

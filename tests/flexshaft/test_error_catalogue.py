"""The CLI's error catalogue: every refusal is one stderr line naming file, field, value and what is valid.

Each case is a bad model file or a bad command line a user can write; the test runs the CLI on it and
checks the line's shape. The lines themselves are the catalogue (``pytest -s`` prints it).
"""

from __future__ import annotations

import warnings

import pytest

from flexshaft.cli import main
from tests.conftest import EXAMPLES, without_progress

M = '[[chain]]\nname = "motor"\ntype = "rigid"\ninertia = 58.1\n\n'
S = '[[chain]]\nname = "p"\ntype = "shaft"\nstiffness = 1e5\ninertia = 1.0\n'
SEG = '[[chain]]\nname = "s"\ntype = "shaft"\nmaterial = "steel"\nsegments = [{length = 1.0, od = 0.1}]\n'
FULL = '[model]\ndofs = "full"\n'
CAD = '[[chain]]\nname = "c"\ntype = "cad"\nmaterial = "steel"\ngeometry = '
C1 = str(EXAMPLES / "customer1.toml")

MODEL_FILES = {
    "negative inertia": M.replace("58.1", "-58.1") + S,
    "NaN stiffness": M + S.replace("1e5", "nan"),
    "unknown key": M + S + "colour = 1\n",
    "unknown type": M + '[[chain]]\nname = "x"\ntype = "spring"\n',
    "duplicate name": M + M,
    "missing key": M + '[[chain]]\nname = "p"\ntype = "shaft"\ninertia = 1.0\n',
    "wrong unit": M + S.replace("1e5", '"1e5 kg"'),
    "bad unit text": M + S.replace("1e5", '"lots"'),
    "damping ratio above one": M + S + "damping_ratio = 1.5\n",
    "elements zero": M + S + "elements = 0\n",
    "unknown material": M + SEG.replace('"steel"', '"unobtainium"'),
    "bore above diameter": M + SEG.replace("od = 0.1}", "od = 0.1, id = 0.2}"),
    "station outside the part": M + SEG + "stations = {j = 2.0}\n",
    "stations on a numbers shaft": M + S + "stations = {j = 0.5}\n",
    "tiny element length": M + SEG + "max_element_length = 1e-12\n",
    "bearing in a torsion model": M + SEG + '[[bearings]]\nstation = "motor"\nstiffness = 1e9\n',
    "bearing at no station": FULL + M + SEG + '[[bearings]]\nstation = "x"\nstiffness = 1e9\n',
    "full model shaft without sections": FULL + M + S,
    "unknown inertia model": '[model]\ninertia_model = "heavy"\n' + M + S,
    "rayleigh unknown key": "[model]\nrayleigh = {gamma = 1.0}\n" + M + S,
    "reduce both": M + S + "reduce = {modes = 2, cutoff_hz = 100.0}\n",
    "flex damping without reduce": M + S + "damping_bands = [[0, 10, 0.01]]\n",
    "code not trusted": M + CAD + '"my:part"\n',
    "standard library": M + CAD + '"os:system"\n',
    "inertia out of scale": (
        M.replace("58.1", "1e-30") + S.replace("inertia = 1.0", "inertia = 0.0") + M.replace("motor", "g")
    ),
    "massless free end": M + S.replace("inertia = 1.0", "inertia = 0.0"),
    "empty chain": "[model]\nname = 'x'\n",
    "not TOML": "[[chain\n",
}


def _line(capsys, argv) -> str:
    code = main(argv)
    out = capsys.readouterr()
    assert code == 2 and out.out == "", (argv, out)
    lines = out.err.strip().splitlines()
    assert len(lines) == 1, out.err
    return lines[0]


@pytest.mark.parametrize("case", list(MODEL_FILES))
def test_model_file_errors_are_one_complete_line(tmp_path, capsys, case):
    model = tmp_path / "m.toml"
    model.write_text(MODEL_FILES[case])
    line = _line(capsys, ["modes", str(model)])
    print(f"{case:>34}: {line}")
    assert line.startswith(f"flexshaft: error: {model}: ")
    # What is valid, always; the field and the value where there is one (a missing key has no value).
    assert "; valid: " in line or case == "not TOML", line


CLI_CASES = {
    "missing file": ["modes", "nowhere.toml"],
    "count zero": ["modes", C1, "--modes", "0"],
    "too many modes": ["modes", C1, "--modes", "99"],
    "force without output": ["modes", C1, "--force"],
    "twist unknown station": ["twist", C1, "--clamp", "nowhere"],
    "twist tiny torque": ["twist", C1, "--torque", "1e-320"],
    "twist bad target": ["twist", C1, "--target", "part 1"],
    "reduce without output": ["reduce", C1, "--part", "part 1", "--modes", "2"],
    "reduce a rigid": ["reduce", C1, "--part", "motor", "--modes", "2", "-o", "x.npz"],
    "reduce unknown part": ["reduce", C1, "--part", "p9", "--modes", "2", "-o", "x.npz"],
    "unknown option": ["modes", C1, "--colour"],
}


@pytest.mark.parametrize("case", list(CLI_CASES))
def test_command_line_errors_are_one_line(tmp_path, capsys, monkeypatch, case):
    monkeypatch.chdir(tmp_path)
    line = _line(capsys, CLI_CASES[case])
    print(f"{case:>34}: {line}")
    assert line.startswith("flexshaft: error: ")


# --- abuse cases (tests/flexshaft/catalogue/): files that never end, units that are programs, outputs over
# inputs, sizes without ceilings, integrity switched off, results that are not numbers ------------------


def _digest(path, size: int) -> str:
    """SHA-256 of the file's size and its data extents: a sparse 2 GB case file is read only where it
    holds data (its holes read as zeros, which writing anything would replace with data extents)."""
    import hashlib
    import os

    h = hashlib.sha256(str(size).encode())
    fd = os.open(path, os.O_RDONLY)
    try:
        offset = 0
        while offset < size:
            try:
                start = os.lseek(fd, offset, os.SEEK_DATA)
            except OSError:  # ENXIO: only a hole is left
                break
            end = os.lseek(fd, start, os.SEEK_HOLE)
            h.update(f"@{start}".encode())
            os.lseek(fd, start, os.SEEK_SET)
            left = end - start
            while left > 0:
                chunk = os.read(fd, min(left, 1 << 20))
                if not chunk:
                    break
                h.update(chunk)
                left -= len(chunk)
            offset = end
    finally:
        os.close(fd)
    return h.hexdigest()


def _snapshot(folder) -> dict:
    """Every file under ``folder`` with its bytes' digest (FIFOs and devices by their kind only)."""
    import stat

    seen = {}
    for p in sorted(folder.rglob("*")):
        st = p.lstat()
        if stat.S_ISREG(st.st_mode):
            seen[p] = _digest(p, st.st_size)
        elif stat.S_ISLNK(st.st_mode):
            seen[p] = f"link to {p.readlink()}"
        elif not stat.S_ISDIR(st.st_mode):
            seen[p] = f"mode {stat.S_IFMT(st.st_mode):o}"
    return seen


from tests.flexshaft.catalogue import all_cases  # noqa: E402 - the section's own import

ABUSE = all_cases()


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=[pytest.mark.slow] if c.slow else []) for n, c in ABUSE.items()]
)
def test_abuse_cases_end_in_one_line_and_touch_no_input(tmp_path, capsys, monkeypatch, name):
    case = ABUSE[name]
    monkeypatch.chdir(tmp_path)
    argv = case.setup(tmp_path)
    before = _snapshot(tmp_path)
    with warnings.catch_warnings(record=True) as heard:  # a warning would reach stderr outside pytest
        warnings.simplefilter("always")
        code = main(argv)
    out = capsys.readouterr()
    err = without_progress(out.err)
    assert not heard, [str(w.message) for w in heard]
    print(f"{name:>50}: {err.strip()}")
    assert code == case.exit, (argv, code, out.err)
    if case.exit == 2:
        assert out.out == "", (argv, out.out)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("flexshaft: error: "), out.err
        for word in case.says:
            assert word in lines[0], (word, lines[0])
    else:
        assert err == "", (argv, out.err)
    after = _snapshot(tmp_path)
    assert {p: after.get(p) for p in before} == before, "an input changed"
    assert not [p for p in after if p.name.endswith(".tmp")], "a temporary file was left"


def _limited():  # pragma: no cover - runs in the child before exec
    import resource

    four_gb = 4 << 30
    resource.setrlimit(resource.RLIMIT_AS, (four_gb, four_gb))


def _run_limited(name: str, case, folder) -> str:
    """One case as its own ``python -m flexshaft`` process under a 4 GB address-space limit; '' when it
    behaved (exit code, one error line or empty stderr, within its time, inputs untouched)."""
    import os
    import subprocess
    import sys
    import time

    argv = case.setup(folder)
    before = _snapshot(folder)
    env = {**os.environ, "PYTHONWARNINGS": "default"}  # a warning must show, to be caught
    t0 = time.monotonic()
    try:
        done = subprocess.run(
            [sys.executable, "-m", "flexshaft", *argv],
            cwd=folder,
            env=env,
            capture_output=True,
            text=True,
            timeout=case.budget_s,
            preexec_fn=_limited,
        )
    except subprocess.TimeoutExpired:
        return f"{name}: still running after {case.budget_s} s"
    took = time.monotonic() - t0
    lines = without_progress(done.stderr).strip().splitlines()
    problems = []
    if done.returncode != case.exit:
        problems.append(f"exit {done.returncode}, expected {case.exit}")
    if case.exit == 2 and (len(lines) != 1 or done.stdout):
        problems.append(f"stderr {lines!r}, stdout {done.stdout[:200]!r}")
    if case.exit == 0 and without_progress(done.stderr):
        problems.append(f"stderr {done.stderr[:300]!r}")
    after = _snapshot(folder)
    if {p: after.get(p) for p in before} != before:
        problems.append("an input changed")
    return f"{name} ({took:.1f} s): {'; '.join(problems)}" if problems else ""


@pytest.mark.slow
def test_found_cases_under_a_memory_limit(tmp_path):
    """Issue 20's demonstration: every abuse case through the real CLI, in its own process with a 4 GB
    address-space limit (``ulimit -v``), ends within its budget - exit 2 with one line, or a valid result
    with nothing on stderr - and changes no input. Two at a time (the machine has two cores)."""
    from concurrent.futures import ThreadPoolExecutor

    def one(item):
        i, (name, case) = item
        folder = tmp_path / f"case{i}"
        folder.mkdir()
        return _run_limited(name, case, folder)

    with ThreadPoolExecutor(2) as pool:
        failures = [f for f in pool.map(one, enumerate(ABUSE.items())) if f]
    assert not failures, "\n".join(failures)

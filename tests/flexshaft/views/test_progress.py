"""Progress off a terminal: plain lines on stderr now and then, never a carriage return, none for quick
work; on a terminal (or asked for) the bar redrawn in place."""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap

from flexshaft.views.progress import PLAIN_INTERVAL_S, ProgressBar
from tests.conftest import EXAMPLES

# a long piece of work in a child whose stderr is a pipe: 30 steps, the clock advancing a second a step
# (a clock of its own, so the test waits for nothing); the bar decides on its own that it is no terminal
LONG_WORK = textwrap.dedent(
    """
    import itertools
    from flexshaft.views.progress import ProgressBar
    seconds = itertools.count()
    bar = ProgressBar("slicing part 1", clock=lambda: float(next(seconds)))
    for k in range(1, 31):
        bar(k, 30)
    """
)


def test_long_work_into_a_pipe_prints_plain_lines_now_and_then():
    r = subprocess.run([sys.executable, "-c", LONG_WORK], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout == "", r.stderr
    assert "\r" not in r.stderr and "#" not in r.stderr
    lines = r.stderr.splitlines()
    # the clock reads 0 at the start and k at step k: a line at 5, 10, ... 30 s, the last the end
    every = int(PLAIN_INTERVAL_S)
    assert lines == [f"slicing part 1: {k}/30 ({k} s)" for k in range(every, 31, every)]


def test_a_quick_command_into_a_pipe_prints_no_progress(tmp_path):
    # a 1 s run at 1 kHz: a thousand steps of the simulating bar in milliseconds
    cmd = [sys.executable, "-m", "flexshaft", "simulate", str(EXAMPLES / "customer1.toml")]
    cmd += ["--scenario", "step", "--torque", "100", "--measure", "speed:generator", "--duration", "1"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""


def test_the_last_line_comes_only_after_earlier_ones():
    clock = iter([0.0, 1.0, 2.0, 3.0])  # start, then three stages within the interval
    stream = io.StringIO()
    bar = ProgressBar("meshing part 2", stream=stream, clock=lambda: next(clock))
    bar.stage("meshing the volume", 0.25)
    bar.stage("placing the mid-side nodes", 0.7)
    bar.stage("done", 1.0)
    assert stream.getvalue() == ""  # quick: nothing at all


def test_a_silent_stretch_is_bridged_by_the_last_state():
    now = [0.0]
    stream = io.StringIO()
    bar = ProgressBar("meshing part 2", stream=stream, clock=lambda: now[0])
    now[0] = PLAIN_INTERVAL_S  # nothing reported yet: the heartbeat says the work is under way
    assert bar._beat()
    bar.stage("meshing the volume", 0.25)  # within the interval of that line: kept for later
    now[0] = 2 * PLAIN_INTERVAL_S + 1
    assert bar._beat()  # the mesher silent: its last state again
    bar.stage("done", 1.0)
    assert not bar._beat()  # ended: the heartbeat stops
    assert stream.getvalue().splitlines() == [
        "meshing part 2: under way (5 s)",
        "meshing part 2: meshing the volume 25 % (11 s)",
        "meshing part 2: done 100 % (11 s)",
    ]


def test_the_bar_on_a_terminal_redraws_in_place():
    stream = io.StringIO()
    bar = ProgressBar("sweep", stream=stream, enabled=True, width=4)
    bar(1, 2)
    bar(2, 2)
    assert stream.getvalue() == "\rsweep [##..] 1/2\rsweep [####] 2/2\n"
    quiet = io.StringIO()
    ProgressBar("sweep", stream=quiet, enabled=False)(1, 2)
    assert quiet.getvalue() == ""


def test_the_bars_of_one_stretch_of_work_share_its_pace():
    from flexshaft.views.progress import _pace

    stream, other = io.StringIO(), io.StringIO()
    first = _pace(stream, 1000.0)
    # slicing, then meshing, then reducing: each bar short, the work long - one pace, begun with the first
    assert _pace(stream, 1000.0 + PLAIN_INTERVAL_S / 2) is first and first.since == 1000.0
    first.activity = 1003.0
    assert _pace(stream, 1003.0 + PLAIN_INTERVAL_S) is first  # idle no longer than an interval
    later = _pace(stream, 1003.0 + 2 * PLAIN_INTERVAL_S)  # idle longer: other work, its own pace
    assert later is not first and later.since == 1003.0 + 2 * PLAIN_INTERVAL_S
    assert _pace(other, later.since) is not later  # another stream (another test's capture): its own

"""Run the ``flexshaft`` command in this process, stopped dead at a chosen point (for the tests only).

    python tests/flexshaft/study/killpoint.py EVENT COUNT ACTION -- [flexshaft arguments ...]

EVENT is a regular expression searched in ``write <path>`` (told after each of flexshaft's
atomic writes has put its file in place), ``unlink <path>`` (after a file was removed) and
``link <path>`` (before a hard link puts a new file in place: its temporary file is written).
At the COUNT-th match the ACTION happens:

- ``kill``: the process sends itself SIGKILL, as ``kill -9`` would - no handler runs, nothing
  is cleaned up or flushed;
- ``pause:READY:GO``: it creates the file READY and waits until the file GO exists (so a test can
  start a second run against one that holds its folder, then let the first one finish).

The hooks wrap ``flexshaft.system.atomic.atomic_write_bytes``, ``os.unlink`` and ``os.link`` before
flexshaft's other modules are imported, so every writer (they bind the function at import)
goes through them. Nothing of this is in flexshaft itself.
"""

from __future__ import annotations

import os
import re
import signal
import sys
import time
from pathlib import Path


def main() -> int:
    event, count, action = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    assert sys.argv[4] == "--", sys.argv
    argv = sys.argv[5:]
    pattern = re.compile(event)
    seen = [0]

    def hit(what: str) -> None:
        if not pattern.search(what):
            return
        seen[0] += 1
        if seen[0] != count:
            return
        if action == "kill":
            os.kill(os.getpid(), signal.SIGKILL)
            time.sleep(60)  # never reached: SIGKILL is not deferred
        _, ready, go = action.split(":", 2)
        Path(ready).write_text(str(os.getpid()))
        while not os.path.exists(go):
            time.sleep(0.05)

    import flexshaft.system.atomic as atomic

    write = atomic.atomic_write_bytes
    unlink, link = os.unlink, os.link

    def hooked_write(path, data, **kw):
        out = write(path, data, **kw)
        hit(f"write {os.path.abspath(path)}")
        return out

    def hooked_unlink(path, *a, **kw):
        unlink(path, *a, **kw)
        hit(f"unlink {os.path.abspath(path)}")

    def hooked_link(src, dst, *a, **kw):
        hit(f"link {os.path.abspath(dst)}")
        link(src, dst, *a, **kw)

    atomic.atomic_write_bytes = hooked_write
    os.unlink, os.link = hooked_unlink, hooked_link

    from flexshaft.cli import main as flexshaft

    return flexshaft(argv)


if __name__ == "__main__":
    sys.exit(main())

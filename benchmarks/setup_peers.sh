#!/usr/bin/env bash
# Create the peer-tool virtualenv used by the benchmarks (openTorsion, ROSS, scikit-fem with pyamg) and
# the tests that have a peer read flexshaft's files (SDynPy 0.23.0, the newest for Python 3.11, reads the
# universal files; it brings PyQt5, imported headless).
#
# Peer tools (openTorsion; ROSS 2.3.0, the newest for Python 3.11, which needs plotly<7) are installed into benchmarks/.venv-peers, a virtualenv of
# their own (git-ignored), and never into flexshaft's .venv: the benchmark calls them
# through a subprocess so that nothing of theirs can leak into our package or its tests.
#
# Idempotent: re-running reuses the virtualenv and leaves satisfied pins alone.
# Usage:  benchmarks/setup_peers.sh        (PYTHON=/path/to/python3.11 to choose the interpreter)
set -euo pipefail
cd "$(dirname "$0")"

PYTHON="${PYTHON:-python3.11}"
VENV=".venv-peers"

if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade pip
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    "opentorsion==0.3.2" "ross-rotordynamics==2.3.0" "plotly<7" "scikit-fem==12.0.2" "pyamg==5.4.1" "sdynpy==0.23.0" numpy scipy
"$VENV/bin/python" -c "import importlib.metadata as m; print('peers ready:', \
'opentorsion', m.version('opentorsion'), '| ross', m.version('ross-rotordynamics'), '| scikit-fem', m.version('scikit-fem'), '| pyamg', m.version('pyamg'), '| sdynpy', m.version('sdynpy'), '| numpy', m.version('numpy'), '| scipy', m.version('scipy'))"

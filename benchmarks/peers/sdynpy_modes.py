"""SDynPy peer read of a universal file of modes (for tests/flexshaft/exports/test_universalfile.py).

Run with the peers virtualenv (benchmarks/setup_peers.sh), never flexshaft's:

    benchmarks/.venv-peers/bin/python benchmarks/peers/sdynpy_modes.py < spec.json

Input (stdin, JSON): {"path": "modes.uff"}. SDynPy reads the file with its own reader
(``sdynpy.unv.readunv``), then its geometry (dataset 2411) and its shapes (dataset 55). Prints
{"missing": WHY} where SDynPy is not installed or cannot load, else one JSON line {"datasets": [...],
"node_ids": [...], "node_x": [...], "frequencies_hz": [...], "damping_ratios": [...],
"coordinates": ["1RX+", ...], "shapes": [[...] per mode]}.
"""

from __future__ import annotations

import json
import os
import sys

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")  # SDynPy imports Qt; nothing is shown

import numpy as np  # noqa: E402


def main() -> None:
    spec = json.load(sys.stdin)
    try:
        import sdynpy as sdpy
    except ImportError:  # an older peers virtualenv: the test skips and says so
        print(json.dumps({"missing": "sdynpy is not installed"}))
        return
    except OSError as err:  # its Qt needs system libraries (libGL ...) a minimal machine may lack
        print(json.dumps({"missing": f"sdynpy cannot load: {str(err).splitlines()[0][:200]}"}))
        return
    data = sdpy.unv.readunv(spec["path"])
    geometry = sdpy.geometry.from_unv(data)
    shapes = sdpy.shape.from_unv(data)
    matrix = shapes.shape_matrix
    coords = [str(c) for c in shapes[0].coordinate]
    print(
        json.dumps(
            {
                "datasets": sorted(int(k) for k in data),
                "node_ids": geometry.node.id.tolist(),
                "node_x": np.asarray(geometry.node.coordinate)[:, 0].tolist(),
                "frequencies_hz": np.asarray(shapes.frequency).tolist(),
                "damping_ratios": np.asarray(shapes.damping).tolist(),
                "coordinates": coords,
                "shapes": np.asarray(matrix).tolist(),
            }
        )
    )


if __name__ == "__main__":
    main()

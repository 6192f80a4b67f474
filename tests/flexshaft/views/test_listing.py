"""`modes` lists the modes up to max_hz, or the lowest 20 - never the hundreds a fine mesh has."""

from __future__ import annotations

import dataclasses

import numpy as np

import flexshaft as fs
from flexshaft.analysis.modal import DEFAULT_LISTED, listing_modes, modes_up_to


def _rod(max_hz=None) -> fs.Drivetrain:
    # A uniform free-free rod in 80 elements: f_k ≈ (k/2)·√(K/I) = 50·k Hz for the lowest.
    return fs.Drivetrain("rod", [fs.Shaft("s", stiffness=1e4, inertia=1.0, elements=80)], max_hz=max_hz)


def test_without_max_hz_the_lowest_twenty_are_computed_and_listed():
    r = listing_modes(_rod())
    assert r.count == DEFAULT_LISTED
    text = r.table()
    rows = [ln for ln in text.splitlines() if ln[:4].strip().isdigit()]
    assert len(rows) == DEFAULT_LISTED
    assert "the lowest 20 of the model's 81 (20 computed)" in text and "--max-hz" in text
    doc = r.to_dict()
    assert len(doc["modes"]) == 20
    listing = {"rule": "lowest", "max_hz": None, "shown": 20, "computed": 20, "model_modes": 81}
    assert doc["listing"] == listing


def test_all_computed_modes_are_listed_when_a_count_is_asked():
    r = listing_modes(_rod(), count=30)
    assert r.count == 30 and len(r.to_dict(count=30)["modes"]) == 30
    # computed beyond the default (an older caller): still only the lowest 20 listed unless asked
    assert len(fs.modal_analysis(_rod(), 40).to_dict()["modes"]) == 20


def test_max_hz_lists_every_mode_up_to_it_and_no_more():
    # Mode k sits near 50·k·(1 + (kπ/80)²/24) Hz (consistent inertia): 23 at 1189, 24 at 1244.
    for r, given in ((listing_modes(_rod(), max_hz=1210.0), 1210.0), (listing_modes(_rod(1210.0)), None)):
        f = r.frequencies_hz
        assert f[-1] > 1210.0 and np.count_nonzero(f <= 1210.0) == 24  # the rigid mode and 23 elastic
        doc = r.to_dict(max_hz=given)
        assert [m["index"] for m in doc["modes"]] == list(range(24))
        assert doc["listing"]["rule"] == "max_hz" and doc["listing"]["max_hz"] == 1210.0
        assert "modes up to 1210 Hz: 24 of the" in r.table(max_hz=given)


def test_modes_up_to_grows_until_past_the_range():
    r = modes_up_to(_rod(), 3000.0, first=4)
    assert r.frequencies_hz[-1] > 3000.0 and np.count_nonzero(r.frequencies_hz <= 3000.0) >= 50
    # a range past every mode: all of them
    small = dataclasses.replace(_rod(), components=(fs.Shaft("s", stiffness=1e4, inertia=1.0, elements=3),))
    assert modes_up_to(small, 1e6).count == 4

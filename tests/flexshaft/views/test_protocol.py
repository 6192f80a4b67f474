"""One result protocol: every result has ``to_dict()`` (the ``--json`` document), ``table()`` (the text the
command prints) and ``.plot()`` (a matplotlib Figure drawn through views); views import no analysis."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import flexshaft as fs
from tests.conftest import EXAMPLES

# (module, class): the results of the analyses, each drawn through views (a stage below them)
RESULTS = [
    ("flexshaft.analysis.modal", "ModalResult"),
    ("flexshaft.analysis.twist", "TwistResult"),
    ("flexshaft.analysis.statespace", "FrequencyResponse"),
    ("flexshaft.analysis.forced", "ForcedResponse"),
    ("flexshaft.analysis.simulate", "SimulationResult"),
    ("flexshaft.analysis.campbell", "CampbellDiagram"),
    ("flexshaft.analysis.sensitivity", "Sensitivities"),
    ("flexshaft.analysis.sweep", "SweepResult"),
    ("flexshaft.analysis.staged", "StagedCalibration"),
    ("flexshaft.analysis.identification", "ModelIdentification"),
]
# results of stages below views: a document and a table (their figures are views' functions, given them)
BELOW_VIEWS = [
    ("flexshaft.model.reduce", "PartReduction"),
    ("flexshaft.measurement.analyse", "SignalAnalysis"),
]


@pytest.mark.parametrize("module, name", RESULTS)
def test_every_result_has_a_document_a_table_and_a_plot(module, name):
    cls = getattr(importlib.import_module(module), name)
    for method in ("to_dict", "table", "plot"):
        assert callable(getattr(cls, method, None)), f"{name} has no {method}()"


@pytest.mark.parametrize("module, name", BELOW_VIEWS)
def test_results_below_views_have_a_document_and_a_table(module, name):
    cls = getattr(importlib.import_module(module), name)
    assert callable(getattr(cls, "to_dict", None)) and callable(getattr(cls, "table", None))


def test_the_forced_response_draws_its_peak_torques():
    result = fs.modal_analysis(fs.load_model(EXAMPLES / "customer2.toml"))
    fr = fs.forced_response(result, "motor", amplitude=100.0)
    fig = fr.plot()
    (ax,) = fig.axes
    parts = [k for k, s in enumerate(fr.signals) if s.startswith("torque:")]
    heights = np.array([bar.get_height() for bar in ax.patches]).reshape(len(parts), -1)
    np.testing.assert_array_equal(heights, fr.amplitudes[:, parts].T)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [fr.signals[k][7:] for k in parts]


def test_the_sweep_draws_each_mode_over_its_parameter():
    from flexshaft.analysis.sweep import sweep

    d = fs.load_model(EXAMPLES / "customer1.toml")
    pts = np.array([[6e4], [4e4], [5e4]])
    res = sweep(d, ["part 3.stiffness"], pts, modes=2)
    fig = res.plot()
    (ax,) = fig.axes
    assert len(ax.lines) == 2
    for k, line in enumerate(ax.lines):
        x, y = line.get_data()
        np.testing.assert_array_equal(x, [4e4, 5e4, 6e4])  # in the parameter's order
        np.testing.assert_array_equal(y, res.frequencies_hz[[1, 2, 0], k])
    assert "part 3.stiffness" in ax.get_xlabel()


def test_a_staged_calibration_draws_its_targets_and_parameters():
    from flexshaft.analysis.staged import calibrate_stages
    from flexshaft.study.tunedfile import read_targets

    staged = calibrate_stages(
        read_targets(EXAMPLES / "calibration" / "study.toml"),
        fs.load_model,
        model=EXAMPLES / "customer1.toml",
    )
    fig = staged.plot()
    assert len(fig.axes) == 2 * len(staged.stages)
    for (targets, params), st in zip(np.reshape(fig.axes, (-1, 2)), staged.stages):
        res = st.result
        tuned = [b.get_height() for b in targets.containers[1]]
        np.testing.assert_allclose(tuned, 100 * res.errors, rtol=0, atol=0)
        widths = [b.get_width() for b in params.patches]
        np.testing.assert_allclose(widths, np.nan_to_num(res.change_percent, nan=0.0), rtol=0, atol=0)

"""The whole study in one command: set-ups, analyses, exports and one report, redone only where needed.

:func:`run_study` reads a study file (:mod:`flexshaft.study.studyfile`), plans its stages
(:mod:`.plan`), runs those whose inputs changed (:mod:`.runner`, :mod:`.store`) with the same
stage functions the CLI commands call (:mod:`.stages`), and writes ``index.html`` and
``results.json`` into the output folder. :func:`run_report` is ``flexshaft report MODEL``: the
study of one model file with the default plan (:func:`default_study`), the same report.
"""

from .runner import REPORT_FILES, SECTIONS, StageRun, StudyRun, default_study, run_report, run_study

__all__ = ["run_study", "run_report", "default_study", "StudyRun", "StageRun", "SECTIONS", "REPORT_FILES"]

"""The ``flexshaft`` commands, grouped by what they are about: each module's ``COMMANDS`` declares
its commands' options and run functions (:class:`flexshaft.cli.registry.Command`).

:mod:`.modelling` (modes, demo, twist, sections, report, view, body), :mod:`.responses` (statespace,
frf, forced), :mod:`.running` (simulate, campbell, spectrum), :mod:`.tuning` (sensitivity, sweep,
calibrate), :mod:`.reducing` (reduce), :mod:`.identifying` (identify) and :mod:`.studying` (study).
"""

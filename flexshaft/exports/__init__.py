"""Exports for other tools: flexible bodies (:mod:`.bodies`: .npz, JSON, .mat, OP4 through
:mod:`.op4`, DMIG through :mod:`.dmig`, their common header in :mod:`.bodyformat`; into the Exudyn
multibody code through :mod:`.exudynbody`), linear systems (:mod:`.statespacefile`; as an FMU through
:mod:`.fmu` and :mod:`.fmudescription`) and universal files for the test lab (:mod:`.universalfile`).
Every file carries its units; every reader checks them.
"""

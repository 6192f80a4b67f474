"""Exports for other tools: flexible bodies (:mod:`.bodies`: .npz, JSON, .mat, OP4 through
:mod:`.op4`, DMIG through :mod:`.dmig`, their common header in :mod:`.bodyformat`) and linear systems
(:mod:`.statespacefile`). Every file carries its units; every reader checks them.
"""

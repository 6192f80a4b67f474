"""The OS-facing safety every stage uses: opening a user's files under ceilings (:mod:`.inputs`), the
ceilings themselves (:mod:`.limits`), nesting depth before a parser recurses (:mod:`.nesting`), atomic
writes (:mod:`.atomic`), foreign native code in a forked child (:mod:`.isolate`), the command line's
supervisor (:mod:`.watchdog`) and the thread policy (:mod:`.threads`).

No physics here: nothing in this package imports a numerical stage.
"""

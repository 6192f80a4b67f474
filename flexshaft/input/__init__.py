"""Model input: model files (:mod:`.modelfile`), numbers with units (:mod:`.quantities`), CAD parts
(:mod:`.cad`) and the disk caches of section tables, meshes and solid results (:mod:`.cache`,
:mod:`.solidcache`). Loading runs no analysis: choosing a mesh for a frequency range is a step the
caller takes after loading (:func:`flexshaft.analysis.convergence.meshed_for_own_range`).
"""

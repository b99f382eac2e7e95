"""The library: parameter sets and their loaders.

The TOML reader (:mod:`.parameters`), bicycles, riders, tyres, the thesis'
measured experiments and the kick plate's motions. It builds on
:mod:`whipple_kick.model` and never on a run or a study.
"""

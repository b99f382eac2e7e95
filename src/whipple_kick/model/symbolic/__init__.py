"""The symbolic (build) side: the SymPy derivation and the code generation, run only on a cache miss.

:mod:`.derivation` forms the equations of motion by Kane's method,
:mod:`.codegen` prints NumPy source, :mod:`.slip_build` the slip model's C
(and its NumPy oracle) and compiles it. Everything here imports SymPy; a
warm run imports none of it (a test checks that ``simulate`` never loads
SymPy): the compiled model and the generated modules are loaded from the
cache by :mod:`whipple_kick.model.slip`, :mod:`whipple_kick.model.classic` and
:mod:`whipple_kick.model.geometry`.
"""

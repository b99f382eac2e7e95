"""The model: its equations and their compiled form.

Symbols, the derivation by Kane's method and the code generation
(:mod:`.symbolic`), the compiled runtime (:mod:`.slip`, :mod:`.rhs_call`,
:mod:`.cache`), the tyre formulas (:mod:`.magic_formula`, :mod:`.transient`,
:mod:`.carcass`), the reflex delay, the energy accounting, the geometry, the
classic no-slip model and the Meijaard benchmark's conversion. The lowest
wing: it imports nothing of the library, a run or a study.
"""

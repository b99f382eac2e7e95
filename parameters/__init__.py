"""The parameter files shipped with whipple_kick: bicycles, riders and tyres.

This folder is the package ``whipple_kick.parameter_files`` (mapped onto the
repository's top-level ``parameters/`` by ``pyproject.toml``), so its TOML
files are package data: installed with the wheel and found with
``importlib.resources`` wherever the package is installed
(:func:`whipple_kick.parameters.shipped`). It holds no code.
"""

"""The thesis' kick-plate set-up, named once: its rear loads and tyre pressures (Dell'Orto 2025, Chapter 8).

The experiments and simulations ran three riders, giving static rear-tyre
loads of 570, 635 and 701 N (Table 8.3), on tyres at 300, 400 and 500 kPa
(Tables 7.9 and 8.5); Table 8.4's LQR gains are given for the three loads.
Every default, table and figure that means "the thesis' loads" or "the
thesis' pressures" reads them here.

Example
-------
>>> LOADS_N, PRESSURES_KPA, loads_text()
((570.0, 635.0, 701.0), (300.0, 400.0, 500.0), '570, 635, 701')
"""

#: Static rear-tyre loads [N] of the thesis' three riders (Table 8.3; Table 8.4 has a gain row for each).
LOADS_N = (570.0, 635.0, 701.0)
#: Inflation pressures [kPa] the tyres were measured and the kick-plate tests run at (Tables 7.9, 8.5).
PRESSURES_KPA = (300.0, 400.0, 500.0)
#: The middle load [N], the default rider's (the thesis' reference case).
REFERENCE_LOAD_N = LOADS_N[1]
#: The middle pressure [kPa], the default tyres'.
REFERENCE_PRESSURE_KPA = PRESSURES_KPA[1]


def loads_text(sep=", ", last=None):
    """The loads as words: ``"570, 635, 701"`` (``sep="/"``: ``"570/635/701"``; ``last=" or "``: ``"570, 635 or 701"``)."""
    words = [f"{load:g}" for load in LOADS_N]
    return sep.join(words) if last is None else sep.join(words[:-1]) + last + words[-1]


def pressures_text(sep=", "):
    """The pressures as words: ``"300, 400, 500"``."""
    return sep.join(f"{p:g}" for p in PRESSURES_KPA)

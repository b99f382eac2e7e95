"""An uncertainty study's P(best) for the page's load: read from the study's p_best.csv.

``whipple-kick-explorer --study DIR`` names a folder written by ``recommend-pressure --uncertain --out DIR``
(or ``scripts/uncertainty_study.py``): its ``p_best.csv`` holds, per rear load and recovery criterion, each
pressure's probability of recovering fastest with its 95 % Wilson interval
(:func:`whipple_kick.studies.uncertainty.p_best_interval`), and the share of rows where no pressure
recovered (``pressure_kpa`` empty: censored, never a number of kPa). The page shows the rows of its load
only where the study computed that load: no load is interpolated.

Example
-------
>>> rows = p_best("docs/uncertainty_study", 635.0)          # doctest: +SKIP
>>> rows["settling"][0]                                      # doctest: +SKIP
{'pressure': '300 kPa', 'p': 0.44..., 'low': 0.35..., 'high': 0.54..., 'measured_best': False}
"""
import math
import pathlib

import pandas as pd

from whipple_kick.errors import InputError
from whipple_kick.simulate.criteria import CRITERIA

#: The study's table (:meth:`whipple_kick.studies.uncertainty.UncertaintyStudy.write`).
P_BEST_FILE = "p_best.csv"
#: Its columns the page reads.
COLUMNS = ("fz_n", "criterion", "pressure_kpa", "p", "low", "high", "measured_best")


def check_folder(folder):
    """The study folder's p_best.csv path; :class:`InputError` (one line) where there is none or it lacks a column."""
    path = pathlib.Path(folder) / P_BEST_FILE
    if not path.is_file():
        raise InputError(f"study folder {str(folder)!r} has no {P_BEST_FILE} (recommend-pressure --uncertain "
                         "--out DIR writes it)")
    try:
        header = pd.read_csv(path, nrows=0).columns
    except (ValueError, OSError) as exc:
        raise InputError(f"{str(path)!r} cannot be read as a table: {exc}") from None
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(f"{str(path)!r} is not a P(best) table: it lacks the column(s) {', '.join(missing)}")
    return path


def p_best(folder, fz_n):
    """The study's P(best) rows at rear load ``fz_n`` [N], by criterion, or None where it has no such load.

    Returns
    -------
    dict or None
        ``{criterion: [{"pressure", "p", "low", "high", "measured_best"}, ...]}``, the criteria in
        :data:`~whipple_kick.simulate.criteria.CRITERIA` order; ``pressure`` is "300 kPa" or "none recovers".
    """
    table = pd.read_csv(check_folder(folder))
    at = table[(table["fz_n"] - float(fz_n)).abs() < 1e-9]
    if at.empty:
        return None
    out = {}
    for criterion in [c for c in CRITERIA if c in set(at["criterion"])]:
        rows = at[at["criterion"] == criterion]
        out[criterion] = [{"pressure": "none recovers" if math.isnan(r["pressure_kpa"]) else f"{r['pressure_kpa']:g} kPa",
                           "p": float(r["p"]), "low": float(r["low"]), "high": float(r["high"]),
                           "measured_best": bool(r["measured_best"])} for _, r in rows.iterrows()]
    return out


def loads(folder):
    """The rear loads [N] the study computed, ascending."""
    return sorted({float(v) for v in pd.read_csv(check_folder(folder))["fz_n"]})

"""The recovery criteria, in one table: how "the bicycle recovered fastest" is measured from a run.

A criterion names the run's result column it ranks (a column of a sweep's
table, :mod:`whipple_kick.studies.sweep_engine`), the criterion whose column
breaks its ties, its words, and the spread [s] below which a difference
between two pressures is not to be trusted. The recommender
(:mod:`whipple_kick.studies.recommend`), the uncertainty study
(:mod:`whipple_kick.studies.uncertainty`), their figures and the commands
read it here.

Example
-------
>>> CRITERIA["settling"].column, CRITERIA["settling"].columns
('recovery.time_s', ('recovery.time_s', 'last_peak_time_s'))
"""
from typing import NamedTuple


class Criterion(NamedTuple):
    """One recovery criterion (:data:`CRITERIA`); its first item is the column it ranks.

    Attributes
    ----------
    column : str
        The result column ranked (smaller is better).
    tie_break : str
        The key of the criterion whose column breaks ties.
    text : str
        What it measures, in words (the recommender's tables).
    short : str
        A short name (figure labels).
    spread_s : float
        Spread [s] of its value over the thesis' nine cases when the tyre coefficients change by 1 % or the
        tolerance by 100x (``scripts/recommender_spread.py``, docs/sweeps.md): a margin between the best and
        the second-best pressure below it is "no clear optimum".
    """

    column: str
    tie_break: str
    text: str
    short: str
    spread_s: float

    @property
    def columns(self):
        """The columns ranked, in order: its own, then its tie-break's."""
        return (self.column, CRITERIA[self.tie_break].column)


#: The recovery criteria by key. ``settling`` (default) is the recovery time of
#: :func:`whipple_kick.simulate.analysis.recovery`: the time from which yaw, roll and steer rates all stay
#: within 5 % of their first peaks (``recovery.time_s``). ``last_peak`` is the thesis' rule (time of the last
#: yaw-rate peak above 8 % of the largest, Section 8.3, Table 8.9; ``last_peak_time_s``). The spreads were
#: measured on the default carcass tyre transient (model slip_b574081a; on the contact-patch form they were
#: 0.218 and 0.005 s, on the thesis' force lag 0.570 and 0.011 s): settling 0.215 s (a random draw at
#: 400 kPa, 570 N), last peak 0.001 s (one sample; several draws); rtol moves neither by 1 ms.
#: scripts/doc_numbers.py checks them against a rerun (group ``spread``).
CRITERIA = {
    "settling": Criterion("recovery.time_s", "last_peak",
                          "recovery time (yaw, roll and steer rates within 5 % of their first peaks)",
                          "recovery time (settling)", 0.215),
    "last_peak": Criterion("last_peak_time_s", "settling",
                           "last-peak time (last yaw-rate peak above 8 % of the largest, thesis)",
                           "last-peak time (thesis)", 0.001),
}

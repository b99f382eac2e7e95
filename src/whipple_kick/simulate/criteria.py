"""The recovery criteria, declared once each: how "the bicycle recovered fastest" is measured from a run.

A criterion is a declaration and its function (:func:`declare`): its key,
the criterion whose value breaks its ties, its words, the spread [s] below
which a difference between two pressures is not to be trusted, and the
function that takes a run's summary and trajectory to its value [s] (None
where it is undefined: not recovered, censored; never a number standing in
for one). Where a run already reports the value (the recovery time, the
thesis' last-peak time), the declaration names that summary entry as its
``column``; otherwise its value goes into the summary's ``criteria``
section (:func:`summary_section`) and a sweep's table has it as
``criteria.<key>``. The recommender (:mod:`whipple_kick.studies.recommend`),
the uncertainty study (:mod:`whipple_kick.studies.uncertainty`), their
figures and the commands read :data:`CRITERIA`, which the declarations fill,
so a criterion declared anywhere (a test, a script) is one of theirs.

Example
-------
>>> CRITERIA["settling"].column, CRITERIA["settling"].columns
('recovery.time_s', ('recovery.time_s', 'last_peak_time_s'))
"""
from collections.abc import Callable, Mapping, Sequence
import dataclasses
import math


@dataclasses.dataclass(frozen=True)
class Criterion:
    """One recovery criterion (:data:`CRITERIA`).

    Attributes
    ----------
    key : str
        Its name (``--criterion`` spells it with hyphens).
    column : str
        The result column ranked (smaller is better): a summary entry's path (:func:`declare`).
    tie_break : str
        The key of the criterion whose column breaks ties.
    text : str
        What it measures, in words (the recommender's tables).
    short : str
        A short name (figure labels).
    spread_s : float
        Spread [s] of its value below which a margin between the best and the second-best pressure is "no
        clear optimum" (measured for each criterion where it is declared).
    value : callable
        ``value(summary, trajectory)`` -> its value [s] or None (undefined), for one run; ``trajectory`` is
        the run's table or a mapping of its columns (a sweep's lean path): read a column as
        ``numpy.asarray(trajectory[name])``.
    columns_read : tuple of str
        The trajectory columns ``value`` reads (a sweep's lean path keeps them).
    """

    key: str
    column: str
    tie_break: str
    text: str
    short: str
    spread_s: float
    value: Callable
    columns_read: tuple = ()

    @property
    def columns(self):
        """The columns ranked, in order: its own, then its tie-break's."""
        return (self.column, CRITERIA[self.tie_break].column)

    @property
    def reported(self):
        """Whether the run reports the value elsewhere in its summary (else the ``criteria`` section holds it)."""
        return self.column != f"criteria.{self.key}"


#: The recovery criteria by key, in declaration order (:func:`declare` fills it).
CRITERIA: dict = {}


def declare(key, *, tie_break, text, short, spread_s, column=None, columns_read=()):
    """Declare the criterion ``key``: a decorator on its function ``value(summary, trajectory) -> float or None``.

    Parameters
    ----------
    key : str
        A name of lower-case words joined by ``_``.
    tie_break : str
        The criterion whose value breaks ties (``key`` itself is allowed).
    text, short : str
        Its words in tables and in figure labels.
    spread_s : float
        Its spread [s] (see :class:`Criterion`), > 0.
    column : str, optional
        The summary entry (flattened path, e.g. ``"recovery.time_s"``) that already holds the value; without
        it the value goes into the summary's ``criteria`` section, column ``criteria.<key>``.
    columns_read : tuple of str
        The trajectory columns the function reads.

    Returns
    -------
    callable
        The decorator; it returns the function unchanged, after adding the criterion to :data:`CRITERIA`.
    """
    if not key.replace("_", "").isalpha() or key != key.lower():
        raise ValueError(f"criterion key {key!r}: lower-case words joined by '_'")
    if not (math.isfinite(spread_s) and spread_s > 0):
        raise ValueError(f"criterion {key!r}: spread_s must be a positive number of seconds, got {spread_s!r}")

    def add(function):
        CRITERIA[key] = Criterion(key, column or f"criteria.{key}", tie_break, text, short, float(spread_s),
                                  function, tuple(columns_read))
        return function
    return add


class _Attribute(Mapping):
    """A read-only mapping key -> one attribute of each declared criterion, read when asked (so it follows
    :data:`CRITERIA`)."""

    def __init__(self, attribute):
        self._attribute = attribute

    def __getitem__(self, key):
        return getattr(CRITERIA[key], self._attribute)

    def __iter__(self):
        return iter(CRITERIA)

    def __len__(self):
        return len(CRITERIA)

    def __repr__(self):
        return repr(dict(self))


def attribute(name):
    """``{key: criterion.<name>}`` over the declared criteria, kept up to date (e.g. ``attribute("spread_s")``)."""
    if name not in Criterion.__dataclass_fields__:
        raise ValueError(f"a criterion has no attribute {name!r}")
    return _Attribute(name)


class Listing(Sequence):
    """A read-only sequence made by ``function()`` each time it is read (names that follow :data:`CRITERIA`)."""

    def __init__(self, function):
        self._function = function

    def __getitem__(self, index):
        return tuple(self._function())[index]

    def __len__(self):
        return len(tuple(self._function()))

    def __repr__(self):
        return repr(tuple(self._function()))


def summary_section(summary, trajectory):
    """The summary's ``criteria`` section: the value [s] or None of each criterion the run reports nowhere else.

    Raises
    ------
    ValueError
        A criterion's function gave something other than a finite number or None (a bug in its declaration).
    """
    out = {}
    for key, c in CRITERIA.items():
        if c.reported:
            continue
        value = c.value(summary, trajectory)
        if value is not None:
            value = float(value)
            if not math.isfinite(value):
                raise ValueError(f"criterion {key!r} gave {value!r}: a value is a finite number of seconds, or None "
                                 "where it is undefined")
        out[key] = value
    return out


# ------------------------------------------------------------------ the criteria

#: The spreads were measured over the thesis' nine cases when the tyre coefficients change by 1 % or the
#: tolerance by 100x (``scripts/recommender_spread.py``, docs/sweeps.md), on the default carcass tyre transient
#: (model slip_b574081a; on the contact-patch form they were 0.218 and 0.005 s, on the thesis' force lag 0.570
#: and 0.011 s): settling 0.215 s (a random draw at 400 kPa, 570 N), last peak 0.001 s (one sample; several
#: draws); rtol moves neither by 1 ms. scripts/doc_numbers.py checks them against a rerun (group ``spread``).


@declare("settling", tie_break="last_peak", column="recovery.time_s",
         text="recovery time (yaw, roll and steer rates within 5 % of their first peaks)",
         short="recovery time (settling)", spread_s=0.215)
def settling(summary, trajectory):
    """The recovery time of :func:`whipple_kick.simulate.analysis.recovery` (default): the time from which yaw,
    roll and steer rates all stay within 5 % of their first peaks."""
    return summary["recovery"]["time_s"]


@declare("last_peak", tie_break="settling", column="last_peak_time_s",
         text="last-peak time (last yaw-rate peak above 8 % of the largest, thesis)",
         short="last-peak time (thesis)", spread_s=0.001)
def last_peak(summary, trajectory):
    """The thesis' rule (Section 8.3, Table 8.9): the time of the last yaw-rate peak above 8 % of the largest."""
    return summary["metrics"].get("last_peak_time_s")

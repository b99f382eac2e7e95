"""The page's form: its fields, derived from the Scenario's declarations, and what the page sends, parsed.

Each field the page shows (:data:`PAGE_FIELDS`) takes its label, unit, range, choices, default and help
from its declaration (:data:`whipple_kick.simulate.scenario.SETTINGS`); nothing of them is written here
again. What the page sends is checked as ``simulate`` checks its flags, with the same one-line messages:
a text that is not a number (the flag's own message), a value outside the declared range or choices (the
Scenario's :class:`~whipple_kick.errors.InputError`), a rear load no rider can put on the bicycle (the
command line's load check), then the whole scenario (:func:`whipple_kick.simulate.assembly.preflight`). A
message goes beside the field it names.

Example
-------
>>> scenario = parse({"pressure_kpa": "300", "fz_n": "701"})
>>> scenario.pressures, scenario.fz_n
((300.0, 300.0), 701.0)
>>> try:
...     parse({"pressure_kpa": "0"})
... except FormError as exc:
...     exc.errors
{'pressure_kpa': 'pressure = 0.0 kPa is outside the allowed range (0, inf] kPa'}
"""
import argparse
import dataclasses
import re

from whipple_kick import cli
from whipple_kick.errors import InputError
from whipple_kick.library import bicycles, inputs, tyres
from whipple_kick.simulate import assembly
from whipple_kick.simulate.scenario import SETTINGS, Scenario, UnusedFieldError

#: The Scenario fields on the page, in the page's order: the bicycle (a shipped set, a path, or a
#: BicycleParameters file sent with the form), the tyres and their pressures, the load, the speed, the rider,
#: the kick and the run's length. Every other field keeps its default, as a flag not given does.
PAGE_FIELDS = ("bicycle", "tyre", "pressure_kpa", "pressure_front_kpa", "pressure_rear_kpa", "fz_n", "speed",
               "rider_body", "controller", "kick_profile", "kick_displacement", "kick_direction", "duration")
#: Kick profiles the page leaves out: a table needs a CSV file of the plate's motion (``simulate --kick-table``).
LEFT_OUT_CHOICES = {"kick_profile": (inputs.TABLE_PROFILE,)}
#: The key under which a message that names no page field is returned (:class:`FormError`).
GENERAL = "form"


@dataclasses.dataclass(frozen=True)
class Field:
    """One field of the page, from its declaration.

    Attributes
    ----------
    name : str
        The Scenario field (the form's key).
    label, unit : str
        Its words and unit, as messages write them.
    choices : tuple of str
        The values of a select; empty: a text input.
    value : str
        Its default as the page shows it ("" for None: the field's rule).
    placeholder : str
        What an empty input means.
    range_text : str
        The allowed range, as the error messages write it ("(0, 15] m/s"), or "".
    help : str
        The declaration's documentation.
    suggestions : tuple of str
        Values offered to a text input (the shipped bicycles).
    """

    name: str
    label: str
    unit: str
    choices: tuple
    value: str
    placeholder: str
    range_text: str
    help: str
    suggestions: tuple = ()


class FormError(InputError):
    """What the page sent is refused: ``errors`` maps a field (or :data:`GENERAL`) to its one-line message."""

    def __init__(self, errors):
        super().__init__("; ".join(errors.values()))
        self.errors = errors


def _text(value):
    """A default as the page shows it."""
    if value is None:
        return ""
    return f"{value:g}" if isinstance(value, float) else str(value)


def plain(doc):
    """A declaration's text without its reStructuredText markup, for a tooltip.

    Example
    -------
    >>> plain("Tyre file (:func:`~whipple_kick.library.tyres.load`); ``None``: the rule.")
    'Tyre file (whipple_kick.library.tyres.load); None: the rule.'
    """
    return re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", doc).replace("``", "")


def _range_text(s):
    """The declared range as :func:`whipple_kick.errors.check_range` writes it, or "" where there is none."""
    if s.low is None and s.high is None:
        return ""
    low = "-inf" if s.low is None else f"{s.low:g}"
    high = "inf" if s.high is None else f"{s.high:g}"
    return f"{'(' if s.low_open else '['}{low}, {high}{')' if s.high_open else ']'} {s.unit}".rstrip()


def _choices(name):
    """A select's values: the declared choices (less :data:`LEFT_OUT_CHOICES`), the shipped tyres, or none."""
    if name == "tyre":
        return tuple(t[0] for t in tyres.available())
    return tuple(c for c in SETTINGS[name].choices if c not in LEFT_OUT_CHOICES.get(name, ()))


def fields():
    """The page's :class:`Field` of every name in :data:`PAGE_FIELDS`."""
    out = []
    for name in PAGE_FIELDS:
        s = SETTINGS[name]
        if s.default is not None:
            placeholder = _text(s.default)
        elif s.none_means is not None:
            placeholder = f"default {_text(s.none_means)}"
        elif "(default: ``" in s.doc:   # "(default: ``pressure_kpa``)": that field's value
            other = s.doc.split("(default: ``")[1].split("``")[0]
            placeholder = f"default: the {SETTINGS[other].words}" if other in SETTINGS else f"default: {other}"
        else:
            placeholder = "its default rule"
        out.append(Field(name=name, label=s.words, unit=s.unit.strip("()"), choices=_choices(name),
                         value=_text(s.default), placeholder=placeholder, range_text=_range_text(s), help=plain(s.doc),
                         suggestions=tuple(bicycles.available()) if name == "bicycle" else ()))
    return out


def _value(name, text):
    """The field's value from the page's text (None: not given); raises InputError with the flag's message."""
    s = SETTINGS[name]
    text = (text or "").strip()
    if not text:
        return None
    kinds = (s.type, *getattr(s.type, "__args__", ()))
    if float in kinds and not s.choices:
        try:
            value = cli._number(s.unit.strip("()"))(text)
        except argparse.ArgumentTypeError as exc:
            raise InputError(str(exc)) from None
    else:
        value = text
    s.check(value)
    return value


def field_of(message):
    """The page field a message names (the longest field words it starts with, or follows "unknown" with:
    "unknown bicycle 'x'"), or :data:`GENERAL`."""
    named = [name for name in PAGE_FIELDS
             if message.startswith((SETTINGS[name].words + " ", f"unknown {SETTINGS[name].words} "))]
    return max(named, key=lambda name: len(SETTINGS[name].words), default=GENERAL)


def parse(values, bicycle_file=None):
    """The validated Scenario of what the page sent, or :class:`FormError` with a message per field.

    Parameters
    ----------
    values : dict of str
        Field name -> the text the page sent; a field left out or empty keeps its default.
    bicycle_file : str or pathlib.Path, optional
        A BicycleParameters bicycle file (``<Name>Benchmark.txt``) sent with the form: the bicycle.
    """
    changes, errors = {}, {}
    for name in PAGE_FIELDS:
        try:
            value = _value(name, values.get(name))
        except InputError as exc:
            errors[name] = str(exc)
            continue
        if value is not None:
            changes[name] = value
    if bicycle_file is not None and "bicycle" not in errors:
        changes["bicycle"] = str(bicycle_file)
    if errors:
        raise FormError(errors)
    scenario = Scenario(**changes)
    try:
        if scenario.fz_n is not None:
            cli._check_loads(scenario.bicycle, [scenario.fz_n], scenario.rider)
    except InputError as exc:
        raise FormError({"fz_n": str(exc)}) from None
    try:
        return assembly.preflight(scenario)
    except UnusedFieldError as exc:
        raise FormError({exc.field if exc.field in PAGE_FIELDS else GENERAL: str(exc)}) from None
    except InputError as exc:
        raise FormError({field_of(str(exc)): str(exc)}) from None


def stability_scenario(scenario, speed):
    """The scenario the ``stability`` command would build from the page's fields: the fields it has flags for,
    the tyres' zero-slip offsets removed (its default, ``--tyre-offsets zero``), at the sweep's first speed."""
    kept = {name: getattr(scenario, name) for name in PAGE_FIELDS if "stability" in SETTINGS[name].commands}
    return Scenario(**kept, symmetric_tyres=True, speed=float(speed))

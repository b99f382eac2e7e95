"""How a :class:`~whipple_kick.simulate.scenario.Scenario` field is declared, and what follows from it.

Each field is declared once, in the class body, with :func:`setting` (or
:func:`part_setting` for a declared part's field): its default, unit,
range or choices, group, the mechanism that reads it, the assembly steps'
views that hold it, and its command-line flag and help. From these
declarations come the class's documentation, the per-field checks of
:meth:`~whipple_kick.simulate.scenario.Scenario.validate`, the groups, the
mechanism refusal table, the views and the command-line flags
(:mod:`whipple_kick.cli`). Everything here works on a class, so a subclass
that adds a field (``class MyScenario(Scenario): new: float = setting(...)``)
gets its checks, group, refusal, views and flag with no other edit.

Example
-------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Run:
...     speed: float = setting(3.0, "Forward speed [m/s].", unit="m/s", low=0.0, high=15.0)
>>> settings(Run)["speed"].unit, settings(Run)["speed"].default
('m/s', 3.0)
"""
from dataclasses import MISSING, dataclass, field, fields, make_dataclass, replace
import functools
import textwrap

from whipple_kick.errors import InputError, check_range
from whipple_kick.model import parts

#: The field groups, in order (:data:`whipple_kick.simulate.scenario.FIELD_GROUPS`).
GROUPS = ("physics", "run", "numerics", "compatibility")
#: The commands whose parsers take the scenario's flags (:mod:`whipple_kick.cli`).
COMMANDS = ("simulate", "stability", "validate")
#: A flag every command that builds a scenario has (tyres, bicycle and rider, control).
EVERY_COMMAND = COMMANDS
#: A flag of the commands that set the pressures and loads per run (not ``validate``, which sets them per case).
CASE_COMMANDS = ("simulate", "stability")
#: A flag of ``simulate`` alone (the kick, the run).
SIMULATE = ("simulate",)


@dataclass(frozen=True)
class Setting:
    """One Scenario field's declaration (:func:`setting`); ``name``, ``default`` and ``type`` come from the field.

    Attributes
    ----------
    doc : str
        What the field is, for the class's documentation (one paragraph).
    unit : str
        Unit of a number, as messages and ``--help`` show it ("m/s", "(factor)").
    low, high : float or None
        Allowed range of a number (None: unbounded; both None: not checked here).
    low_open, high_open : bool
        Exclude the bound itself.
    choices : tuple of str
        Allowed values of a string field (also the flag's choices).
    check_choices : bool
        False where the step that reads the field checks it with its own message.
    label : str
        The field in messages ("settle time"); default: the name with spaces.
    group : str
        One of :data:`GROUPS`.
    mechanisms : tuple of str
        Keys of the mechanisms that read it (a Scenario's mechanism table, or a declared part's name): it
        is refused, given other than its default, while one of them is off.
    views : tuple of str
        The assembly steps' views that hold it (``"bicycle"``, ``"tyre"``, ``"body"``, ``"gains"``,
        ``"model"``, ``"design"``).
    commands : tuple of str
        The commands that give it a flag (:data:`COMMANDS`); empty: no flag.
    section : str
        The ``--help`` section of its flag.
    flag : str
        The flag (default ``--`` + the name, dashed).
    help : str
        The flag's help; ``{default}`` is the default as the flag takes it, other ``{names}`` the command's.
    metavar : str
        The flag's value placeholder (default: from the unit).
    exclusive : str
        Flags with the same name here are mutually exclusive.
    none_means : object
        What the default ``None`` stands for, where the field's rule is a value (635 N).
    part : str
        The declared part (:mod:`whipple_kick.model.parts`) whose parameter it sets.
    refuse_low : str
        With ``part``: the low end itself is refused while the part is selected, and this says why.
    """

    doc: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple = ()
    check_choices: bool = True
    label: str = ""
    group: str = "physics"
    mechanisms: tuple = ()
    views: tuple = ()
    commands: tuple = ()
    section: str = ""
    flag: str = ""
    help: str = ""
    metavar: str = ""
    exclusive: str = ""
    none_means: object = None
    part: str = ""
    refuse_low: str = ""
    name: str = ""
    default: object = None
    type: object = None

    @property
    def words(self):
        """The field in messages."""
        return self.label or self.name.replace("_", " ")

    @property
    def option(self):
        """The command-line flag (``--`` + the name, dashed, unless declared)."""
        return self.flag or "--" + self.name.replace("_", "-")

    @property
    def optional(self):
        """Whether None is a value of the field (its default, or ``float | None``)."""
        return self.default is None or type(None) in getattr(self.type, "__args__", ())

    def check(self, value):
        """Raise :class:`InputError` for a value outside the declared range or choices (None passes where allowed)."""
        if value is None and self.optional:
            return
        if self.choices and self.check_choices and value not in self.choices:
            raise InputError(f"{self.words} {value!r} is unknown; choose one of {', '.join(self.choices)}")
        if self.low is not None or self.high is not None:
            check_range(self.words, value, self.low, self.high, self.unit, low_open=self.low_open,
                        high_open=self.high_open)

    def entry(self):
        """The field's entry in the class's numpy-style Attributes section."""
        kind = ("{" + ", ".join(f'"{c}"' for c in self.choices) + "}" if self.choices
                else getattr(self.type, "__name__", None) or str(self.type).replace(" | None", " or None"))
        if self.default is None and self.choices:
            kind += " or None"
        body = textwrap.fill(self.doc, 104, initial_indent=" " * 8, subsequent_indent=" " * 8)
        return f"    {self.name} : {kind}\n{body}\n"


def setting(default, doc, **declared):
    """A Scenario field with its declaration (:class:`Setting`), for the class body.

    ``default`` and ``doc`` first, then the declaration's other attributes by
    keyword: ``speed: float = setting(3.0, "Forward speed [m/s].", unit="m/s", low=0.0)``.
    """
    return field(default=default, metadata={"setting": Setting(doc=doc, **declared)})


def part_setting(part_name, field_name):
    """The Scenario field that sets a declared part's parameter (:class:`whipple_kick.model.parts.Field`).

    Its range, unit, default, words and source come from the part's declaration; it sits in the physics
    group, is read by the part (refused while the scenario does not select it), is held by the body's view
    and has a flag in the rider's-body section of ``--help``.
    """
    part = parts.REGISTRY[part_name]
    f = next(f for f in part.fields if f.name == field_name)
    title = part.title or part.name
    low = f"more than {f.low:g}" if f.refuse_low else f"{f.low:g}"   # its low end is refused (validate)
    interval = f"{'(' if f.refuse_low else '['}{f.low:g}, {f.high:g}]"
    return setting(f.default, f"The {f.label} of {title} [{f.unit}], {low} to {f.high:g}; default {f.default:g}: "
                   f"{f.source}.", unit=f.unit, low=f.low, high=f.high, label=f.label, mechanisms=(part.name,),
                   views=("body",), commands=EVERY_COMMAND, section="rider's body",
                   help=f"{f.label} of {title} in {f.unit}, {interval} (default {{default}})", part=part.name,
                   refuse_low=f.refuse_low)


@functools.cache
def settings(cls):
    """Every field's :class:`Setting` of dataclass ``cls``, by name, in field order."""
    out = {}
    for f in fields(cls):
        declared = f.metadata.get("setting")
        if declared is None:
            raise TypeError(f"{cls.__name__}.{f.name} is not declared with setting()")
        out[f.name] = replace(declared, name=f.name, default=None if f.default is MISSING else f.default,
                              type=f.type)
    return out


def groups(cls):
    """The field names of each group (:data:`GROUPS`), in field order."""
    table = {group: [] for group in GROUPS}
    for s in settings(cls).values():
        table[s.group].append(s.name)
    return {group: tuple(names) for group, names in table.items()}


def documented(cls):
    """Class decorator: append every field's entry (:meth:`Setting.entry`) to the docstring's Attributes.

    The entries go before the docstring's Notes section, or at its end.
    """
    text = "".join(s.entry() for s in settings(cls).values())
    head = "\n    Attributes\n    ----------\n" + text
    notes = "\n    Notes\n    -----"
    doc = cls.__doc__ or ""
    cls.__doc__ = doc.replace(notes, head + notes, 1) if notes in doc else doc.rstrip() + "\n" + head
    return cls


@functools.cache
def view_class(cls, name, class_name, base, derived=()):
    """The frozen view ``name`` of ``cls``: dataclass ``class_name`` on ``base`` with the fields declared with it.

    ``derived`` pairs ``(attribute, fields it replaces)``: the view holds the Scenario's derived attribute
    (a property) in place of the fields it comes from, at the first one's place.
    """
    replaced = {f: attr for attr, sources in derived for f in sources}
    members, lines, seen = [], [], set()
    for s in settings(cls).values():
        if name not in s.views:
            continue
        member = replaced.get(s.name, s.name)
        if member in seen:
            continue
        seen.add(member)
        if member == s.name:
            kind, doc = s.type, s.doc
        else:   # a derived attribute: the Scenario's property
            prop = getattr(cls, member)
            kind, doc = prop.fget.__annotations__.get("return", object), prop.__doc__ or ""
        members.append((member, kind))
        first = doc.split(". ")[0].split("\n")[0].rstrip(".")
        lines.append(f"    {member} : {getattr(kind, '__name__', kind)}\n        {first}.\n")
    lines = "".join(lines)
    return make_dataclass(class_name, members, bases=(base,), frozen=True, namespace={
        "__doc__": (base.__doc__ or "").rstrip() + "\n\n    Attributes\n    ----------\n" + lines,
        "__module__": base.__module__})

"""What the compiled model is: its declared parts, the reflex's delay filter and its tyre transient form.

A :class:`Model` is chosen once, from the scenario's settings (the rider's body, its arms, the reflex
delay, the tyre transient), and travels with the parameters (:class:`Parameters`): the compiled library,
the steady solver and the linearisation read it there, and nothing infers the model from which parameter
names a mapping holds or what their values are.
"""
from dataclasses import dataclass

from whipple_kick.model import parts, transient
import whipple_kick.model.slip.layout as layouts  # the module by its full name, not through the package


@dataclass(frozen=True)
class Model:
    """The model's description.

    Attributes
    ----------
    parts : tuple of str
        The declared parts it has (:mod:`whipple_kick.model.parts`), in build order (:func:`whipple_kick.model.parts.named`); () the rigid rider.
    delayed_reflex : bool
        Whether it has the reflex's delay filter (:mod:`whipple_kick.model.reflex`): a nonzero delay needs it.
    transient : str
        Its tyre transient form (:data:`whipple_kick.model.transient.FORMS`).
    """

    parts: tuple = ()
    delayed_reflex: bool = False
    transient: str = transient.DEFAULT_TRANSIENT

    def __post_init__(self):
        object.__setattr__(self, "parts", tuple(p.name for p in parts.named(tuple(self.parts))))
        object.__setattr__(self, "delayed_reflex", bool(self.delayed_reflex))
        transient.check(self.transient)

    @property
    def layout(self):
        """Its states', parameters' and outputs' names (:class:`whipple_kick.model.slip.layout.Layout`, shared)."""
        return layouts.for_parts(self.parts, self.delayed_reflex)

    @property
    def key(self):
        """A short name: the layout's key and the tyre form (``"trunk+delay carcass"``)."""
        return f"{self.layout.key} {self.transient}"


class Parameters(dict):
    """The model's parameters by name (a dict) with the :class:`Model` they are for (``.model``).

    ``copy`` and :meth:`replace` keep the model; a plain ``dict(...)`` of it does not, and the compiled
    model refuses a mapping without one.
    """

    def __init__(self, model, values=()):
        super().__init__(values)
        self.model = model

    def copy(self):
        """A copy with the same model."""
        return Parameters(self.model, self)

    def replace(self, **changes):
        """A copy with ``changes`` (names the model has: an unknown one is refused)."""
        unknown = [n for n in changes if n not in self]
        if unknown:
            raise KeyError(f"no parameter {unknown[0]!r} in the {self.model.key} model")
        out = self.copy()
        out.update(changes)
        return out

    def __reduce__(self):   # pickled to sweep workers: the model with the values
        return (Parameters, (self.model, dict(self)))

    def __repr__(self):
        return f"Parameters({self.model!r}, {dict.__repr__(self)})"

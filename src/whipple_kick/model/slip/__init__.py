"""The slip model at run time: the compiled C right-hand side, its parameters, jumps and linearisation.

The C library is built from the symbolic equations by :mod:`whipple_kick.model.symbolic.slip_build`
on a cache miss (once per version); this module only loads it (ctypes) with
the plain-data metadata written beside it, so a warm run imports neither
SymPy nor the derivation. One C call evaluates the right-hand side: the
kick-plate profile, the dependent speeds, slip and camber, normal forces,
the tyre block of the active transient form (:mod:`whipple_kick.model.transient`,
the ``tyre_transient`` parameter), the steer controller, Kane's equations
and the rates of the energy quadratures (:mod:`whipple_kick.model.energy`); the
named outputs (:data:`OUTPUTS`) only when asked for.

State vector layout of the base model (the rigid rider; by name, see :data:`STATE_NAMES`): q1..q10, the
independent speeds u1 u2 u3 u4 u7 u9 u10, four tyre states in fixed slots
(:func:`tyre_state_names`: the contact patch's slip and camber angles, or
the thesis' relaxed forces fyr fyf mzr mzf, which :data:`X` also names),
the reflex delay filter's four states, and the quadratures of :data:`whipple_kick.model.energy.QUADRATURE_STATES`;
a model with declared parts (:mod:`whipple_kick.model.parts`: the leaning upper body) appends their
coordinates and speeds (:class:`Layout`); :class:`Model` says which model a parameter set is for
(:class:`Parameters`).

The package, one module per concern: :mod:`.layout` (names and indices),
:mod:`.compiled` (the compiler, the cache entry, loading), :mod:`.call`
(:class:`CompiledRHS`), :mod:`.parameters` (the model's parameters by
name), :mod:`.jumps` (the plate stop) and :mod:`.linear` (the heading-frame
linearisation); the steady motion is :mod:`whipple_kick.simulate.steady`'s.
Everything is reachable as ``whipple_kick.model.slip.<name>``.
"""
from .call import (  # noqa: F401 -- the package's names, as before the split
    CompiledRHS,
    parameter_vector,
)
from .compiled import (  # noqa: F401 -- the package's names, as before the split
    library,
    library_path,
    metadata_layout,
    model_hash,
)
from .description import (  # noqa: F401 -- the package's names
    Model,
    Parameters,
)
from .jumps import (  # noqa: F401 -- the package's names, as before the split
    kept_speeds_slide,
    velocity_jump,
)
from .layout import (  # noqa: F401 -- the package's names, as before the split
    COORDINATES,
    DEPENDENT,
    DYNAMIC_STATES,
    IGNORABLE,
    INDEPENDENT,
    JACOBIAN_EVALUATIONS,
    OUT,
    OUTPUT_NAMES,
    OUTPUTS,
    PARAMETER_NAMES,
    PATCH_STATES,
    QUADRATURE_STATES,
    REFLEX_STATES,
    SPEEDS,
    STATE_NAMES,
    TYRE_STATES,
    Layout,
    P,
    X,
    for_parts,
    tyre_state_names,
)
from .linear import (  # noqa: F401 -- the package's names, as before the split
    HOLONOMIC_ROW,
    LINEAR_STATES,
    heading_linearisation,
    heading_state,
    linear_state_space,
    linear_states,
    linearize,
    solve_pitch,
)
from .parameters import (  # noqa: F401 -- the package's names, as before the split
    FY_OFFSET_INDICES,
    MZ_OFFSET_INDICES,
    SLIP_SPEEDS,
    ModelOptions,
    gain_names,
    gain_states,
    model_parameters,
    tyre_parameters,
)

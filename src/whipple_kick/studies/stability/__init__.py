"""Linear stability of the slip model against speed: weave, capsize, wobble and the tyre modes.

For a bicycle, rider, tyre, pressure and load (a
:class:`whipple_kick.simulate.scenario.Scenario`), at each speed of a sweep:

1. the steady motion is found (:func:`whipple_kick.simulate.steady.steady_state`,
   continued from the previous speed's solution; the robust
   :func:`whipple_kick.simulate.steady.find_steady_state` where that fails);
2. the slip model is linearised about it in the heading frame
   (:func:`whipple_kick.model.slip.heading_linearisation`) at constant speed (the
   forward-speed row and column removed, as the classic model treats speed
   as a parameter), open loop (no steer torque; about the uncontrolled
   steady motion) and closed loop (the scenario's rider, designed at each
   speed unless ``design_speed`` fixes it);
3. its eigenvalues and eigenvectors are followed across speed
   (:func:`track`: eigenvalue distance plus eigenvector dissimilarity,
   optimal assignment) and each mode is named from where its eigenvector
   carries its amplitude (:func:`mode_content`, :func:`name_mode`).

The classic no-slip model of the same bicycle (and rider) is computed beside
it. :func:`analyse` returns the tables and a summary (weave and capsize
speeds, self-stable speed range, wobble); :func:`linear_model` gives the
linear model at one speed as a :class:`LinearModel`, whose
:meth:`LinearModel.state_space` is a ``control.StateSpace`` with named states,
the steer torque as input and the states as outputs. The ``stability``
command writes ``eigenvalues.csv``, ``stability.png`` and ``summary.json``
(docs/stability.md).

The package, one module per concern: :mod:`.linear` (the linear model at
one speed), :mod:`.modes` (mode content, names, tracking), :mod:`.sweep`
(the sweep over speed, :func:`analyse`), :mod:`.summary` (weave and capsize
speeds, stable ranges, wobble), :mod:`.response` (free responses that check
an eigenvalue on the nonlinear model), :mod:`.report` (figure, printed
lines, files) and :mod:`.pressure_load` (the pressure x load table); the
constants in :mod:`._constants`. Everything is reachable as
``whipple_kick.studies.stability.<name>``.

Example
-------
>>> import numpy as np
>>> from whipple_kick import stability
>>> from whipple_kick import Scenario
>>> result = stability.analyse(Scenario(symmetric_tyres=True), np.arange(2.0, 6.01, 0.5),
...                            loops=("open",))
>>> round(result.summary["slip"]["open"]["weave_speed_m_s"], 2)
3.82
"""
from ._constants import (  # noqa: F401 -- the package's names, as before the split
    BODY_GROUPS,
    DEFAULT_SPEEDS,
    DOMINANT_SHARE,
    GROUPS,
    LOOPS,
    MAX_SPEEDS,
    MIN_NAME_RUN,
    MODE_DESCRIPTIONS,
    MODES,
    TURN_NOTE_DEG,
    TYRE_SHARE,
    WOBBLE_MIN_FREQUENCY_HZ,
    ZERO_TORQUE_N_M,
)
from .linear import (  # noqa: F401 -- the package's names, as before the split
    STATES,
    LinearModel,
    active_states,
    linear_model,
    linearise,
    state_labels,
)
from .modes import (  # noqa: F401 -- the package's names, as before the split
    groups_of,
    match_cost,
    mode_content,
    name_mode,
    name_tracks,
    track,
)
from .pressure_load import (  # noqa: F401 -- the package's names, as before the split
    THESIS_LOADS_N,
    THESIS_PRESSURES_KPA,
    case_row,
    pressure_load_figure,
    pressure_load_table,
)
from .report import (  # noqa: F401 -- the package's names, as before the split
    MODE_COLOURS,
    SLOW_RANGE,
    describe,
    figure,
    range_text,
    report_lines,
    speeds_text,
    write,
)
from .response import (  # noqa: F401 -- the package's names, as before the split
    fit_eigenvalue,
    free_response,
    modal_coordinate,
    perturbed_state,
)
from .sweep import (  # noqa: F401 -- the package's names, as before the split
    Stability,
    analyse,
    check_speeds,
    parse_speeds,
)

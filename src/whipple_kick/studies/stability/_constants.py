"""Constants of the stability analysis: loops, mode vocabulary, naming and sweep thresholds."""
#: Loops analysed: without rider control, and with the scenario's rider.
LOOPS = ("open", "closed")
#: Content groups of an eigenvector (:func:`mode_content`).
GROUPS = ("roll", "steer", "heading", "vertical", "rear_tyre", "front_tyre")
#: Content groups added when the model has the rider's body (a leaning rider, a delayed reflex): the
#: upper body's lean on the hip and the reflex delay filter's states.
BODY_GROUPS = ("lean", "reflex")
#: Mode names (:func:`name_mode`), in the order the figure's legend lists them.
MODES = ("weave", "capsize", "caster", "wobble", "arm_steer", "lean", "lateral_rear", "lateral_front",
         "relaxation_rear", "relaxation_front", "vertical", "reflex_delay")
#: What each mode name means (summary.json, docs/stability.md).
MODE_DESCRIPTIONS = {
    "weave": "oscillation of roll, steer and heading together (the knife-edge bicycle's weave)",
    "capsize": "non-oscillatory, roll-dominated: the bicycle falls over slowly (or recovers)",
    "caster": "steer-dominated, non-oscillatory or slow: the front frame aligns with its motion",
    "wobble": "steer-dominated oscillation with the front tyre lagging, faster than WOBBLE_MIN_FREQUENCY_HZ",
    "lateral_rear": "fast oscillation of heading and lateral position on the rear tyre's lateral "
                    "carcass stiffness (cornering stiffness / relaxation length), little roll or steer",
    "lateral_front": "the same on the front tyre",
    "relaxation_rear": "non-oscillatory, the rear tyre's contact patch relaxing toward its kinematic slip",
    "relaxation_front": "the same for the front tyre",
    "vertical": "tyre compressions (bounce and pitch on the vertical tyre stiffness)",
    "arm_steer": "arms on the bar: steer-dominated oscillation on the arms' stiffness and damping, faster than "
                 "WOBBLE_MIN_FREQUENCY_HZ, with the front tyre lagging less than in the wobble (with more, "
                 "it is still named wobble: the wobble on the arms)",
    "lean": "leaning rider: the upper body's lean on the hip's spring-damper carries more of the amplitude "
            "than roll, steer, heading or either tyre (oscillatory, or real when the hip is overdamped)",
    "reflex_delay": "delayed reflex: the Pade delay filter's own poles (its states carry most of the amplitude, "
                    "scaled by the reflex's torque per radian); a filter artefact, not a motion of the bicycle",
}
#: A steer-dominated oscillation slower than this [Hz] is the caster mode coupled with the
#: front tyre's relaxation (at walking speed), not wobble: bicycle wobble is reported at
#: 4-10 Hz (thesis Section 2.2.1; Meijaard et al. 2007 call the fast steer mode caster).
WOBBLE_MIN_FREQUENCY_HZ = 2.0
#: ``|steer torque|`` [N m] below which a steady motion of one loop is also the other loop's.
ZERO_TORQUE_N_M = 1e-12
#: Fewest consecutive sweep speeds a mode name must hold along a track (shorter runs take a
#: neighbour's name): no flicker where a content hovers near a rule's threshold.
MIN_NAME_RUN = 3
#: A share of at least this of an eigenvector's amplitude makes a group dominant.
DOMINANT_SHARE = 0.5
#: The front tyre takes part in a steer oscillation (wobble, or the slow caster pair) with at
#: least this share; the weave's front-tyre lag is 0.01-0.04.
TYRE_SHARE = 0.1
#: Default speed sweep [m/s] of the ``stability`` command: start, stop, step.
DEFAULT_SPEEDS = (0.5, 10.0, 0.05)
#: A steady lean above this [deg] is reported: the eigenvalues are then those of a turn.
TURN_NOTE_DEG = 5.0
#: Largest number of speeds in one sweep (about 10 ms each).
MAX_SPEEDS = 2000


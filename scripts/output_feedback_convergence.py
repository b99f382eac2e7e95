"""How far from a stationary point the output-feedback LQR designs stop: the tolerance of its convergence check.

``whipple_kick.simulate.control.output_feedback_lqr`` minimises the LQR cost of
a law that feeds back only what the rider feels, by BFGS. BFGS often stops with
"Desired error not necessarily achieved due to precision loss" (its line
search cannot lower the cost any more in floating point), which says nothing
about how close the gains are to the optimum. This script designs the rider
on the simulated model (``lqr_model="simulated"``) for seven bodies (arms,
reflex gains, a leaning upper body; each design runs one or more
optimisations along its continuation) and prints, per optimisation, BFGS'
message and the relative gradient at the gains returned
(``control.relative_gradient``: |gradient| max(|K|, 1) / cost). The largest is
what ``control.GRADIENT_TOLERANCE`` (1e-4) is set well above.

Usage: ``python scripts/output_feedback_convergence.py`` (about 20 s on one core).
"""
import scipy.optimize

from whipple_kick.simulate import assembly, control
from whipple_kick.simulate.scenario import Scenario

#: The designs: scenario fields beside lqr_model="simulated" (reflex gains in N m/rad, N m s/rad; delays in s).
DESIGNS = (
    {"arms": "on"},
    {"arms": "on", "reflex_roll": -20.0},
    {"arms": "on", "reflex_roll_rate": -5.0, "reflex_delay": 0.1},
    {"rider_body": "leaning"},
    {"rider_body": "leaning", "arms": "on"},
    {"arms": "on", "reflex_steer": 5.0, "reflex_steer_rate": 1.0},
    {"rider_body": "leaning", "arms": "on", "reflex_roll": -20.0, "reflex_delay": 0.05},
)


def main():
    minimize = scipy.optimize.minimize
    seen = []

    def watched(fun, x0, **options):   # each optimisation's end: BFGS' message and the relative gradient there
        found = minimize(fun, x0, **options)
        cost, gradient = fun(found.x)
        seen.append((found.message, control.relative_gradient(cost, gradient, found.x)))
        return found

    scipy.optimize.minimize = watched
    try:
        worst = 0.0
        for fields in DESIGNS:
            seen.clear()
            sc = Scenario(lqr_model="simulated", **fields)
            assembly.simulated_design(sc.design_spec, sc.tyre_spec, sc.bicycle_spec, sc.body_spec)
            for message, gradient in seen:
                worst = max(worst, gradient)
                print(f"{fields}: relative gradient {gradient:.2e} ({message})")
        print(f"largest relative gradient {worst:.2e}; tolerance {control.GRADIENT_TOLERANCE:g}")
    finally:
        scipy.optimize.minimize = minimize


if __name__ == "__main__":
    main()

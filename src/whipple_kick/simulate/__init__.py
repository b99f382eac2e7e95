"""One scenario to one result (what the ``simulate`` command runs).

Scenario, assembly, control design, steady motion, integration, results,
provenance and the one-run analysis; :func:`whipple_kick.simulate.simulation.run`
reads top-down through them. It builds on the model and the library.

The wing is called ``simulate``, not ``run``: ``whipple_kick.run`` is the
public function, and a subpackage of that name would replace it on the
package as soon as one of its modules was imported.
"""

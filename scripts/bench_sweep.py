"""Sweep benchmarks: where a case's time goes, parallel efficiency on the nine thesis cases, a large sweep.

Usage:
    python scripts/bench_sweep.py split           # per-case split: integration, outputs, summary, the rest
    python scripts/bench_sweep.py nine            # 9 thesis cases, 1 vs 2 workers, interleaved repeats
    python scripts/bench_sweep.py parallel        # the same in both kick directions (18 cases): 1 vs 2 workers
    python scripts/bench_sweep.py blend           # a blended pressure (350 kPa) against a measured one (400 kPa)
    python scripts/bench_sweep.py many --n 1000   # an n-case sweep into a temporary folder
    python scripts/bench_sweep.py cost            # a case's wall time on each of a sweep's paths
    python scripts/bench_sweep.py cost --callgrind   # and its instructions (valgrind, ~2 min)
    python scripts/bench_sweep.py tolerance --samples 8 --fz 635 --rtol 1e-8   # a study at two rtols
    python scripts/bench_sweep.py flags [--callgrind]   # the model's compiler flags: wall, instructions, bits
    python scripts/bench_sweep.py fall [--callgrind]    # falling runs: the careful path in Python against C
    python scripts/bench_sweep.py all

"Warm" means the compiled model is already in the on-disk cache and this
process has imported the package (one throw-away case runs first). The
nine cases are the thesis grid 300/400/500 kPa x 570/635/701 N with the
default scenario (LQR rider, 6 s after the kick, rtol 1e-10, 1000 Hz output).

Every figure is a median over interleaved repeats: each repeat runs every
variant once, in an order that rotates from repeat to repeat, so a neighbour's
load on a shared machine falls on all variants alike.

* ``split``: each of the nine cases run piece by piece in this process
  (:func:`case_split`): assembly, integration, the model's outputs at every
  sample, the trajectory table around them, the summary. The acceptance
  figure, ``run.wall_s`` over ``numerics.integration_wall_s``, comes from
  one-worker sweep tables (``nine``).
* ``nine``: per repeat a one-worker sweep, a two-worker sweep (the default
  pool kept between sweeps, as in a user's session) and the machine's
  pure-Python ceiling (two processes against one, :func:`parallel_ceiling`);
  the parallel efficiency is the speed-up over the ceiling, per repeat, then
  the median. The pool's start-up is measured on its own (a fresh pool until
  each worker has answered, :func:`pool_startup`), and a first sweep on a
  fresh pool is timed for one and two workers (a nine-case sweep must not
  take longer on two).
* ``cost``: what one case costs on each of a sweep's paths, in this process (:func:`bench_cost`): a
  plain :func:`whipple_kick.run` (the baseline: a table and a summary), a case that keeps only the table's
  row (``run_case`` without a trajectory) and one that keeps its trajectory (``run_case`` with the default
  200 Hz columns, then the folder's ``add``, where the compression happened before issue 41). Wall time:
  median of interleaved repeats, and each path's ratio to the baseline run beside it in the same repeat
  (the ratio shrugs off a neighbour's load). Instructions per case: the same paths counted by valgrind's
  callgrind (``--callgrind``; ``perf stat`` has no counters on a virtual machine), instrumented only
  while the cases run (client requests around each path, :func:`_callgrind_helper`), so the count is
  the case's own, not the imports', and does not depend on the machine's load. The integration alone is
  counted too, with its C floor (LSODA with the right-hand side, the Jacobian and LAPACK, less the C chunk
  loop's glue, :func:`_integration_floor`; issue 41 item 1) and each path's ratio to it. Running this script with
  ``PYTHONPATH=<another checkout>/src`` measures that checkout's code with the same bench: a before/after.
* ``tolerance``: the uncertainty study (shipped file, N samples, one load) at the default rtol and at
  ``--rtol``, on the same sampled rows (:func:`bench_tolerance`): P(best) per pressure and criterion, the
  recovery-time distributions, the per-case change of each criterion's time and outcome, and the CPU time
  per case. What a study's ``[fixed] rtol`` (or ``base=Scenario(rtol=...)``) buys and costs.
* ``flags``: the compiled model's C source (the cache's ``.c`` beside the library) built with each of
  :data:`FLAG_SETS` and run in this process, one library after the other (:func:`bench_flags`): each
  case's integration wall time as a ratio to the current flags' beside it (interleaved repeats, medians),
  and its trajectory compared bit for bit with theirs; with ``--callgrind`` the integration's
  instructions per case (the sets valgrind can run: AVX-512 it cannot).
* ``fall``: the falling runs of :data:`FALLING` (the controller off, a low speed, a big kick, the thesis'
  set-up at 1.92 m/s), each integrated (:func:`whipple_kick.simulate.integration.integrate_run`, the model
  assembled before) with the careful path (the chunk with the fall) in Python, scipy's LSODA stepped from
  Python as before, and in C (:mod:`whipple_kick.simulate.lsoda_c`), the fast chunks in C in both
  (:func:`bench_fall`). Wall time: medians of interleaved repeats of the whole integration and of its
  careful chunks alone, and C's ratio to Python in the same repeat; the evaluations and fall times beside
  (the same steps on both paths). With ``--callgrind`` each case's integration on each path counted by
  callgrind between client requests (:func:`_count_fall_inner`), after a warm run of every case.
* ``blend``: 350 kPa (T03's 300 and 400 kPa fits blended) against 400 kPa in
  this process: the integration's wall time per evaluation that LSODA counts
  (``numerics.evaluations``, Jacobian columns included), and the compiled
  right-hand side alone at the samples of each run (:func:`bench_blend`).
"""
import argparse
import os
import statistics
import sys
import tempfile
import time


def _thesis_grid():
    return {"pressure_kpa": [300.0, 400.0, 500.0], "fz_n": [570.0, 635.0, 701.0]}


def _thesis_scenarios(duration):
    from whipple_kick.simulate import simulation
    return [simulation.Scenario(duration=duration, pressure_kpa=p, fz_n=f)
            for p in _thesis_grid()["pressure_kpa"] for f in _thesis_grid()["fz_n"]]


def _burn(n):
    """Pure-Python CPU work; returns its wall time [s]."""
    t0 = time.perf_counter()
    total = 0
    for i in range(n):
        total += i * i
    return time.perf_counter() - t0


def parallel_ceiling(workers=2, n=10_000_000):
    """Speed-up ``workers`` independent CPU-bound processes get over one on this machine now.

    On shared or virtual cores this is often well below ``workers``; no sweep can beat it.
    The workers' own loop times are compared (their pool's start-up is left out).
    """
    from concurrent.futures import ProcessPoolExecutor
    one = _burn(n)
    with ProcessPoolExecutor(workers) as pool:
        many = max(pool.map(_burn, [n] * workers))
    return workers * one / many


def _rotated(items, k):
    """``items`` rotated by ``k`` (the interleaving order of repeat ``k``)."""
    k %= len(items)
    return items[k:] + items[:k]


def _warm_up():
    from whipple_kick.simulate import simulation
    simulation.run(simulation.Scenario(duration=0.3))


def table_split(table):
    """Per-case medians [s] of a sweep table: the worker's wall time, the integration's, and the rest."""
    wall = table["run.wall_s"]
    integration = table["numerics.integration_wall_s"]
    return {"wall": wall.median(), "integration": integration.median(), "rest": (wall - integration).median(),
            "cpu": table["run.cpu_s"].median()}


def case_split(scenario):
    """Wall times [s] of one case's pieces, run as :func:`whipple_kick.simulate.simulation.run` runs them."""
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, integration, results
    t0 = time.perf_counter()
    kick = inputs.kick_of(scenario.validate())
    model = assembly.assemble(scenario, kick)
    t1 = time.perf_counter()
    solution = integration.integrate_run(model, scenario, kick)
    t2 = time.perf_counter()
    outputs = solution.outputs()
    t3 = time.perf_counter()
    solution.outputs(via_rhs=True)
    t3b = time.perf_counter()
    solution.outputs = lambda **_: outputs   # the table around the outputs already timed
    frame = results.trajectory_frame(solution, scenario.tyre_transient)
    t4 = time.perf_counter()
    results.summarise(scenario, kick, model, solution, frame)
    t5 = time.perf_counter()
    rest = (t1 - t0) + (t4 - t3b)
    return {"integration": t2 - t1, "outputs": t3 - t2, "summary": t5 - t4, "rest": rest,
            "total": (t2 - t1) + (t3 - t2) + (t5 - t4) + rest,
            "outputs_via_rhs": t3b - t3}


def bench_split(repeats, duration):
    """Print the per-case split of the nine thesis cases (medians over cases and interleaved repeats)."""
    from whipple_kick.studies import sweep_engine
    scenarios = _thesis_scenarios(duration)
    rows = []
    sweep_engine._keep_freed_memory()   # as in a sweep's worker
    with sweep_engine._blas_controller().limit(limits=1):   # as in a sweep's worker
        for r in range(repeats):
            rows += [case_split(sc) for sc in _rotated(scenarios, r)]
    med = {k: statistics.median(row[k] for row in rows) for k in rows[0]}
    ratio = statistics.median(row["total"] / row["integration"] for row in rows)
    print(f"per case (medians of {len(rows)}, in this process): integration {med['integration'] * 1e3:.1f} ms, "
          f"outputs {med['outputs'] * 1e3:.1f} ms, summary {med['summary'] * 1e3:.1f} ms, the rest (assembly, "
          f"trajectory table) {med['rest'] * 1e3:.1f} ms; total {med['total'] * 1e3:.1f} ms = "
          f"{ratio:.2f} x integration (median of the ratios); the outputs by the whole right-hand side at "
          f"each sample (the path before) {med['outputs_via_rhs'] * 1e3:.1f} ms")
    return med


def pool_startup(workers):
    """Wall time [s] of a fresh default pool of ``workers`` until each worker has answered once."""
    from whipple_kick.studies import sweep_engine
    sweep_engine._discard_default_pool(end_workers=True)
    t0 = time.perf_counter()
    pool = sweep_engine._default_pool(workers)
    list(pool.map(_burn, [0] * workers, chunksize=1))
    return time.perf_counter() - t0


def _sweep_time(workers, base, fresh=False, grid=None, executor=None):
    """(wall time [s], table) of the sweep over ``grid`` (default: the nine thesis cases) on ``workers``;
    ``fresh``: on a new pool; ``executor``: on that one instead of the default pool."""
    import whipple_kick as wk
    from whipple_kick.studies import sweep_engine
    if fresh:
        sweep_engine._discard_default_pool(end_workers=True)
    t0 = time.perf_counter()
    table = wk.sweep(grid or _thesis_grid(), base=base, workers=workers, progress=False, executor=executor)
    wall = time.perf_counter() - t0
    assert (table["status"] == "ok").all(), table["error"].dropna().tolist()
    return wall, table


def _interleaved(repeats, base, grid=None):
    """One- and two-worker sweeps of ``grid`` and the pure-Python ceiling, interleaved: (times, tables,
    ceilings, efficiencies), the efficiency per repeat being the speed-up over the ceiling beside it."""
    from concurrent.futures import ProcessPoolExecutor

    from whipple_kick.studies import sweep_engine
    times, tables, ceilings, efficiency = {1: [], 2: []}, {1: [], 2: []}, [], []
    # A pool of each size, both kept for the whole measurement and warmed once, as the default pool is between
    # sweeps of one size: the default pool is replaced whenever the worker count changes, so alternating 1 and 2
    # workers on it timed a fresh pool's start in two thirds of the sweeps (and which ones, by the order).
    sweep_engine._preload()   # what the default pool's workers inherit
    pools = {w: ProcessPoolExecutor(max_workers=w, initializer=sweep_engine._worker_start) for w in (1, 2)}
    try:
        for w in (1, 2):
            _sweep_time(w, base, grid=grid, executor=pools[w])
        for r in range(repeats):
            done = {}
            for what in _rotated(["1", "2", "ceiling"], r):
                if what == "ceiling":
                    done["ceiling"] = parallel_ceiling(2)
                else:
                    w = int(what)
                    wall, table = _sweep_time(w, base, grid=grid, executor=pools[w])
                    done[w] = wall
                    times[w].append(wall)
                    tables[w].append(table)
            ceilings.append(done["ceiling"])
            efficiency.append((done[1] / done[2]) / done["ceiling"])
    finally:
        for pool in pools.values():
            pool.shutdown()
    return times, tables, ceilings, efficiency


def _print_scaling(label, times, ceilings, efficiency, cap_note):
    speedup = [a / b for a, b in zip(times[1], times[2], strict=True)]
    print(f"{label}: speed-up 2 workers over 1, per repeat: {', '.join(f'{s:.2f}' for s in speedup)} "
          f"(median {statistics.median(speedup):.2f}x; {cap_note})")
    print(f"pure-Python ceiling beside them (two processes vs one): {', '.join(f'{c:.2f}' for c in ceilings)} "
          f"(median {statistics.median(ceilings):.2f}x)")
    quartiles = statistics.quantiles(efficiency, n=4) if len(efficiency) > 1 else efficiency * 3
    low, high = _median_interval(efficiency)
    print(f"parallel efficiency, speed-up / ceiling per repeat: {', '.join(f'{e:.2f}' for e in efficiency)}; "
          f"median {statistics.median(efficiency):.2f} (90% bootstrap interval {low:.2f}-{high:.2f}), quartiles "
          f"{quartiles[0]:.2f}-{quartiles[2]:.2f} (target >= 0.85, held when the interval's low end is); ratio of "
          f"the medians {statistics.median(times[1]) / statistics.median(times[2]) / statistics.median(ceilings):.2f}")
    if len(efficiency) >= 6:   # by interleaving order: an order effect (the machine's state) shows here
        orders = ("1, 2, ceiling", "2, ceiling, 1", "ceiling, 1, 2")
        print("efficiency median by order: " + "; ".join(
            f"{orders[k]}: {statistics.median(efficiency[k::3]):.2f}" for k in range(3)))


def _median_interval(values, level=0.90, resamples=10_000, seed=0):
    """Percentile bootstrap interval of the median of ``values`` (its ``level`` central part of the resampled
    medians): how far the median of this many noisy repeats can be trusted."""
    import numpy as np
    values = np.asarray(values, dtype=float)
    rng = np.random.default_rng(seed)
    medians = np.median(rng.choice(values, size=(resamples, values.size)), axis=1)
    return tuple(np.quantile(medians, [(1 - level) / 2, (1 + level) / 2]))


def bench_nine(repeats, duration):
    import pandas as pd

    from whipple_kick.simulate import simulation
    base = simulation.Scenario(duration=duration)
    starts = {1: [], 2: []}
    first = {1: [], 2: []}
    for r in range(repeats):   # fresh pools: the start-up alone, then a first sweep on a fresh pool
        for w in _rotated([1, 2], r):
            starts[w].append(pool_startup(w))
        for w in _rotated([1, 2], r):
            first[w].append(_sweep_time(w, base, fresh=True)[0])
    times, tables, ceilings, efficiency = _interleaved(repeats, base)
    for w in (1, 2):
        split = table_split(pd.concat(tables[w]))
        print(f"9 thesis cases, {w} worker(s): wall median {statistics.median(times[w]):.3f} s "
              f"(runs: {', '.join(f'{t:.3f}' for t in times[w])}); per case (median of {9 * repeats}): "
              f"run.wall_s {split['wall'] * 1e3:.1f} ms = integration {split['integration'] * 1e3:.1f} ms "
              f"+ the rest {split['rest'] * 1e3:.1f} ms (CPU {split['cpu'] * 1e3:.1f} ms); "
              f"median run.wall_s / median integration {split['wall'] / split['integration']:.2f}"
              + (" (target <= 1.3)" if w == 1 else ""))
    _print_scaling("9 thesis cases", times, ceilings, efficiency, "nine equal cases cannot beat 9/5 = 1.8x")
    print(f"pool start-up until every worker answered: 1 worker {statistics.median(starts[1]) * 1e3:.0f} ms, "
          f"2 workers {statistics.median(starts[2]) * 1e3:.0f} ms (medians of {repeats})")
    print(f"first sweep on a fresh pool: 1 worker {statistics.median(first[1]):.3f} s, 2 workers "
          f"{statistics.median(first[2]):.3f} s (medians of {repeats}; 2 must not exceed 1)")
    return statistics.median(efficiency)


def bench_parallel(repeats, duration):
    """Print the parallel efficiency on the nine thesis cases in both kick directions (18 cases).

    Eighteen cases on two workers are nine rounds each, so the granularity that caps nine cases at
    9/5 = 1.8x (one worker runs five, the other four) does not enter; the cases are the validation's set.
    """
    from whipple_kick.simulate import simulation
    base = simulation.Scenario(duration=duration)
    grid = {**_thesis_grid(), "kick_direction": ["right", "left"]}
    times, _, ceilings, efficiency = _interleaved(repeats, base, grid)
    for w in (1, 2):
        print(f"18 cases (9 thesis cases x 2 kick directions), {w} worker(s): wall median "
              f"{statistics.median(times[w]):.3f} s (runs: {', '.join(f'{t:.3f}' for t in times[w])})")
    _print_scaling("18 cases", times, ceilings, efficiency, "equal cases on two workers could reach 2x")
    return statistics.median(efficiency)


def bench_blend(repeats, duration):
    """Print what a blended pressure costs against a measured one, per evaluation, side by side.

    The integrations alternate (their order rotating); each pair gives a ratio and the median of the
    ratios is the figure (a neighbour's load drifting between pairs cancels). The right-hand side alone
    is timed in blocks of 500 samples, alternating between the two runs' models, 20 blocks a repeat.
    """
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, integration, simulation
    from whipple_kick.studies import sweep_engine
    pressures = (400.0, 350.0)
    per_eval, evaluations, models = {p: [] for p in pressures}, {}, {}
    sweep_engine._keep_freed_memory()   # as in a sweep's worker
    with sweep_engine._blas_controller().limit(limits=1):
        for r in range(repeats):
            for p in _rotated(list(pressures), r):
                scenario = simulation.Scenario(pressure_kpa=p, fz_n=635.0, duration=duration)
                kick = inputs.kick_of(scenario.validate())
                solution = integration.integrate_run(assembly.assemble(scenario, kick), scenario, kick)
                evaluations[p] = solution.states.evaluations
                per_eval[p].append(solution.wall_s / evaluations[p])
                if solution.owner is None:
                    models[p] = (solution.rhs.fast, solution.states.t, solution.states.x)
        block_ratios = []
        if len(models) == 2:
            for r in range(20 * repeats):
                start = (r * 500) % max(1, min(m[1].size for m in models.values()) - 500)
                cost = {}
                for p in _rotated(list(pressures), r):
                    f, t, x = models[p]
                    t0 = time.perf_counter()
                    for k in range(start, start + 500):
                        f(t[k], x[k])
                    cost[p] = time.perf_counter() - t0
                block_ratios.append(cost[350.0] / cost[400.0])
    ratios = [b / a for a, b in zip(per_eval[400.0], per_eval[350.0], strict=True)]
    m = {p: statistics.median(v) for p, v in per_eval.items()}
    print(f"integration per evaluation (medians of {repeats}): 400 kPa {m[400.0] * 1e6:.2f} us "
          f"({evaluations[400.0]} evaluations), 350 kPa {m[350.0] * 1e6:.2f} us ({evaluations[350.0]}); "
          f"ratio per pair {', '.join(f'{q:.2f}' for q in ratios)}: median {statistics.median(ratios):.2f} "
          f"(target <= 1.3)")
    if block_ratios:
        print(f"right-hand side alone at each run's own samples, 350 / 400 kPa: median of {len(block_ratios)} "
              f"alternating blocks {statistics.median(block_ratios):.2f} (quartiles "
              f"{', '.join(f'{q:.2f}' for q in statistics.quantiles(block_ratios, n=4))})")
    return statistics.median(ratios)


def bench_many(n, duration, workers, folder):
    import numpy as np

    import whipple_kick as wk
    from whipple_kick.simulate import simulation
    # A pressure x load grid of about n cases (interpolated tyres between the measured pressures).
    n_p = max(1, int(round(np.sqrt(n / 1.6))))
    n_f = max(1, int(round(n / n_p)))
    grid = {"pressure_kpa": list(np.round(np.linspace(300.0, 500.0, n_p), 6)),
            "fz_n": list(np.round(np.linspace(550.0, 720.0, n_f), 6))}
    base = simulation.Scenario(duration=duration)
    workers = workers or os.cpu_count()
    with tempfile.TemporaryDirectory() as tmp:
        target = folder or os.path.join(tmp, "sweep")
        t0 = time.perf_counter()
        table = wk.sweep(grid, base=base, workers=workers, folder=target, progress=sys.stderr.isatty())
        wall = time.perf_counter() - t0
        size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(target) for f in fs)
    n_cases = len(table)
    rate = n_cases / wall
    ok = int((table["status"] == "ok").sum())
    print(f"{n_cases} cases ({n_p} pressures x {n_f} loads, {duration:g} s each), {workers} workers: "
          f"{wall:.1f} s wall, {rate:.2f} cases/s, {rate / workers:.2f} cases/s/core; "
          f"{ok} ok, {n_cases - ok} failed, {int(table['fell'].fillna(False).astype(bool).sum())} fell; "
          f"per case median {table['run.wall_s'].median():.3f} s in the worker; "
          f"folder {size / 1e6:.0f} MB")
    split = table_split(table)
    print(f"per case (medians): integration {split['integration']:.4f} s + the rest {split['rest']:.4f} s; "
          f"{workers} pure-Python processes get {parallel_ceiling(workers):.2f}x one here now")
    return rate / workers


#: The paths :func:`bench_cost` compares, in the order printed ("run" is the baseline).
COST_PATHS = ("run", "table", "kept")


def _cost_case(path, scenario, cid, spec, store):
    """One case on ``path``: (wall time of the worker's part [s], of the parent's part [s])."""
    import inspect

    from whipple_kick.simulate import simulation
    from whipple_kick.studies import sweep_engine
    t0 = time.perf_counter()
    if path == "run":
        simulation.run(scenario)
        return time.perf_counter() - t0, 0.0
    # packed: the worker compresses the trajectory file (issue 41); code before it has no such keyword.
    parameters = inspect.signature(sweep_engine.run_case).parameters
    packed = {"packed": True} if "packed" in parameters else {}
    # As the sweep calls it: a case without trajectory returns no summary text (the parent keeps its flat results).
    if "summary" in parameters:
        packed["summary"] = path == "kept"
    record = sweep_engine.run_case(scenario, cid, spec if path == "kept" else None, **packed)
    t1 = time.perf_counter()
    assert record["status"] == "ok", record["error"]
    if path == "kept":
        store.add(record)   # writes the trajectory file (compressing it first where the worker did not)
    else:
        sweep_engine.slim(record)   # what the parent keeps of a table-only case
    return t1 - t0, time.perf_counter() - t1


def _cost_setup(n_cases, duration, folder):
    """The cases, their ids, the default trajectory spec and a sweep folder to save kept cases into."""
    from whipple_kick.studies import sweep_engine, sweep_store
    scenarios = _thesis_scenarios(duration)[:n_cases]
    case_list = [({}, sc, sweep_store.case_id(sc)) for sc in scenarios]
    spec = sweep_engine._trajectory_spec(sweep_engine.DEFAULT_TRAJECTORY_COLUMNS, "float32", 200.0)
    store = sweep_store.Folder(folder, case_list, scenarios[0], False, spec)
    return case_list, spec, store


def _cost_warm_up(case_list, spec, store):
    """Every case on every path once, unmeasured: the per-scenario caches (rider, LQR gains: a cold case
    costs ~100 ms more) and first-call costs fall here, not on the first path measured."""
    for path in COST_PATHS:
        for _, scenario, cid in case_list:
            _cost_case(path, scenario, cid, spec, store)


def bench_cost(repeats, duration, n_cases):
    """Print each path's wall time per case (worker and parent parts) and its ratio to the baseline run."""
    from whipple_kick.studies import sweep_engine
    sweep_engine._keep_freed_memory()   # as in a sweep's worker, for every path alike
    walls = {p: [] for p in COST_PATHS}
    parent = {p: [] for p in COST_PATHS}
    ratios = {p: [] for p in COST_PATHS}
    with tempfile.TemporaryDirectory() as tmp:
        case_list, spec, store = _cost_setup(n_cases, duration, os.path.join(tmp, "sweep"))
        try:
            _cost_warm_up(case_list, spec, store)
            for r in range(repeats):
                # Case by case, every path back to back in a rotating order: a neighbour's load, which
                # drifts over seconds on a shared machine, falls on the paths of a case alike.
                for k, (_, sc, cid) in enumerate(case_list):
                    cost = {path: _cost_case(path, sc, cid, spec, store)
                            for path in _rotated(list(COST_PATHS), r + k)}
                    for path, (worker, saving) in cost.items():
                        walls[path].append(worker)
                        parent[path].append(saving)
                        ratios[path].append(sum(cost[path]) / sum(cost["run"]))
        finally:
            store.close()
    print(f"wall per case ({n_cases} thesis cases x {repeats} repeats, {duration:g} s; medians, each case's paths "
          "back to back):")
    for path in COST_PATHS:
        quartiles = statistics.quantiles(ratios[path], n=4) if len(ratios[path]) > 1 else ratios[path] * 3
        print(f"  {path:6s} worker {statistics.median(walls[path]) * 1e3:7.1f} ms + parent "
              f"{statistics.median(parent[path]) * 1e3:5.1f} ms; / run: {statistics.median(ratios[path]):.3f} "
              f"(quartiles {quartiles[0]:.3f}-{quartiles[2]:.3f})")
    return {p: statistics.median(ratios[p]) for p in COST_PATHS}


_CALLGRIND_C = """
#include <valgrind/callgrind.h>
void wk_cg_start(void) { CALLGRIND_ZERO_STATS; CALLGRIND_START_INSTRUMENTATION; }
void wk_cg_stop(const char *label) { CALLGRIND_DUMP_STATS_AT(label); CALLGRIND_STOP_INSTRUMENTATION; }
"""


def _callgrind_helper(folder):
    """ctypes library with callgrind's client requests: start counting, dump and stop (no-ops outside valgrind)."""
    import ctypes
    import subprocess
    source = os.path.join(folder, "wk_callgrind.c")
    library = os.path.join(folder, "wk_callgrind.so")
    with open(source, "w") as fh:
        fh.write(_CALLGRIND_C)
    subprocess.run(["cc", "-shared", "-fPIC", "-O1", "-o", library, source], check=True)
    lib = ctypes.CDLL(library)
    lib.wk_cg_stop.argtypes = [ctypes.c_char_p]
    return lib


def _count_inner(duration, n_cases, helper_folder):
    """Under callgrind: warm every path, then count each path's cases between client requests."""
    import gc

    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, integration
    from whipple_kick.studies import sweep_engine
    lib = _callgrind_helper(helper_folder)
    sweep_engine._keep_freed_memory()
    with tempfile.TemporaryDirectory() as tmp:
        case_list, spec, store = _cost_setup(n_cases, duration, os.path.join(tmp, "sweep"))
        try:
            _cost_warm_up(case_list, spec, store)
            # The integration alone (what its C floor is taken from, _integration_floor), the model assembled first.
            prepared = []
            for _, sc, _ in case_list:
                kick = inputs.kick_of(sc.validate())
                prepared.append((assembly.assemble(sc, kick), sc, kick))
            gc.collect()
            lib.wk_cg_start()
            for model, sc, kick in prepared:
                integration.integrate_run(model, sc, kick)
            lib.wk_cg_stop(b"integration")
            for path in COST_PATHS:
                # Each path starts from an empty young generation: a full collection falling into one path's
                # cases and not another's (some 1e8 instructions with the package's objects) is not its cost.
                gc.collect()
                lib.wk_cg_start()
                for _, sc, cid in case_list:
                    _cost_case(path, sc, cid, spec, store)
                lib.wk_cg_stop(path.encode())
        finally:
            store.close()


def bench_instructions(duration, n_cases):
    """Print the instructions per case of each path, counted by callgrind in a child process."""
    t0 = time.perf_counter()
    floor = {}
    counts = _callgrind_counts("_count", duration, n_cases, (*COST_PATHS, "integration"), floor)
    print(f"instructions per case (callgrind, {n_cases} thesis cases, {duration:g} s; {time.perf_counter() - t0:.0f} s "
          "under valgrind):")
    for path in (*COST_PATHS, "integration"):
        per_floor = f"; / integration's C floor: {counts[path] / floor['floor']:.3f}" if "floor" in floor else ""
        print(f"  {path:11s} {counts[path] / 1e6:8.1f} M; / run: {counts[path] / counts['run']:.3f}{per_floor}")
    if "floor" in floor:
        print(f"  the integration's C floor (LSODA with the right-hand side, Jacobian and LAPACK, less the C loop's "
              f"glue): {floor['floor'] / 1e6:.1f} M")
    else:
        print("  the integration's C floor: not separable here (the odeint path: LSODA calls the model through Python)")
    return counts


def _integration_floor(dump, n_cases):
    """Instructions per case of LSODA with everything it calls, less the C loop's calls into the model (glue).

    From the ``integration`` dump: ``lsoda`` inclusive, less ``f_thunk`` and ``jac_thunk`` exclusive (the
    limit test and the Jacobian's transpose); None where the run did not go through the C loop
    (:mod:`whipple_kick.simulate.lsoda_c`), since ``odeint``'s LSODA calls the model through Python.
    """
    import re
    import subprocess

    def cost(inclusive, name):
        text = subprocess.run(["callgrind_annotate", f"--inclusive={inclusive}", "--threshold=100", dump],
                              capture_output=True, text=True, check=True).stdout
        found = re.search(rf"^\s*([\d,]+) \([^)]*\)\s+\S*:{name}(?:\.\S*)? \[", text, re.MULTILINE)
        return int(found.group(1).replace(",", "")) if found else None
    total, thunks = cost("yes", "lsoda"), [cost("no", "f_thunk"), cost("no", "jac_thunk")]
    if total is None or None in thunks:
        return None
    return (total - sum(thunks)) / n_cases


def bench_tolerance(samples, fz, rtol, workers):
    """Print the uncertainty study at the default rtol and at ``rtol`` side by side (same rows, same seed)."""
    import numpy as np

    from whipple_kick.simulate.criteria import CRITERIA
    from whipple_kick.simulate.scenario import Scenario
    from whipple_kick.studies import uncertainty
    rtols = (Scenario().rtol, rtol)
    studies, walls = {}, {}
    for r in rtols:
        t0 = time.perf_counter()
        studies[r] = uncertainty.run_study(samples=samples, loads=[fz], base=Scenario(rtol=r), workers=workers)
        walls[r] = time.perf_counter() - t0
    ref, new = (studies[r] for r in rtols)
    n = len(ref.outcomes)
    print(f"uncertainty study, shipped file, N = {samples}, fz {fz:g} N: {n} cases at each rtol")
    for r in rtols:
        o = studies[r].outcomes
        print(f"  rtol {r:g}: wall {walls[r]:.0f} s, per case (medians) wall {o['run.wall_s'].median() * 1e3:.0f} ms, "
              f"CPU {o['run.cpu_s'].median() * 1e3:.0f} ms "
              f"(sum {o['run.cpu_s'].sum():.0f} s), integration median {o['numerics.integration_wall_s'].median() * 1e3:.0f} ms, "
              f"{int((o['status'] != 'ok').sum())} failed, {int(o['fell'].sum())} fell")
    keys = ["fz_n", "criterion", "pressure_kpa"]
    pb = ref.p_best.merge(new.p_best, on=keys, suffixes=("_ref", "_new"), how="outer")
    print("P(best) [95 % interval], default rtol | --rtol:")
    for _, row in pb.iterrows():
        p = "none" if np.isnan(row["pressure_kpa"]) else f"{row['pressure_kpa']:g} kPa"
        print(f"  {row['criterion']:10s} {p:8s} {row['p_ref']:.3f} [{row['low_ref']:.2f}, {row['high_ref']:.2f}] | "
              f"{row['p_new']:.3f} [{row['low_new']:.2f}, {row['high_new']:.2f}]")
    dist = ref.distributions.merge(new.distributions, on=keys, suffixes=("_ref", "_new"))
    print("recovery-time distributions (recovered rows; median and 5-95 %), default rtol | --rtol:")
    for _, row in dist.iterrows():
        print(f"  {row['criterion']:10s} {row['pressure_kpa']:g} kPa: {row['recovered_ref']} recovered, "
              f"{row['q50_s_ref']:.3f} s ({row['q05_s_ref']:.3f}-{row['q95_s_ref']:.3f}) | {row['recovered_new']}, "
              f"{row['q50_s_new']:.3f} s ({row['q05_s_new']:.3f}-{row['q95_s_new']:.3f})")
    pair = ["sample", "fz_n", "pressure_kpa"]
    both = ref.outcomes.merge(new.outcomes, on=pair, suffixes=("_ref", "_new"))
    for key, criterion in CRITERIA.items():
        a, b = (both[f"{criterion.column}{s}"].astype(float).to_numpy() for s in ("_ref", "_new"))
        finite = np.isfinite(a) & np.isfinite(b)
        moved = np.abs(a[finite] - b[finite])
        print(f"  {key}: per case |change| median {np.median(moved) if moved.size else 0.0:.2g} s, "
              f"max {moved.max(initial=0.0):.2g} s, {int((moved > 1e-6).sum())} of {int(finite.sum())} moved "
              f"by more than 1 us; "
              f"{int((np.isfinite(a) != np.isfinite(b)).sum())} cases recovered at one rtol only")
    print(f"  falls changed in {int((both['fell_ref'] != both['fell_new']).sum())} of {len(both)} cases")
    return studies


#: Compiler flag sets :func:`bench_flags` compares, the first the reference (the model's flags before issue
#: 41; ``model.compiler.MODEL_FLAGS`` is now the second): (name, flags, whether valgrind runs it). ``-std=c99``
#: (not gnu99) keeps GCC from contracting a*b+c into an FMA, which would round differently.
FLAG_SETS = (
    ("O2", ("-O2", "-fPIC", "-shared", "-std=c99"), True),
    ("O3", ("-O3", "-fPIC", "-shared", "-std=c99"), True),
    ("O3-nomatherrno", ("-O3", "-fno-math-errno", "-fPIC", "-shared", "-std=c99"), True),
    ("O2-v3", ("-O2", "-march=x86-64-v3", "-fPIC", "-shared", "-std=c99"), True),
    ("O3-v3", ("-O3", "-march=x86-64-v3", "-fPIC", "-shared", "-std=c99"), True),
    ("O3-native", ("-O3", "-march=native", "-fPIC", "-shared", "-std=c99"), False),
)


def _flag_libraries(folder, names=None):
    """Build the current model's C source with each flag set into ``folder``: {name: loaded library}."""
    import pathlib
    import subprocess

    from whipple_kick.model import compiler, transient
    from whipple_kick.model.slip import compiled, layout
    base = layout.BASE
    source = compiled.library_path(base).with_suffix(".c")
    cc = compiler.find()
    libraries = {}
    for name, flags, _ in FLAG_SETS:
        if names is not None and name not in names:
            continue
        target = os.path.join(folder, f"slip_{name}.so")
        subprocess.run([cc, *flags, "-o", target, str(source), "-lm"], check=True)
        original = compiled.library_path
        compiled.library_path = lambda L, target=target: pathlib.Path(target)
        try:
            libraries[name] = compiled._library.__wrapped__(base, transient.fingerprint())   # the model's argument types
        finally:
            compiled.library_path = original
    return libraries


def _integrate_with(library, scenario):
    """(integration wall [s], states, times) of ``scenario`` with the compiled model ``library``."""
    from whipple_kick.library import inputs
    from whipple_kick.model.slip import compiled
    from whipple_kick.simulate import assembly, integration
    kick = inputs.kick_of(scenario.validate())
    model = assembly.assemble(scenario, kick)
    original = compiled.library
    compiled.library = lambda L=None: library
    try:
        solution = integration.integrate_run(model, scenario, kick)
    finally:
        compiled.library = original
    return solution.wall_s, solution.states.x, solution.states.t


def bench_flags(repeats, duration, n_cases):
    """Print each flag set's integration wall time against the model's own flags, and whether its bits agree."""
    import numpy as np

    from whipple_kick.studies import sweep_engine
    scenarios = _thesis_scenarios(duration)[:n_cases]
    names = [name for name, _, _ in FLAG_SETS]
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        libraries = _flag_libraries(tmp)
        print(f"built {len(libraries)} variants in {time.perf_counter() - t0:.0f} s")
        sweep_engine._keep_freed_memory()
        ratios = {name: [] for name in names}
        walls = {name: [] for name in names}
        reference, identical = {}, dict.fromkeys(names, True)
        with sweep_engine._blas_controller().limit(limits=1):
            for k, sc in enumerate(scenarios):   # warm: the per-scenario caches, and the reference bits
                for name in names:
                    _, x, t = _integrate_with(libraries[name], sc)
                    if name == names[0]:
                        reference[k] = (x, t)
                    else:
                        identical[name] &= np.array_equal(x, reference[k][0]) and np.array_equal(t, reference[k][1])
            for r in range(repeats):
                for k, sc in enumerate(scenarios):
                    wall = {name: _integrate_with(libraries[name], sc)[0] for name in _rotated(names, r + k)}
                    for name in names:
                        walls[name].append(wall[name])
                        ratios[name].append(wall[name] / wall[names[0]])
    print(f"integration per case ({n_cases} thesis cases, {duration:g} s, {repeats} interleaved repeats), "
          f"against {names[0]} ({' '.join(FLAG_SETS[0][1])}) in the same repeat:")
    for name, flags, _ in FLAG_SETS:
        print(f"  {name:10s} median {statistics.median(walls[name]) * 1e3:6.1f} ms; ratio median "
              f"{statistics.median(ratios[name]):.3f} (quartiles "
              f"{', '.join(f'{q:.3f}' for q in statistics.quantiles(ratios[name], n=4))}); trajectories "
              f"{'bit-identical' if identical[name] else 'DIFFER'} ({' '.join(flags)})")
    return ratios, identical


def _count_flags_inner(duration, n_cases, helper_folder):
    """Under callgrind: each valgrind-safe flag set's integrations of the cases, counted between client requests."""
    import gc
    lib = _callgrind_helper(helper_folder)
    names = [name for name, _, safe in FLAG_SETS if safe]
    libraries = _flag_libraries(helper_folder, names)
    scenarios = _thesis_scenarios(duration)[:n_cases]
    for name in names:
        for sc in scenarios:
            _integrate_with(libraries[name], sc)
    for name in names:
        gc.collect()
        lib.wk_cg_start()
        for sc in scenarios:
            _integrate_with(libraries[name], sc)
        lib.wk_cg_stop(name.encode())


def _callgrind_counts(mode, duration, n_cases, labels, floor=None):
    """Run this script's ``mode`` under callgrind; {label: instructions per case} of its client-request dumps.

    With a dict ``floor``, its ``"floor"`` gets the integration's C floor per case (:func:`_integration_floor`)
    where the ``integration`` dump allows it.
    """
    import glob
    import re
    import subprocess
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        # One BLAS thread in every path (a sweep's worker limits it per case; the plain run would not).
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        subprocess.run(["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={out}",
                        sys.executable, os.path.abspath(__file__), mode, "--duration", str(duration),
                        "--cases", str(n_cases), "--folder", tmp],
                       check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        counts = {}
        for name in glob.glob(out + "*"):
            with open(name) as fh:
                text = fh.read()
            label = re.search(r"^desc: Trigger: Client Request: (\S+)", text, re.MULTILINE)
            total = re.search(r"^(?:totals|summary): (\d+)", text, re.MULTILINE)
            if label and total and label.group(1) in labels:
                counts[label.group(1)] = int(total.group(1)) / n_cases
                if floor is not None and label.group(1) == "integration":
                    value = _integration_floor(name, n_cases)
                    if value is not None:
                        floor["floor"] = value
    return counts


def bench_flag_instructions(duration, n_cases):
    """Print the integration's instructions per case of each valgrind-safe flag set."""
    names = [name for name, _, safe in FLAG_SETS if safe]
    t0 = time.perf_counter()
    counts = _callgrind_counts("_count_flags", duration, n_cases, names)
    print(f"integration instructions per case (callgrind, {n_cases} thesis cases, {duration:g} s; "
          f"{time.perf_counter() - t0:.0f} s under valgrind):")
    for name in names:
        print(f"  {name:10s} {counts[name] / 1e6:8.1f} M; / {names[0]}: {counts[name] / counts[names[0]]:.3f}")
    return counts


#: The falling runs of the ``fall`` bench: (label, Scenario keywords; ``thesis`` selects ``Scenario.thesis``).
FALLING = (
    ("off", {"controller": "off"}),                                    # the fork turns over at 1.54 s
    ("speed_1.5", {"speed": 1.5, "design_speed": 3.0}),                # a rider designed for 3 m/s at 1.5 m/s
    ("kick_200", {"kick_accel": 200.0, "speed": 1.5, "design_speed": 3.0}),
    ("thesis_300kPa_1.92", {"thesis": True, "pressure_kpa": 300.0, "speed": 1.92}),   # |roll| reaches 45 deg
    ("thesis_400kPa_1.92", {"thesis": True, "pressure_kpa": 400.0, "speed": 1.92}),   # the budget's largest
)

#: The careful path's two implementations the ``fall`` bench compares.
CAREFUL_PATHS = ("python", "c")


def _falling_cases(duration):
    """[(label, assembled model, scenario, kick)] of :data:`FALLING`, each ``duration`` s after the kick."""
    from whipple_kick.library import inputs
    from whipple_kick.simulate import assembly, simulation
    cases = []
    for label, keywords in FALLING:
        keywords = dict(keywords, duration=duration)
        scenario = (simulation.Scenario.thesis(**{k: v for k, v in keywords.items() if k != "thesis"})
                    if keywords.pop("thesis", False) else simulation.Scenario(**keywords))
        kick = inputs.kick_of(scenario.validate())
        cases.append((label, assembly.assemble(scenario, kick), scenario, kick))
    return cases


def _integrate_careful(path, case, careful_wall=None):
    """The case's integration (``integrate_run``'s solution) with the careful path in ``path``; the careful
    chunks' wall time [s] is added to ``careful_wall[0]`` where given."""
    from whipple_kick.simulate import integration, lsoda
    _, model, scenario, kick = case
    in_c, in_python = lsoda._careful_chunk_in_c, lsoda._careful_chunk

    def python(chunks_in_c, *arguments):
        return timed(in_python, *arguments)

    def timed(function, *arguments):
        t0 = time.perf_counter()
        try:
            return function(*arguments)
        finally:
            if careful_wall is not None:
                careful_wall[0] += time.perf_counter() - t0
    lsoda._careful_chunk_in_c = python if path == "python" else (lambda *arguments: timed(in_c, *arguments))
    try:
        return integration.integrate_run(model, scenario, kick)
    finally:
        lsoda._careful_chunk_in_c = in_c


def bench_fall(repeats, duration):
    """Print each falling case's integration and careful-chunk wall times on both careful paths, and C's ratio.

    Returns ``(walls, careful, facts)``: per (case, path) the integration's and the careful chunks' wall times
    [s] of each repeat, and the evaluations, fall time [s] and message of the run.
    """
    from whipple_kick.studies import sweep_engine
    cases = _falling_cases(duration)
    walls = {(c[0], p): [] for c in cases for p in CAREFUL_PATHS}
    careful = {(c[0], p): [] for c in cases for p in CAREFUL_PATHS}
    facts = {}
    sweep_engine._keep_freed_memory()
    with sweep_engine._blas_controller().limit(limits=1):
        for case in cases:   # warm, and what each path ends with
            for path in CAREFUL_PATHS:
                states = _integrate_careful(path, case).states
                facts[case[0], path] = (states.evaluations, states.fall_time, states.message)
        for r in range(repeats):
            for case in cases:
                for path in _rotated(list(CAREFUL_PATHS), r):
                    spent = [0.0]
                    t0 = time.perf_counter()
                    _integrate_careful(path, case, spent)
                    walls[case[0], path].append(time.perf_counter() - t0)
                    careful[case[0], path].append(spent[0])
    print(f"falling runs ({duration:g} s after the kick, {repeats} interleaved repeats; the fast chunks in C on "
          "both paths): integration wall time, its careful chunks alone, C / Python in the same repeat")
    for label, *_ in cases:
        ratio = [c / p for c, p in zip(walls[label, "c"], walls[label, "python"], strict=True)]
        careful_ratio = [c / p for c, p in zip(careful[label, "c"], careful[label, "python"], strict=True)]
        evaluations, fall_time, message = facts[label, "c"]
        same = "the same" if facts[label, "python"][:2] == (evaluations, fall_time) else "DIFFERENT"
        print(f"  {label:19s} Python {statistics.median(walls[label, 'python']) * 1e3:7.1f} ms "
              f"(careful {statistics.median(careful[label, 'python']) * 1e3:6.1f} ms), "
              f"C {statistics.median(walls[label, 'c']) * 1e3:7.1f} ms "
              f"(careful {statistics.median(careful[label, 'c']) * 1e3:6.2f} ms); C / Python "
              f"{statistics.median(ratio):.3f} (careful {statistics.median(careful_ratio):.4f}); {evaluations} "
              f"evaluations, fall at {fall_time} s ({same} on both paths): {message}")
    return walls, careful, facts


def _careful_calls(case):
    """The careful chunks of the case's run: [(the C chunk loop, _careful_chunk's arguments)], ``x`` copied."""
    from whipple_kick.simulate import lsoda
    calls, in_c = [], lsoda._careful_chunk_in_c

    def recording(chunks_in_c, rhs, x, *rest):
        calls.append((chunks_in_c, (rhs, x.copy(), *rest)))
        return in_c(chunks_in_c, rhs, x, *rest)
    lsoda._careful_chunk_in_c = recording
    try:
        _integrate_careful("c", case)
    finally:
        lsoda._careful_chunk_in_c = in_c
    return calls


def _careful_alone(path, calls):
    """The recorded careful chunks again on ``path`` ("python": scipy's LSODA from Python, "c")."""
    import numpy as np

    from whipple_kick.simulate import lsoda
    for chunks_in_c, arguments in calls:
        if path == "python":
            lsoda._careful_chunk(*(a.copy() if isinstance(a, np.ndarray) else a for a in arguments))
        else:
            lsoda._careful_chunk_in_c(chunks_in_c, *arguments)


def _count_fall_inner(duration, helper_folder):
    """Under callgrind: every falling case on both careful paths warm, then each counted between client
    requests: the whole integration, and its careful chunks alone (rerun from their recorded arguments)."""
    import gc
    lib = _callgrind_helper(helper_folder)
    cases = _falling_cases(duration)
    calls = {case[0]: _careful_calls(case) for case in cases}
    for case in cases:
        for path in CAREFUL_PATHS:
            _integrate_careful(path, case)
            _careful_alone(path, calls[case[0]])
    for case in cases:
        for path in CAREFUL_PATHS:
            gc.collect()
            lib.wk_cg_start()
            _integrate_careful(path, case)
            lib.wk_cg_stop(f"{path}:{case[0]}".encode())
            gc.collect()
            lib.wk_cg_start()
            _careful_alone(path, calls[case[0]])
            lib.wk_cg_stop(f"{path}-careful:{case[0]}".encode())


def bench_fall_instructions(duration):
    """Print each falling case's integration instructions on both careful paths (callgrind, a child process)."""
    t0 = time.perf_counter()
    labels = [f"{p}{part}:{label}" for label, _ in FALLING for p in CAREFUL_PATHS for part in ("", "-careful")]
    counts = _callgrind_counts("_count_fall", duration, 1, labels)
    print(f"instructions per falling case (callgrind, {duration:g} s; {time.perf_counter() - t0:.0f} s under "
          "valgrind): the integration, and its careful chunks alone")
    for label, _ in FALLING:
        python, c = counts[f"python:{label}"], counts[f"c:{label}"]
        careful_python, careful_c = counts[f"python-careful:{label}"], counts[f"c-careful:{label}"]
        print(f"  {label:19s} Python {python / 1e6:8.1f} M, C {c / 1e6:8.1f} M; C / Python {c / python:.3f}; "
              f"careful chunks: Python {careful_python / 1e6:7.1f} M, C {careful_c / 1e6:6.1f} M, C / Python "
              f"{careful_c / careful_python:.3f}")
    return counts


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("what", choices=("split", "nine", "parallel", "blend", "many", "cost", "tolerance", "flags",
                                    "fall", "all", "_count", "_count_flags", "_count_fall"))
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--n", type=int, default=1000, help="cases of the large sweep")
    p.add_argument("--duration", type=float, default=6.0, help="simulated time after the kick [s]")
    p.add_argument("--workers", type=int, default=None, help="workers of the large sweep (default: cores)")
    p.add_argument("--folder", default=None, help="keep the large sweep's folder here")
    p.add_argument("--cases", type=int, default=3, help="thesis cases per path of the cost bench (1-9)")
    p.add_argument("--callgrind", action="store_true", help="cost: also count instructions (valgrind, minutes)")
    p.add_argument("--samples", type=int, default=8, help="tolerance: the study's N (default 8)")
    p.add_argument("--fz", type=float, default=635.0, help="tolerance: the rear load [N] (default 635)")
    p.add_argument("--rtol", type=float, default=1e-8, help="tolerance: the rtol beside the default (1e-8)")
    args = p.parse_args(argv)
    if args.what == "_count":   # the child process bench_instructions runs under valgrind
        _count_inner(args.duration, args.cases, args.folder)
        return 0
    if args.what == "_count_flags":   # the child process bench_flag_instructions runs under valgrind
        _count_flags_inner(args.duration, args.cases, args.folder)
        return 0
    if args.what == "_count_fall":   # the child process bench_fall_instructions runs under valgrind
        _count_fall_inner(args.duration, args.folder)
        return 0
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f} before the run")
    _warm_up()
    if args.what in ("split", "all"):
        bench_split(args.repeats, args.duration)
    if args.what in ("nine", "all"):
        bench_nine(args.repeats, args.duration)
    if args.what in ("parallel", "all"):
        bench_parallel(args.repeats, args.duration)
    if args.what in ("blend", "all"):
        bench_blend(args.repeats, args.duration)
    if args.what in ("cost", "all"):
        bench_cost(args.repeats, args.duration, args.cases)
        if args.callgrind:
            bench_instructions(args.duration, args.cases)
    if args.what == "flags":   # builds five libraries: not part of "all"
        bench_flags(args.repeats, args.duration, args.cases)
        if args.callgrind:
            bench_flag_instructions(args.duration, args.cases)
    if args.what in ("fall", "all"):
        bench_fall(args.repeats, args.duration)
        if args.callgrind:
            bench_fall_instructions(args.duration)
    if args.what == "tolerance":   # minutes: not part of "all"
        bench_tolerance(args.samples, args.fz, args.rtol, args.workers)
    if args.what in ("many", "all"):
        bench_many(args.n, args.duration, args.workers, args.folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())

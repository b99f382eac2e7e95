"""Speed benchmarks of the slip model (medians; ratios against a baseline in the same process).

Usage:
    python scripts/bench.py rhs        # one RHS call from Python vs the C function alone (a C loop), and vs
                                       # the NumPy (lambdify-style) oracle
    python scripts/bench.py build      # cold build (derive + generate + compile) and warm start, fresh processes
    python scripts/bench.py run        # the 6 s kick-plate base case at rtol 1e-12 and 1e-8, C vs NumPy RHS
    python scripts/bench.py cli        # end to end: `simulate --pressure 400 --fz 635 --out NEW --quiet`, warm cache
    python scripts/bench.py transient  # each tyre transient form against contact_patch: RHS call and 6 s run
    python scripts/bench.py all
    python scripts/bench.py build cli --record [--machine "TEXT"]
                                       # also record the medians in docs/timings.json (the README's timings,
                                       # checked by scripts/doc_numbers.py), with the machine and the date
    python scripts/bench.py compare --against DIR [--against-cache DIR]
                                       # this checkout against another one (e.g. main) in the same session:
                                       # RHS call cost, the C function alone and the call from Python (both
                                       # compiled libraries in one process, interleaved rounds), and the 6 s
                                       # default run at rtol 1e-10 and 1e-12, and with tyre_transient
                                       # "force_lag" against the other's default (interleaved fresh processes),
                                       # and the default model's cold build (--build-repeats, default 3)
    python scripts/bench.py instructions --against DIR [--against-cache DIR]
                                       # the default run's integration in instructions (valgrind callgrind),
                                       # this checkout against the other: independent of the machine's load
"""
import argparse
import os
import pathlib
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np


def _base_case(rtol=1e-10):
    import whipple_kick as wk
    from whipple_kick.model import slip
    from whipple_kick.simulate import steady
    bike = wk.bicycles.load("balanceassist_v1")
    combined, _ = wk.riders.for_rear_load(bike, fz_n=635.0)
    K, _ = wk.control.lqr_gains(combined, 3.0)
    tyre = wk.tyres.load("T03", pressure_kpa=400)
    par = slip.model_parameters(combined, tyre, tyre, gains=wk.control.gains_dict(K),
                                kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    return steady.steady_state(par, 3.0)


def bench_rhs(repeats):
    from whipple_kick.model import slip
    from whipple_kick.model.symbolic import slip_build
    ss = _base_case()
    rhs = slip.CompiledRHS(ss.params)
    p = slip.parameter_vector(ss.params)
    x = ss.x.copy()
    x[slip.X["u4"]] = 0.1
    n_c, n_np = 20000, 200
    c_times, alone_times, np_times = [], [], []
    slip_build.numpy_rhs(0.05, x, p, ss.params.model)  # import and warm up
    f = rhs.fast   # what the integrators call
    native = hasattr(f, "repeat")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n_c):
            f(0.05, x)
        c_times.append((time.perf_counter() - t0) / n_c)
        if native:   # the C function alone: a C loop over the prepared pointers
            t0 = time.perf_counter()
            f.repeat(0.05, x, n_c)
            alone_times.append((time.perf_counter() - t0) / n_c)
        t0 = time.perf_counter()
        for _ in range(n_np):
            slip_build.numpy_rhs(0.05, x, p, ss.params.model)
        np_times.append((time.perf_counter() - t0) / n_np)
    c, n = statistics.median(c_times), statistics.median(np_times)
    print(f"RHS call from Python ({'rhs_call extension' if native else 'ctypes fallback'}): median "
          f"{c * 1e6:.2f} us  ({repeats} runs x {n_c} calls)")
    if native:
        alone = statistics.median(alone_times)
        print(f"the C function alone (C loop): median {alone * 1e6:.2f} us; call / alone {c / alone:.3f} (bound 1.3)")
    print(f"RHS call, NumPy oracle (same expressions):  median {n * 1e6:.1f} us  ({repeats} runs x {n_np} calls)")
    print(f"speed-up C / NumPy: {n / c:.0f}x")


#: Where ``--record`` keeps the medians the README states (scripts/doc_numbers.py checks the README against it).
TIMINGS = pathlib.Path(__file__).resolve().parents[1] / "docs" / "timings.json"
RECORD = {"on": False, "machine": None}


def _machine():
    """CPU model and count (and the load at the start), for the record: timings depend on the machine."""
    model = platform.machine()
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = f"; load average {os.getloadavg()[0]:.1f} when recorded" if hasattr(os, "getloadavg") else ""
    return f"{os.cpu_count()} CPUs, {model} ({platform.system()}{load})"


def _record(key, value, script, digits=1):
    """Keep ``value`` [s] as the latest output of ``script`` in :data:`TIMINGS` (with ``--record`` only)."""
    import datetime
    import json

    if not RECORD["on"]:
        return
    record = json.loads(TIMINGS.read_text()) if TIMINGS.is_file() else {}
    record[key] = {"value": round(float(value), digits), "digits": digits, "script": script,
                   "machine": RECORD["machine"] or _machine(),
                   "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d")}
    TIMINGS.write_text(json.dumps(record, indent=1) + "\n")
    print(f"recorded {key} = {value:.{digits}f} s in {TIMINGS}")


def _fresh(cache, code):
    env = dict(os.environ, WHIPPLE_KICK_CACHE=cache)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    return time.perf_counter() - t0


def bench_build(repeats):
    code = "from whipple_kick import slip; slip.library()"
    cold, warm = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cache = os.path.join(tmp, "cache")
            cold.append(_fresh(cache, code))
            warm.append(_fresh(cache, code))
    base = statistics.median(_fresh(tempfile.gettempdir(), "import numpy, scipy.integrate, sympy") for _ in range(repeats))
    print(f"cold build (derive + generate C + compile): median {statistics.median(cold):.2f} s  runs {[round(v, 2) for v in cold]}")
    print(f"warm start (load cached library):           median {statistics.median(warm):.2f} s  runs {[round(v, 2) for v in warm]}")
    print(f"baseline (python + numpy + scipy + sympy import): median {base:.2f} s")
    _record("build_cold_s", statistics.median(cold), "scripts/bench.py build", digits=0)


def bench_run(repeats):
    from whipple_kick.model import slip
    from whipple_kick.model.symbolic import slip_build
    from whipple_kick.simulate import lsoda
    ss = _base_case()
    p = slip.parameter_vector(ss.params)
    for rtol in (1e-12, 1e-8):
        times = []
        for _ in range(repeats):
            rhs = slip.CompiledRHS(ss.params)
            t0 = time.perf_counter()
            traj = lsoda.integrate(rhs, ss.x, 6.0, t_start=0.0, breakpoints=(0.15,), rtol=rtol)
            times.append(time.perf_counter() - t0)
        print(f"6 s base case, C RHS, rtol {rtol:g}: median {statistics.median(times):.3f} s  "
              f"({traj.nfev} RHS calls)  runs {[round(v, 3) for v in times]}")
        c_med = statistics.median(times)
        t0 = time.perf_counter()
        lsoda.integrate(lambda t, x: slip_build.numpy_rhs(t, x, p, ss.params.model), ss.x, 6.0, t_start=0.0,
                            breakpoints=(0.15,), rtol=rtol)
        n = time.perf_counter() - t0
        print(f"6 s base case, NumPy RHS, rtol {rtol:g}: {n:.2f} s (one run); C is {n / c_med:.0f}x faster")


def bench_transient(repeats):
    """Each tyre transient form against the contact-patch form, in one process, interleaved rounds.

    The RHS call from Python (20 000 calls at a perturbed steady state) and
    the 6 s default run (``wk.run``, its integration wall time and whole),
    medians over ``repeats`` rounds and the ratio to the contact-patch form.
    """
    import whipple_kick as wk
    from whipple_kick.model import slip
    from whipple_kick.simulate import steady
    forms = ("contact_patch", "carcass", "slip_lag", "force_lag")
    calls, runs, integration = ({f: [] for f in forms} for _ in range(3))
    fast = {}
    base = _base_case()
    for form in forms:
        params = slip.Parameters(slip.Model(base.params.model.parts, base.params.model.delayed_reflex, form),
                                 base.params.replace(tyre_transient=float(wk.transient.transients().index(form))))
        ss = steady.steady_state(params, 3.0)
        x = ss.x.copy()
        x[slip.X["u4"]] = 0.1
        fast[form] = (slip.CompiledRHS(ss.params).fast, x)
        wk.run(wk.Scenario(pressure_kpa=400.0, fz_n=635.0, tyre_transient=form))   # warm
    for _ in range(repeats):
        for form in forms:
            f, x = fast[form]
            t0 = time.perf_counter()
            for _ in range(20000):
                f(0.05, x)
            calls[form].append((time.perf_counter() - t0) / 20000)
            t0 = time.perf_counter()
            r = wk.run(wk.Scenario(pressure_kpa=400.0, fz_n=635.0, tyre_transient=form))
            runs[form].append(time.perf_counter() - t0)
            integration[form].append(r.summary["numerics"]["integration_wall_s"])
    ref = {k: statistics.median(v["contact_patch"]) for k, v in (("call", calls), ("run", runs),
                                                                  ("integration", integration))}
    print(f"medians of {repeats} interleaved rounds; ratio to contact_patch")
    print("| form | RHS call [us] | ratio | 6 s run: integration [s] | ratio | whole wk.run [s] | ratio |")
    print("|---|---|---|---|---|---|---|")
    for form in forms:
        c, i, w = (statistics.median(v[form]) for v in (calls, integration, runs))
        print(f"| {form} | {c * 1e6:.2f} | {c / ref['call']:.2f} | {i:.4f} | {i / ref['integration']:.2f} | "
              f"{w:.3f} | {w / ref['run']:.2f} |")


def _simulate_command():
    """The ``simulate`` console script of this interpreter's environment (or an equivalent -c call)."""
    script = shutil.which("simulate", path=str(pathlib.Path(sys.executable).parent))
    if script:
        return [script]
    return [sys.executable, "-c", "from whipple_kick.cli import simulate_main; simulate_main()"]


_BASELINE = "import numpy, scipy.integrate, pandas, matplotlib"

# One warm run in a fresh process, each stage of simulate timed (the same calls the CLI makes).
_STAGES = r"""
import json, sys, time
t0 = time.perf_counter()
stages = {}
import numpy, scipy.integrate, pandas, matplotlib
stages["import numpy, scipy, pandas, matplotlib"] = time.perf_counter() - t0
t = time.perf_counter()
from whipple_kick import Scenario, assembly, cli, plotting, simulation, slip, steady
stages["import whipple_kick (cli, simulation, plotting)"] = time.perf_counter() - t
t = time.perf_counter()
slip.library()
stages["load the compiled model"] = time.perf_counter() - t
t = time.perf_counter()
import matplotlib.figure, matplotlib.backends.backend_agg
stages["import matplotlib.figure + Agg (not in baseline)"] = time.perf_counter() - t
t = time.perf_counter()
scenario = assembly.preflight(Scenario(pressure_kpa=400.0, fz_n=635.0))
result = simulation.run(scenario)
stages["run() total"] = time.perf_counter() - t
stages["  of which integration"] = result.summary["numerics"]["integration_wall_s"]
t = time.perf_counter()
result.save(sys.argv[1])
stages["trajectory.csv + summary.json"] = time.perf_counter() - t
t = time.perf_counter()
plotting.response_figure([("", result)], sys.argv[1] + "/response.png", title=plotting.result_title(result),
                         kick=plotting.kick_band(result))
stages["response.png (after its imports)"] = time.perf_counter() - t
stages["total in process"] = time.perf_counter() - t0
print(json.dumps(stages))
"""


def time_against_baseline(command, baseline, repeats, each=None):
    """Wall times [s] of ``command`` and of ``baseline``, each run in a fresh process, interleaved.

    ``command`` gets a new ``--out`` folder every time; one untimed run first
    warms the cache. After each timed run ``baseline`` is timed, then
    ``each(folder, k)`` is called if given. Returns ``(times, baseline_times)``.
    """
    times, base = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeats + 1):
            t0 = time.perf_counter()
            subprocess.run(command + ["--out", os.path.join(tmp, f"run{k}")], check=True)
            if k:   # the first run only warms the cache
                times.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                subprocess.run(baseline, check=True)
                base.append(time.perf_counter() - t0)
                if each is not None:
                    each(tmp, k)
    return times, base


def bench_cli(repeats):
    """Wall time of the whole command, each run in a fresh process writing into a new folder.

    Uses the normal per-user cache (or $WHIPPLE_KICK_CACHE); one untimed run
    first makes sure it is warm, so this measures what a user sees on every
    run after the first. Each round also times the baseline
    ``python -c "import numpy, scipy.integrate, pandas, matplotlib"`` (the
    bound is <= 1.5 s and <= 0.6 s above it) and a staged run in process.
    """
    import json
    command = _simulate_command() + ["--pressure", "400", "--fz", "635", "--quiet"]
    stages = []

    def staged_run(tmp, k):
        staged = os.path.join(tmp, f"staged{k}")
        os.mkdir(staged)
        done = subprocess.run([sys.executable, "-c", _STAGES, staged], check=True, capture_output=True, text=True)
        stages.append(json.loads(done.stdout.splitlines()[-1]))

    times, base = time_against_baseline(command, [sys.executable, "-c", _BASELINE], repeats, staged_run)
    median, baseline = statistics.median(times), statistics.median(base)
    print(f"simulate --pressure 400 --fz 635 --quiet (warm cache, fresh process): "
          f"median {median:.2f} s  runs {[round(v, 2) for v in times]}")
    print(f"baseline python -c '{_BASELINE}': median {baseline:.2f} s  runs {[round(v, 2) for v in base]}")
    _record("simulate_warm_s", median, "scripts/bench.py cli")
    print(f"simulate - baseline: {median - baseline:.2f} s (bound 0.6 s); simulate / baseline: "
          f"{median / baseline:.2f}")
    print("stages of a warm run in one process (medians):")
    for name in stages[0]:
        print(f"  {name:<50s} {statistics.median(st[name] for st in stages):.3f} s")


# Runs in either checkout (no newer API): dumps the base case's state and parameters and the library path.
_DUMP = r"""
import sys, numpy as np
import whipple_kick as wk
from whipple_kick import slip, steady
bike = wk.bicycles.load("balanceassist_v1")
combined, _ = wk.riders.for_rear_load(bike, fz_n=635.0)
K, _ = wk.control.lqr_gains(combined, 3.0)
tyre = wk.tyres.load("T03", pressure_kpa=400)
par = slip.model_parameters(combined, tyre, tyre, gains=wk.control.gains_dict(K),
                                kick=dict(t0=0.0, duration=0.15, displacement=0.15))
ss = steady.steady_state(par, 3.0)
x = ss.x.copy(); x[slip.X["u4"]] = 0.1
np.save(sys.argv[1] + "_x.npy", x); np.save(sys.argv[1] + "_p.npy", slip.parameter_vector(ss.params))
print(slip.library()._name)
"""
_RUN = r"""
import json, statistics, sys
from whipple_kick import Scenario, run   # the package top: the same in a checkout from before the wings
changes = json.loads(sys.argv[1])
run(Scenario(duration=0.2, **changes))
runs = [run(Scenario(**changes)).summary["numerics"] for _ in range(3)]
# all evaluations, the Jacobians' included (a checkout without a C Jacobian counts its differences in nfev)
print(json.dumps([statistics.median(r[k] for r in runs) for k in ("integration_wall_s", "wall_s")]
                 + [statistics.median(r.get("evaluations", r["nfev"]) for r in runs)]
                 + [min(r["integration_wall_s"] for r in runs)]))
"""

#: 6 s default runs compared: (label, this checkout's Scenario changes, the other's). The other
#: checkout may predate ``tyre_transient`` (06612a3 has only the relaxed-force tyre, this
#: checkout's "force_lag"), so like is compared with like beside the two defaults.
_RUN_CASES = (
    ("defaults, rtol 1e-10", {"rtol": 1e-10}, {"rtol": 1e-10}),
    ("defaults, rtol 1e-12", {"rtol": 1e-12}, {"rtol": 1e-12}),
    ("force_lag vs its default, rtol 1e-10", {"rtol": 1e-10, "tyre_transient": "force_lag"}, {"rtol": 1e-10}),
    ("force_lag vs its default, rtol 1e-12", {"rtol": 1e-12, "tyre_transient": "force_lag"}, {"rtol": 1e-12}),
)


def _environments(args):
    """{label: environment} of this checkout and of the one compared against."""
    # Each side imports its own checkout's src/ (this one's too: the installed package may be another checkout).
    here = dict(os.environ, PYTHONPATH=str(pathlib.Path(__file__).resolve().parents[1] / "src"))
    other = dict(os.environ, PYTHONPATH=str(pathlib.Path(args.against).resolve() / "src"))
    other["WHIPPLE_KICK_CACHE"] = args.against_cache or os.path.join(tempfile.gettempdir(), "wkcache_bench_against")
    return {"this": here, "against": other}


def bench_compare(args):
    """RHS call and 6 s run of this checkout against ``--against`` (ratios this/against)."""
    import ctypes
    import json
    envs = _environments(args)
    libs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, env in envs.items():
            out = subprocess.run([sys.executable, "-c", _DUMP, os.path.join(tmp, label)], env=env,
                                 capture_output=True, text=True, check=True, cwd=tmp)
            lib = ctypes.CDLL(out.stdout.strip().splitlines()[-1])
            lib.wk_slip_rhs.restype = ctypes.c_int
            lib.wk_slip_rhs.argtypes = [ctypes.c_double] + [ctypes.c_void_p] * 4
            x = np.load(os.path.join(tmp, f"{label}_x.npy"))
            libs[label] = (lib, x, np.load(os.path.join(tmp, f"{label}_p.npy")), np.empty(x.size))

    # The C function alone: a C loop over the prepared pointers (rhs_call's repeat), the same
    # method for both libraries. The call from Python: this checkout's as the integrator makes it
    # (slip.CompiledRHS.fast), the other's as its CompiledRHS.__call__ did (contiguous input,
    # x.ctypes, ctypes call, copy).
    from whipple_kick.model import compiler, rhs_call
    native = rhs_call.module(compiler.find())

    def c_alone(label, n):
        lib, x, p, _ = libs[label]
        address = ctypes.cast(lib.wk_slip_rhs, ctypes.c_void_p).value
        f = native.Rhs(address, p, x.size, lambda status, t: None)
        t0 = time.perf_counter()
        f.repeat(0.05, x, n)
        return (time.perf_counter() - t0) / n

    def from_python(label, n):
        lib, x, p, dx = libs[label]
        if label == "this":
            address = ctypes.cast(lib.wk_slip_rhs, ctypes.c_void_p).value
            f = native.Rhs(address, p, x.size, lambda status, t: None)
            t0 = time.perf_counter()
            for _ in range(n):
                f(0.05, x)
            return (time.perf_counter() - t0) / n
        fn, p_ptr, dx_ptr = lib.wk_slip_rhs, p.ctypes.data, dx.ctypes.data
        t0 = time.perf_counter()
        for _ in range(n):
            fn(0.05, np.ascontiguousarray(x, dtype=float).ctypes.data, p_ptr, dx_ptr, None)
            dx.copy()
        return (time.perf_counter() - t0) / n

    times = {(label, how): [] for label in libs for how in ("C", "py")}
    for _ in range(max(args.repeats, 1) * 8):
        for label in libs:
            times[label, "C"].append(c_alone(label, 5000))
            times[label, "py"].append(from_python(label, 5000))
    med = {k: statistics.median(v) for k, v in times.items()}
    for label in libs:
        print(f"RHS, {label}: C alone {med[label, 'C'] * 1e6:.2f} us, call from Python {med[label, 'py'] * 1e6:.2f} us, "
              f"ratio {med[label, 'py'] / med[label, 'C']:.3f} (medians of {len(times[label, 'C'])} interleaved "
              f"rounds of 5000 calls)")
    print(f"RHS C alone this/against {med['this', 'C'] / med['against', 'C']:.3f}; "
          f"call from Python this/against {med['this', 'py'] / med['against', 'py']:.3f}")
    for case, this_changes, other_changes in _RUN_CASES:
        changes = {"this": this_changes, "against": other_changes}
        runs = {label: [] for label in envs}
        for _ in range(args.repeats):
            for label, env in envs.items():
                out = subprocess.run([sys.executable, "-c", _RUN, json.dumps(changes[label])], env=env,
                                     capture_output=True, text=True, check=True, cwd=tempfile.gettempdir())
                runs[label].append(json.loads(out.stdout.strip().splitlines()[-1]))
        # The fastest of a process's runs too: on a shared or virtual machine a run is now and then slowed
        # by half (steal, frequency), which moves a median of few processes; the fastest is the code's.
        for k, name in enumerate(("integration [s]", "run() wall [s]", "RHS evaluations (Jacobians' included)",
                                  "integration, fastest of each process's 3 [s]")):
            this, against = (statistics.median(r[k] for r in runs[label]) for label in ("this", "against"))
            print(f"6 s run, {case}, {name}: this {this:.4g}, against {against:.4g}, ratio {this / against:.3f} "
                  f"(medians of {args.repeats} interleaved processes x 3 runs)")
    # The cold build of the default model: a fresh process on an empty cache, each side in turn.
    builds = {label: [] for label in envs}
    for _ in range(max(args.build_repeats, 1)):
        for label, env in envs.items():
            with tempfile.TemporaryDirectory() as cache:
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-c", "import whipple_kick as wk; wk.slip.library()"],
                               env=dict(env, WHIPPLE_KICK_CACHE=cache), check=True, capture_output=True,
                               cwd=tempfile.gettempdir())
                builds[label].append(time.perf_counter() - t0)
    this, against = (statistics.median(builds[label]) for label in ("this", "against"))
    print(f"cold build of the default model [s]: this {this:.2f}, against {against:.2f}, ratio {this / against:.3f} "
          f"(medians of {len(builds['this'])} interleaved fresh processes on empty caches)")


_INTEGRATION_RUN = """
import sys
import whipple_kick as wk
result = wk.run(wk.Scenario(rtol=float(sys.argv[1])))
print("evaluations", result.summary["numerics"]["evaluations"])
"""


def bench_instructions(args):
    """Instructions the default 6 s run's integration executes, this checkout against ``--against``.

    Counted by valgrind's callgrind inside SciPy's LSODA (``--toggle-collect=lsoda``: the integrator, the
    right-hand side and Jacobian calls from Python into C, nothing before or after), so the figure does not
    depend on the machine's load the way a wall time does; each side runs once per tolerance.
    """
    import re
    if shutil.which("valgrind") is None:
        raise SystemExit("instructions needs valgrind (Debian package valgrind)")
    counts = {}
    with tempfile.TemporaryDirectory() as tmp:
        script = os.path.join(tmp, "run.py")
        pathlib.Path(script).write_text(_INTEGRATION_RUN)
        for rtol in ("1e-12", "1e-10"):
            for label, env in _environments(args).items():
                out = subprocess.run(["valgrind", "--tool=callgrind", "--toggle-collect=lsoda",
                                      f"--callgrind-out-file={os.path.join(tmp, label + '.out')}", sys.executable,
                                      script, rtol], env=env, capture_output=True, text=True, check=True, cwd=tmp)
                collected = int(re.search(r"Collected : (\d+)", out.stderr).group(1))
                evaluations = int(re.search(r"evaluations (\d+)", out.stdout).group(1))
                counts[rtol, label] = (collected, evaluations)
            (this, n_this), (against, n_against) = counts[rtol, "this"], counts[rtol, "against"]
            print(f"6 s run, defaults, rtol {rtol}: integration instructions this {this:.4e}, against "
                  f"{against:.4e}, ratio {this / against:.4f}; RHS evaluations (Jacobians' included) this "
                  f"{n_this}, against {n_against}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", choices=("rhs", "build", "run", "cli", "all", "compare", "instructions", "transient"),
                        nargs="+")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--build-repeats", type=int, default=3, help="cold builds per side in compare (default 3)")
    parser.add_argument("--record", action="store_true",
                        help="record the build and cli medians in docs/timings.json (the README's timings)")
    parser.add_argument("--machine", help="the machine in words for the record (default: CPU model and count)")
    parser.add_argument("--against", metavar="DIR", help="checkout to compare with (its src/ is imported)")
    parser.add_argument("--against-cache", metavar="DIR", help="model cache of that checkout (default: a temp dir)")
    args = parser.parse_args()
    RECORD.update(on=args.record, machine=args.machine)
    np.set_printoptions(precision=4)
    if "compare" in args.what or "instructions" in args.what:
        if not args.against:
            parser.error("compare and instructions need --against DIR")
        if "compare" in args.what:
            bench_compare(args)
        if "instructions" in args.what:
            bench_instructions(args)
        return
    if "transient" in args.what:
        bench_transient(args.repeats)
        return
    for name, fn in (("rhs", bench_rhs), ("build", bench_build), ("run", bench_run), ("cli", bench_cli)):
        if name in args.what or "all" in args.what:
            fn(args.repeats)


if __name__ == "__main__":
    main()

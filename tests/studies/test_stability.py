"""Linear stability of the slip model: the fast linearisation, mode tracking and naming, the
stiff-tyre limit, consistency with the nonlinear model, the wobble, the command."""
import json
import math

import numpy as np
import pandas as pd
import pytest

import whipple_kick as wk
from whipple_kick import cli
from whipple_kick.model import classic, slip
from whipple_kick.simulate.simulation import Scenario
from whipple_kick.studies import stability
from whipple_kick.studies.stability import modes, summary

#: The default case of the stability command: T03 at 400 kPa, 635 N, offsets removed.
DEFAULT = Scenario(symmetric_tyres=True)
DEFAULT_SPEEDS = stability.parse_speeds("0.5:10:0.05")
#: Near-rigid linear tyre: cornering 1e5 /rad, relaxation length 1e-5 m, vertical 1e10 N/m.
RIGID = (1e5, 1e-5, 1e10)


@pytest.fixture(scope="module")
def default_sweep():
    return stability.analyse(DEFAULT, DEFAULT_SPEEDS)


@pytest.fixture(scope="module")
def rigid_sweep():
    tyre = wk.tyres.linear_tyre(*RIGID)
    return stability.analyse(DEFAULT, stability.parse_speeds("1:7:0.1"), tyres=(tyre, tyre))


def _eigs(table, model, loop, speed, mode=None):
    sel = table[(table["model"] == model) & (table["loop"] == loop) & np.isclose(table["speed_m_s"], speed)]
    if mode is not None:
        sel = sel[sel["mode"] == mode]
    return np.sort_complex((sel["real_1_s"] + 1j * sel["imag_1_s"]).to_numpy())


# ------------------------------------------------------------ the fast linearisation

@pytest.mark.parametrize("symmetric, speed, controller", [(True, 4.0, "off"), (False, 3.0, "lqr"), (False, 5.0, "lqr"),
                                                          (False, 5.0, "off")])
def test_heading_linearisation_equals_the_central_difference_one(symmetric, speed, controller):
    """The chain-rule Jacobian against slip.linearize (central differences, pitch re-solved).

    Two independent routes to the same matrix: perturbing the heading-frame
    state and re-solving the pitch numerically, against the compiled model's
    forward-difference Jacobian times the exact embedding. Measured 5e-8 to
    2e-7 of each column's largest entry (forward differences ~1e-7); the
    steer-torque column to 6e-10 of its largest entry (it is exact; the
    reference's bumped-gain difference is not). Measured T03 at 3 and 5 m/s
    is a steady turn, so the rotating-frame terms are exercised (at 5 m/s with
    the rider designed at 3 m/s, and without a rider).
    """
    # At 5 m/s the rider designed at 3 m/s: designed at 5 m/s it has no near-upright start there (issue 40).
    sc = Scenario(symmetric_tyres=symmetric, controller=controller, speed=speed,
                  design_speed=3.0 if speed == 5.0 and controller == "lqr" else None)
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    gains, _ = wk.assembly.controller_gains(sc.gains_spec, design)
    params = slip.model_parameters(moore, rear, front, slip.ModelOptions(symmetric_tyres=symmetric), gains=gains)
    steady = wk.steady.find_steady_state(params, speed).steady
    rhs = slip.CompiledRHS(steady.params)
    A_ref = slip.linearize(rhs, steady.x)
    A, B = slip.heading_linearisation(rhs, steady.x)
    assert np.max(np.abs(A - A_ref) / np.abs(A_ref).max(axis=0)) < 1e-6
    _, B_ref, _ = slip.linear_state_space(steady.params, steady.x)
    assert np.max(np.abs(B - B_ref)) < 1e-8 * np.abs(B_ref).max()
    if not symmetric:
        # A turn: the u3 u1, u3 u2 terms matter (measured 0.024 rad/s at 5 m/s under the rider designed at 3 m/s,
        # 0.12 rad/s without a rider; the rider designed at 5 m/s has no near-upright start there, issue 40).
        assert abs(steady.x[slip.X["u3"]]) > 0.02


def test_holonomic_row_is_the_front_contact_height_gradient():
    """The constraint-matrix row the pitch embedding uses equals d(height)/dq by central differences.

    Measured agreement 6e-11 of the row's largest entry (central differences, step 1e-6 rad or m).
    """
    sc = Scenario(speed=3.0)
    moore, design, _ = wk.assembly.build_bicycle(sc.bicycle_spec)
    rear, front, _ = wk.assembly.build_tyres(sc.tyre_spec)
    steady = wk.steady.steady_state(slip.model_parameters(moore, rear, front), 3.0)
    rhs = slip.CompiledRHS(steady.params)
    row = rhs.impulse_terms(0.0, steady.x)[1][slip.HOLONOMIC_ROW]
    for k, q in enumerate(slip.COORDINATES):
        h = 1e-6
        xp, xm = steady.x.copy(), steady.x.copy()
        xp[slip.X[q]] += h
        xm[slip.X[q]] -= h
        height = lambda x: rhs.outputs(0.0, x)[1][slip.OUT["holonomic"]]
        assert abs((height(xp) - height(xm)) / (2 * h) - row[k]) < 1e-7 * np.abs(row).max()


# ------------------------------------------------------------ naming and tracking

@pytest.mark.parametrize("shares, real, freq, expected", [
    ([0.9, 0.05, 0.05, 0, 0, 0], True, 0.0, "capsize"),
    ([0.05, 0.6, 0.35, 0, 0, 0], True, 0.0, "caster"),
    ([0.3, 0.4, 0.3, 0, 0, 0], False, 0.8, "weave"),
    ([0.0, 0.17, 0.01, 0, 0.07, 0.75], False, 9.5, "wobble"),
    ([0.0, 0.45, 0.02, 0, 0.0, 0.53], False, 0.3, "caster"),
    ([0.0, 0.01, 0.01, 0, 0.9, 0.08], False, 10.2, "lateral_rear"),
    ([0.0, 0.0, 0.0, 0, 0.97, 0.03], True, 0.0, "relaxation_rear"),
    ([0.0, 0.01, 0.0, 0, 0.01, 0.98], True, 0.0, "relaxation_front"),
    ([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], False, 4.1, "vertical"),
])
def test_name_rules(shares, real, freq, expected):
    """The stated rules on contents like those measured (docs/stability.md)."""
    assert stability.name_mode(shares, real, freq) == expected


def test_tracking_keeps_identity_where_real_parts_cross():
    """Two modes whose real parts cross: sorting by real part would swap them, tracking does not."""
    speeds = np.linspace(0.0, 2.0, 21)
    a_vec, b_vec = np.array([[1.0], [0.1]], dtype=complex), np.array([[0.1], [1.0]], dtype=complex)
    lams, vecs = [], []
    for v in speeds:
        lam = np.array([-v + 3j, -1.0 + 0.5j])          # real parts cross at v = 1
        order = np.argsort(lam.real)                     # any order the eigen-solver returns
        lams.append(lam[order])
        vecs.append(np.hstack([a_vec, b_vec])[:, order])
    ids = stability.track(lams, vecs)
    for lam, cur in zip(lams, ids, strict=True):
        first = lam[cur == ids[0][np.argmax(lams[0].imag)]][0]
        assert first.imag == 3.0                          # the same mode all along


def test_mode_names_are_continuous_on_the_default_case(default_sweep):
    """Default case, both loops: where two tracks cross in real part, neither changes its name and
    keeping them is a closer continuation than swapping them; a track's name changes only where its
    own content changes (its per-point rule name holds for MIN_NAME_RUN speeds) or it turns real/complex.

    Closeness of two eigenpairs: eigenvalue distance over (|a| + |b| + 1 1/s)
    plus half the L1 distance of their content shares (the eigenvalue alone
    cannot tell two real eigenvalues crossing apart). Measured: 38 crossings
    of differently named tracks, none with a name change; the kept
    continuation costs at most 0.3 of the swapped one, except 0.65 at 3.7 m/s
    closed loop, where the weave pair and the capsize eigenvalue are about to
    merge (shares within 0.02) and keeping them keeps the pair complex and
    the capsize real. Content changes (modes exchanging character where their
    eigenvalues veer, all below 4 m/s): 7 in the two loops. The expected modes all appear; conjugates share a name.
    """
    table = default_sweep.eigenvalues
    share_cols = [f"share_{g}" for g in stability.GROUPS]
    crossings, worst, changes = 0, 0.0, 0
    for (model, loop), g in table.groupby(["model", "loop"]):
        pivot = lambda col: g.pivot(index="speed_m_s", columns="track", values=col)
        lam = (pivot("real_1_s") + 1j * pivot("imag_1_s")).to_numpy()
        names = pivot("mode").to_numpy()
        shares = np.stack([pivot(c).to_numpy() for c in share_cols], axis=-1)
        freq = pivot("frequency_hz").to_numpy()
        rule = np.vectorize(lambda k, j: stability.name_mode(shares[k, j], lam[k, j].imag == 0, freq[k, j]))(
            *np.indices(names.shape))
        dist = lambda k0, a, k1, b: (abs(lam[k0, a] - lam[k1, b]) / (abs(lam[k0, a]) + abs(lam[k1, b]) + 1)
                                     + 0.5 * np.abs(shares[k0, a] - shares[k1, b]).sum())
        renamed = set()
        for k in range(lam.shape[0] - 1):
            for i in range(lam.shape[1]):
                if names[k, i] != names[k + 1, i] and (lam[k, i].imag == 0) == (lam[k + 1, i].imag == 0):
                    changes += 1
                    renamed.add((k, i))
                    run = rule[k + 1:k + 1 + stability.MIN_NAME_RUN, i]
                    assert (run == names[k + 1, i]).all(), (model, loop, k, i, names[k, i], names[k + 1, i])
            for i in range(lam.shape[1]):
                for j in range(i + 1, lam.shape[1]):
                    before, after = lam[k, i].real - lam[k, j].real, lam[k + 1, i].real - lam[k + 1, j].real
                    if before * after < 0 and names[k, i] != names[k, j]:
                        crossings += 1
                        assert (k, i) not in renamed and (k, j) not in renamed
                        kept = dist(k, i, k + 1, i) + dist(k, j, k + 1, j)
                        swapped = dist(k, i, k + 1, j) + dist(k, j, k + 1, i)
                        worst = max(worst, kept / swapped)
        for _speed, rows in g.groupby("speed_m_s"):
            for r in rows[rows["imag_1_s"] > 0].itertuples():
                partner = rows[(rows["real_1_s"] == r.real_1_s) & (rows["imag_1_s"] == -r.imag_1_s)]
                assert list(partner["mode"]) == [r.mode]
    assert crossings > 20 and worst < 0.8 and changes < 20, (crossings, worst, changes)
    slip_modes = set(table[table["model"] == "slip"]["mode"])
    assert {"weave", "capsize", "caster", "wobble", "lateral_rear", "relaxation_rear", "relaxation_front",
            "vertical"} <= slip_modes


# ------------------------------------------------------------ the stiff-tyre limit

def test_stiff_tyres_give_the_classic_speeds_and_modes(rigid_sweep):
    """Near-rigid linear tyre (1e5 /rad, 1e-5 m, 1e10 N/m): weave and capsize speeds to 0.5 %,
    weave, capsize and caster eigenvalues to 1e-3 at 2, 4, 6 m/s, open and closed loop.

    The slip model's modes are found by their names (rules on eigenvector
    content), the classic ones by theirs: the naming must agree. Measured:
    speeds 1.1e-6, eigenvalues 1.0e-4 (the capsize eigenvalue at 6 m/s, 0.010
    1/s, just past its zero crossing), elsewhere <= 2e-5. The no-slip speeds
    from the canonical matrices equal classic.weave_speed/capsize_speed to
    1e-8 m/s (two root-finders on two routes to the same matrices).
    """
    s = rigid_sweep.summary
    moore, _, _ = wk.assembly.build_bicycle(DEFAULT.bicycle_spec)
    weave, capsize = classic.weave_speed(moore, (2.0, 8.0)), classic.capsize_speed(moore, (4.0, 15.0))
    assert abs(s["no-slip"]["open"]["weave_speed_m_s"] - weave) < 1e-8
    assert abs(s["no-slip"]["open"]["capsize_speed_m_s"] - capsize) < 1e-8
    assert abs(s["slip"]["open"]["weave_speed_m_s"] / weave - 1) < 5e-3
    assert abs(s["slip"]["open"]["capsize_speed_m_s"] / capsize - 1) < 5e-3
    table = rigid_sweep.eigenvalues
    for loop in ("open", "closed"):
        for v in (2.0, 4.0, 6.0):
            for mode in ("weave", "capsize", "caster"):
                ref = _eigs(table, "no-slip", loop, v, mode)
                got = _eigs(table, "slip", loop, v, mode)
                assert len(got) == len(ref)
                if len(ref):
                    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-3, (loop, v, mode, got, ref)
    # every classic eigenvalue is named, and each of the three names occurs
    assert set(table[(table["model"] == "no-slip")]["mode"]) == {"weave", "capsize", "caster"}


# ------------------------------------------------------------ the default case

def test_measured_tyres_shrink_the_self_stable_range(default_sweep):
    """Symmetric T03, 400 kPa, 635 N, no control: an earlier quick look (weave stable near 3.9 m/s,
    a real mode unstable at +0.4 to +0.7 1/s above 4 m/s, a 9-10 Hz mode), confirmed.

    Weave stable from 3.82 m/s (first look: "near 3.9"); a real, roll-dominated
    (capsize) eigenvalue unstable from 3.88 m/s at every speed up to 10 m/s,
    +0.39 at 4 m/s, +0.45 to +0.72 1/s above (first look: +0.4 to +0.7); so the
    knife-edge bicycle's self-stable range 3.97-5.93 m/s shrinks to
    3.82-3.88 m/s; a 9-10 Hz mode at 1 m/s, -1.27 +- 59.69j (first look:
    -1.3 +- 59.7j), which is steer and the front tyre: named wobble.
    """
    s = default_sweep.summary["slip"]["open"]
    assert 3.7 < s["weave_speed_m_s"] < 3.9
    assert s["weave_speed_m_s"] < s["capsize_speed_m_s"] < 3.95
    (rng,) = s["stable_speed_ranges"]
    assert rng["to_m_s"] - rng["from_m_s"] < 0.1
    table = default_sweep.eigenvalues
    above = table[(table["model"] == "slip") & (table["loop"] == "open") & (table["speed_m_s"] > 4.0)]
    capsize = above[above["mode"] == "capsize"].groupby("speed_m_s")["real_1_s"].max()
    assert len(capsize) == len(above["speed_m_s"].unique())
    assert capsize.min() > 0.4 and capsize.max() < 0.75
    wobble = _eigs(table, "slip", "open", 1.0, "wobble")
    assert np.allclose(wobble, [-1.27 - 59.69j, -1.27 + 59.69j], atol=0.02)
    noslip = default_sweep.summary["no-slip"]["open"]["stable_speed_ranges"]
    assert [round(noslip[0]["from_m_s"], 2), round(noslip[0]["to_m_s"], 2)] == [3.97, 5.93]


@pytest.mark.parametrize("pressure", [300.0, 400.0, 500.0])
def test_wobble_exists_and_matches_a_free_response(pressure):
    """T03 at 300-500 kPa: a steer oscillation on the front tyre (wobble) exists; its frequency and
    damping from the nonlinear model's free response (closed loop, 3 m/s) match the eigenvalue to 2 %.

    The response starts from the steady motion displaced by 1e-4 rad along
    the mode's eigenvector and is integrated (LSODA, rtol 1e-11) for 1 s;
    the mode's amplitude (left-eigenvector projection) is fitted with
    e^(st)(a cos wt + b sin wt). Measured agreement <= 9e-7 (rate) and
    <= 4e-7 (frequency): the wobble is linear at this amplitude. Content: steer carries 10 times the roll and the heading,
    and the front tyre's lag is the largest share.
    """
    model = stability.linear_model(Scenario(symmetric_tyres=True, pressure_kpa=pressure), 3.0, "closed")
    lam, vec = np.linalg.eig(model.matrix)
    wheelbase = modes._wheelbase(wk.assembly.build_bicycle(DEFAULT.bicycle_spec)[0])
    named = [(k, stability.name_mode(stability.mode_content(model, lam[k], vec[:, k], wheelbase)[0],
                                     lam[k].imag == 0, abs(lam[k].imag) / (2 * math.pi)))
             for k in range(lam.size)]
    wobble = [k for k, name in named if name == "wobble" and lam[k].imag > 0]
    assert len(wobble) == 1
    k = wobble[0]
    assert 8.0 < lam[k].imag / (2 * math.pi) < 10.0 and lam[k].real < 0
    shares = stability.mode_content(model, lam[k], vec[:, k], wheelbase)[0]
    roll, steer, heading, _, rear, front = shares
    assert steer > 10 * max(roll, heading) and front == max(shares)
    t, dev = stability.free_response(model, vec[:, k], 1e-4, duration=1.0, rate=2000.0)
    eta = stability.modal_coordinate(model, k, dev)
    fit = stability.fit_eigenvalue(t, np.column_stack([eta.real, eta.imag]))
    assert abs(fit.real - lam[k].real) < 0.02 * abs(lam[k].real)
    assert abs(fit.imag - lam[k].imag) < 0.02 * lam[k].imag


@pytest.mark.parametrize("speed, mode", [(3.6, "weave"), (6.0, "capsize")])
def test_growth_of_a_weakly_unstable_mode_matches_the_nonlinear_model(speed, mode):
    """Open loop, symmetric T03, 400 kPa: the weave at 3.6 m/s (+0.40 +- 0.86j) and the capsize at
    6 m/s (+0.70): growth rate and frequency from the nonlinear model within 2 % of the eigenvalue.

    1e-4 rad along the eigenvector, 4 s (weave) or 3 s (capsize): the
    amplitude grows five- to eightfold and stays below 1e-3 rad. Measured
    9e-4 and 7e-4 (weave rate, frequency), 4e-4 (capsize rate): the
    nonlinearity at that amplitude.
    """
    model = stability.linear_model(DEFAULT, speed, "open")
    lam, vec = np.linalg.eig(model.matrix)
    slow = np.abs(lam) < 5.0
    if mode == "weave":
        k = int(np.argmax(np.where(slow & (lam.imag > 0), lam.real, -np.inf)))
    else:
        k = int(np.argmax(np.where(slow & (lam.imag == 0), lam.real, -np.inf)))
    assert 0.2 < lam[k].real < 1.0
    t, dev = stability.free_response(model, vec[:, k], 1e-4, duration=4.0 if mode == "weave" else 3.0)
    eta = stability.modal_coordinate(model, k, dev)
    osc = lam[k].imag != 0
    fit = stability.fit_eigenvalue(t, np.column_stack([eta.real, eta.imag]) if osc else eta.real[:, None],
                                   oscillatory=osc)
    assert abs(fit.real - lam[k].real) < 0.02 * abs(lam[k].real)
    assert abs(fit.imag - abs(lam[k].imag)) <= 0.02 * abs(lam[k].imag)
    assert np.abs(dev[:, model.states.index("q4")]).max() < 1e-3


def test_fit_finds_a_known_oscillation():
    t = np.linspace(0.0, 2.0, 801)
    y = np.column_stack([np.exp(0.3 * t) * np.sin(7.0 * t + 0.4), 2 * np.exp(0.3 * t) * np.cos(7.0 * t)])
    lam = stability.fit_eigenvalue(t, y)
    assert abs(lam - (0.3 + 7.0j)) < 1e-9


# ------------------------------------------------------------ StateSpace and tables

def test_state_space_has_named_states_and_the_loops_poles():
    """control.StateSpace: 14 named states, the steer torque as input; poles = the analysis's eigenvalues."""
    model = stability.linear_model(DEFAULT, 4.0, "closed")
    sys_cl = model.state_space()
    sys_ol = model.state_space(closed=False)
    assert sys_cl.nstates == 14 and sys_cl.input_labels == ["steer_torque"]
    assert sys_cl.state_labels[:2] == ["roll", "steer"] and "carcass_deflection_front" in sys_cl.state_labels
    assert sys_cl.output_labels == sys_cl.state_labels
    ref = np.sort_complex(np.linalg.eigvals(model.A - model.B @ model.K))
    assert np.allclose(np.sort_complex(sys_cl.poles()), ref)
    # closing the loop by hand with the rider's gains on the open-loop system gives the same poles
    import control as ct
    closed = ct.feedback(sys_ol, ct.ss([], [], [], model.K), sign=-1)
    assert np.allclose(np.sort_complex(closed.poles()), ref, rtol=1e-9, atol=1e-9)
    # the rider's gains, by name, on roll, steer and their rates
    gains, _ = wk.assembly.controller_gains(DEFAULT.with_changes(speed=4.0).gains_spec,
                                           wk.assembly.build_bicycle(DEFAULT.bicycle_spec)[1])
    for g, state in (("kq4", "q4"), ("kq7", "q7"), ("ku4", "u4"), ("ku7", "u7")):
        assert model.K[0, model.states.index(state)] == gains[g]


def test_tables_and_summary(default_sweep):
    table = default_sweep.eigenvalues
    assert {"model", "loop", "speed_m_s", "track", "mode", "real_1_s", "imag_1_s", "frequency_hz",
            "damping_ratio", *[f"share_{g}" for g in stability.GROUPS]} <= set(table.columns)
    assert table[table["model"] == "slip"].groupby(["loop", "speed_m_s"]).size().eq(14).all()
    assert table[table["model"] == "no-slip"].groupby(["loop", "speed_m_s"]).size().eq(4).all()
    assert np.isfinite(table.select_dtypes("number").to_numpy()).all()
    shares = table[[f"share_{g}" for g in stability.GROUPS]].sum(axis=1)
    assert np.allclose(shares, 1.0)
    json.dumps(wk.results.clean(default_sweep.summary), allow_nan=False)
    steady = default_sweep.steady
    assert steady["found_by"].notna().all() and steady["roll_rad"].abs().max() < 1e-12
    # the state space of one sweep speed
    assert default_sweep.state_space(3.0, "open").nstates == 14


def test_measured_offsets_are_linearised_about_the_steady_turn():
    """With the measured offsets the open-loop steady motion approaching 3.8 m/s is a steady turn (7.3 deg of
    lean at 3.7 m/s, measured), which the summary reports (the eigenvalues are those of that turn). Before
    issue 40 the sweep continued it to a 26 deg turn at 5 m/s; a start is now near-upright (within 10 deg)."""
    res = stability.analyse(Scenario(), [3.0, 3.7, 5.0], loops=("open",))
    lean = res.summary["steady_motion"]["open"]["largest_lean_rad"]
    assert stability.TURN_NOTE_DEG < math.degrees(lean) <= wk.steady.NEAR_UPRIGHT_DEG
    assert any("turn with up to" in line for line in stability.report_lines(res.summary))


# ------------------------------------------------------------ speeds and the command

def test_parse_speeds():
    v = stability.parse_speeds("0.5:10:0.05")
    assert v.size == 191 and v[0] == 0.5 and abs(v[-1] - 10.0) < 1e-12
    assert list(stability.parse_speeds("2,3.5,4")) == [2.0, 3.5, 4.0]
    for bad, words in (("1:2", "START:STOP:STEP"), ("a:b:c", "START:STOP:STEP"), ("3:1:0.5", "below START"),
                       ("1:2:0", "speed step"), ("0:2:0.5", "speed = 0"), ("1,20", "speed = 20"),
                       ("3,2", "increase"), ("0.001:10:0.001", "at most")):
        with pytest.raises(wk.errors.InputError, match=words):
            stability.parse_speeds(bad)


def test_cli_writes_the_three_files(tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exc:
        cli.stability_main(["--pressure", "400", "--fz", "635", "--speeds", "3:5:0.5", "--out", str(out)])
    assert exc.value.code == 0
    printed = capsys.readouterr().out
    assert "open loop" in printed and "closed loop" in printed and "weave" in printed
    assert len(printed.splitlines()) <= 14
    table = pd.read_csv(out / "eigenvalues.csv")
    assert set(table["loop"]) == {"open", "closed"} and set(table["model"]) == {"slip", "no-slip"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"]["symmetric_tyres"] is True and summary["loops"] == ["open", "closed"]
    assert summary["provenance"]["versions"]["whipple_kick"] == wk.__version__    # issue 25: provenance here too
    assert set(summary["provenance"]["input_files"]) == {"bicycle", "rider", "tyre"}
    assert (out / "stability.png").stat().st_size > 10000


@pytest.mark.parametrize("argv, words", [
    (["--speeds", "5:1:1"], "below START"),
    (["--speeds", "1:3"], "START:STOP:STEP"),
    (["--pressure", "-3"], "pressure = -3"),
    (["--controller", "thesis", "--fz", "600"], "570, 635 and 701"),
    (["--fz", "abc"], "not a number"),
    (["--speed", "3"], "unrecognized arguments"),
])
def test_cli_bad_input_is_one_line_with_status_2(tmp_path, capsys, argv, words):
    with pytest.raises(SystemExit) as exc:
        cli.stability_main([*argv, "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_cli_controller_off_has_the_open_loop_only(tmp_path, capsys):
    out = tmp_path / "off"
    with pytest.raises(SystemExit) as exc:
        cli.stability_main(["--controller", "off", "--speeds", "4,5", "--out", str(out), "--no-plot", "--quiet"])
    assert exc.value.code == 0 and capsys.readouterr().out == ""
    assert set(pd.read_csv(out / "eigenvalues.csv")["loop"]) == {"open"}
    assert not (out / "stability.png").exists()


# ------------------------------------------------------------------ root finding that may fail

def test_root_without_a_bracket_is_not_found_with_a_reason():
    """Before, _root extrapolated linearly outside [a, b] and returned that as the crossing speed."""
    speed, why = summary._root(lambda v: v + 1.0, 2.0, 3.0)     # +3 and +4: no sign change
    assert speed is None and "does not change sign between 2 and 3 m/s" in why
    speed, why = summary._root(lambda v: v - 2.5, 2.0, 3.0)
    assert speed == pytest.approx(2.5, abs=1e-9) and why is None


class _WeaveTurnsIntoAnotherPair:
    """A stand-in sweep: the unstable weave at 1 m/s continues at 2 m/s as a stable oscillatory
    eigenvalue of another name, with no real eigenvalue near it (no split)."""

    def __init__(self):
        self.speeds = np.array([1.0, 2.0])
        self.lams = [np.array([0.5 + 2j]), np.array([-1.0 + 5j])]
        self.name = {(0, 7): "weave", (1, 7): "wobble"}

    def present(self, k):
        return True

    def values(self, k, mode):
        return [(complex(self.lams[k][0]), 7)] if self.name[k, 7] == mode else []

    def eigenvalue(self, k, track_id):
        return complex(self.lams[k][0])

    def tracked_real_part(self, k, track_id):
        return lambda v: 0.5 - 1.5 * (v - 1.0)


def test_weave_pair_that_neither_stays_nor_splits_is_not_found_with_a_reason():
    """Before, ``max`` over the empty list of split partners raised ValueError."""
    speed, why = summary._weave_speed(_WeaveTurnsIntoAnotherPair())
    assert speed is None and "without turning into two real eigenvalues" in why and "wobble" in why


def test_stable_range_with_an_end_not_located_says_so():
    text = stability.range_text({"from_m_s": 2.0, "to_m_s": 4.33, "lower_open": False, "upper_open": False,
                                 "note": "lower end not located, ..."})
    assert text == "2.00-4.33 (an end not located: at a sweep speed)"


# ------------------------------------------------------------------ weave and capsize where the weave pair splits

def _split_sweep(speeds):
    """A stand-in sweep on ``A(v) = [[a, 1], [v - 3.87, a]]``, ``a = 3.82 - v``: eigenvalues ``a +- sqrt(v - 3.87)``.

    A pair whose real part crosses zero at 3.82 m/s, splitting at 3.87 m/s
    into two real eigenvalues; the larger crosses zero at
    3.87 + (0.9 - sqrt(0.8)) / 2 m/s. Every eigenvector is named by roll: the
    pair is the weave, the real eigenvalues capsize.
    """
    from whipple_kick.studies.stability import summary
    from whipple_kick.studies.stability import sweep as sweep_module

    def eigen_at(v, k=None):
        return np.linalg.eig(np.array([[3.82 - v, 1.0], [v - 3.87, 3.82 - v]]))

    lams, vecs = zip(*(eigen_at(v) for v in speeds), strict=True)
    shares = [np.tile([1.0, 0, 0, 0, 0, 0], (2, 1))] * len(speeds)
    raw = {}
    rows = sweep_module._named_rows("slip", "open", speeds, list(lams), list(vecs), shares, raw)
    return summary._Sweep(pd.DataFrame(rows), np.asarray(speeds), raw["slip", "open"], eigen_at)


@pytest.mark.parametrize("speeds", [np.arange(3.5, 4.25, 0.1), np.arange(3.5, 4.25, 0.05),
                                    np.arange(3.5, 4.25, 0.1) + 1e-12])
def test_weave_crossing_before_the_split_is_the_weave_speed(speeds):
    """Before, a pair that crossed zero and then split between two samples was reported as splitting
    while unstable, at a split speed interpolated from the samples (3.87 m/s on the 0.1 m/s grid); the
    weave is stable from its crossing, 3.82 m/s, and the capsize eigenvalue crosses zero after the split."""
    sweep = _split_sweep(speeds)
    weave, how = summary._weave_speed(sweep)
    assert weave == pytest.approx(3.82, abs=1e-8) and "crosses zero" in how
    capsize, how = stability.summary._capsize_speed(sweep, above=weave)
    assert capsize == pytest.approx(3.87 + (0.9 - math.sqrt(0.8)) / 2, abs=1e-8) and "after" in how


def test_weave_and_capsize_speeds_do_not_depend_on_round_off():
    """Symmetric T03, 400 kPa, 635 N, open loop: the weave pair crosses zero at 3.82 m/s, splits at
    3.87 m/s, and a real root crosses zero at 3.88 m/s, all between 3.8 and 3.9 on a 0.1 m/s grid.

    Before, on 2:6:0.1 the answer was 3.8606 m/s for both (a split speed
    interpolated from samples whose roots the tracker had paired one way),
    or 3.8718 m/s and no capsize speed with every speed moved by 1e-14 m/s
    (paired the other way), and 3.8184 and 3.8785 m/s on 2:6:0.05.
    Measured now: 3.81843 and 3.87854 m/s on all four, spread 3e-7 and
    8e-7 m/s: the linearisation itself differs by ~2e-8 of its largest entry
    between steady motions equal to 1e-15 (forward differences), which
    moves the eigenvalues by ~3e-7 1/s.
    """
    grid = stability.parse_speeds("2:6:0.1")
    out = []
    for speeds in (grid, grid + 1e-14, grid - 1e-12, stability.parse_speeds("2:6:0.05")):
        s = stability.analyse(DEFAULT, speeds, loops=("open",)).summary["slip"]["open"]
        out.append((s["weave_speed_m_s"], s["capsize_speed_m_s"]))
    weave, capsize = np.array(out, dtype=float).T
    assert np.all(np.abs(weave - 3.818) < 2e-3) and np.all(np.abs(capsize - 3.8785) < 2e-3), out
    assert np.ptp(weave) < 1e-5 and np.ptp(capsize) < 1e-5, out


def test_capsize_after_a_split_and_a_merge_between_two_sweep_speeds():
    """500 kPa, 635 N, open loop: between 3.75 and 3.8 m/s the weave pair splits (3.762 m/s) and the
    smaller real root merges with the low-speed capsize root into a new pair (3.792 m/s), so the number
    of complex eigenvalues is the same at both samples; the split is found by stepping through the
    interval, and the larger real root crosses zero at 3.7667 m/s (the weave at 3.7189, before it)."""
    sc = DEFAULT.with_changes(pressure_kpa=500.0)
    s = stability.analyse(sc, stability.parse_speeds("3.5:4:0.05"), loops=("open",)).summary["slip"]["open"]
    assert s["weave_speed_m_s"] == pytest.approx(3.7189, abs=1e-4)
    assert s["capsize_speed_m_s"] == pytest.approx(3.7667, abs=1e-4) and "after" in s["capsize_speed_how"]


# ------------------------------------------------------------ the rider's body

def _named(table, speed, mode):
    return table[(table["model"] == "slip") & np.isclose(table["speed_m_s"], speed) & table["mode"].isin(mode)
                 & (table["imag_1_s"] >= 0)]


def test_leaning_rider_has_a_lean_mode_near_the_hip_estimate():
    # A stiff, lightly damped hip so the lean oscillates (the default 128 N m/rad nearly cancels gravity).
    sc = DEFAULT.with_changes(rider_body="leaning", controller="off", hip_stiffness=400.0, hip_damping=5.0)
    res = stability.analyse(sc, [1.0, 1.5, 2.0])
    lean = _named(res.eigenvalues, 1.0, ["lean"])
    assert len(lean) == 1 and lean["share_lean"].iloc[0] > 0.5   # the eigenvector is mostly q11
    body = wk.assembly.rider_body(sc.body_spec, wk.assembly.build_bicycle(sc.bicycle_spec)[2])
    inertia = body["it11"] + body["mt"] * body["lt3"] ** 2          # about the hinge
    stiffness = 400.0 - body["mt"] * 9.81 * -body["lt3"]             # hip spring less gravity
    f_sdof = math.sqrt(stiffness / inertia) / (2 * math.pi)         # 1.04 Hz
    f = lean["frequency_hz"].iloc[0]                                 # 1.67 Hz: the bicycle rolls and steers too
    assert 1.3 * f_sdof < f < 1.9 * f_sdof
    # The rigid rider's table has no lean or reflex columns (unchanged).
    assert "share_lean" not in stability.analyse(DEFAULT, [3.0], loops=("open",)).eigenvalues


def test_arm_steer_mode_frequency_rises_with_arm_stiffness():
    # Hands on, the steer oscillates on the arms: named arm_steer while the front tyre lags little
    # (2.9 Hz at 200 N m/rad), wobble once it takes the tyre along (4.1 Hz at 400, 5.8 Hz at 800).
    freqs = []
    for stiffness in (200.0, 400.0, 800.0):
        sc = DEFAULT.with_changes(arms="on", controller="off", arm_stiffness=stiffness, arm_damping=1.0)
        steer = _named(stability.analyse(sc, [2.5, 3.0, 3.5]).eigenvalues, 3.0, ["arm_steer", "wobble"])
        arm = steer.loc[steer["share_steer"].idxmax()]
        assert arm["share_steer"] > 0.4 and (stiffness > 200.0 or arm["mode"] == "arm_steer")
        freqs.append(float(arm["frequency_hz"]))
    assert freqs[0] < freqs[1] < freqs[2]


def test_reflex_filter_poles_are_named_reflex_delay():
    # The open loop keeps the reflex (the body's, not the voluntary law's); controller "off" refuses a reflex
    # (no rider torque at all), so the scenario keeps its rider.
    sc = DEFAULT.with_changes(reflex_delay=0.1, reflex_roll=20.0, reflex_roll_rate=5.0)
    res = stability.analyse(sc, [3.5, 4.0, 4.5], loops=("open",))
    assert len(_named(res.eigenvalues, 4.0, ["reflex_delay"])) >= 1
    model = res.models["open", 1]
    assert model.states[-4:] == slip.REFLEX_STATES and model.matrix.shape == (18, 18)


def test_pressure_load_figure_draws_the_nine_case_table(tmp_path):
    """The figure of the pressure-load table: three loads (the nine thesis cases) draw one colour each; it
    raised a ValueError before (three loads zipped strictly against four colours)."""
    import pandas as pd

    from whipple_kick.studies.stability.pressure_load import pressure_load_figure

    rows = [{"fz_n": fz, "pressure_kpa": p, "at_speed_m_s": 2.0, "weave_speed_m_s": 3.8, "capsize_speed_m_s": 3.9,
             "noslip_weave_speed_m_s": 4.1, "noslip_capsize_speed_m_s": 6.0, "closed_weave_damping_ratio": 0.5,
             "closed_slowest_real_1_s": -1.0, "closed_wobble_frequency_hz": 9.0, "closed_wobble_damping_ratio": 0.05}
            for fz in (570.0, 635.0, 701.0) for p in (300.0, 400.0, 500.0)]
    path = pressure_load_figure(pd.DataFrame(rows), tmp_path / "pl.png")
    assert path.stat().st_size > 10_000


@pytest.mark.parametrize("changes", [{"carcass_damping": 200.0}, {"carcass_stiffness_scale": 0.5}],
                         ids=["carcass_damping", "carcass_stiffness_scale"])
def test_the_carcass_options_of_the_scenario_enter_the_linear_model(changes):
    """The analysis builds its model as a run does (assembly.model_parameters): the carcass tyre's damping and
    stiffness scale move the open-loop eigenvalues (measured: by 9.6 and 4.3 1/s at 3 m/s). Before, the
    analysis left them out, so a stability sweep over them gave identical rows."""
    base = stability.analyse(DEFAULT, [3.0], loops=("open",)).eigenvalues["real_1_s"].to_numpy()
    changed = stability.analyse(DEFAULT.with_changes(**changes), [3.0], loops=("open",)).eigenvalues
    assert np.abs(changed["real_1_s"].to_numpy() - base).max() > 1.0


@pytest.mark.parametrize("name", stability.sweep.NOT_ANALYSED)
def test_fields_the_analysis_does_not_read_are_refused(name):
    """A kick, run, integration or start field set other than its default would be ignored by the linear
    analysis: one line naming it and its default (the walk's non-default value of each field)."""
    from conftest import other_value

    value = other_value(name, "other_rider")   # (the rider is not among these fields)
    with pytest.raises(wk.InputError, match=rf"^{name} = .* is not read by the stability analysis .* default"):
        stability.analyse(DEFAULT.with_changes(**{name: value}), [3.0], loops=("open",))


def test_the_sweep_linearises_only_about_near_upright_steady_motions():
    """Issue 40: with the 3 m/s design and measured tyres the sweep linearised about steady turns at 85 deg of
    steer at 2.6-2.7 m/s (between near-upright points at 2.5 and 2.8 m/s). Over 1-6 m/s in 0.1 m/s steps, both
    loops: every steady motion is a start by the steady search's bounds (lean and steer within 10 deg, slip
    within the measured 6 deg), none has more than 45 deg of steer (the issue's bound), and the speeds without
    one are left out with the one-line reason (2.5-2.7 m/s closed loop among them, measured)."""
    from whipple_kick.simulate import steady
    speeds = np.round(np.arange(1.0, 6.001, 0.1), 2)
    result = stability.analyse(Scenario(design_speed=3.0), speeds)
    rows = result.steady
    found = rows[rows["found_by"].notna()]
    assert len(found) > 0.7 * len(rows)
    assert np.all(np.abs(np.degrees(found["steer_rad"])) <= steady.NEAR_UPRIGHT_DEG)
    assert np.all(np.abs(np.degrees(found["roll_rad"])) <= steady.NEAR_UPRIGHT_DEG)
    assert len(result.models) == len(found)
    for (loop, _), model in result.models.items():
        assert steady.start_problem(model.steady) is None, (loop, model.speed)
    missing = rows[rows["found_by"].isna()]
    closed_missing = set(missing[missing["loop"] == "closed"]["speed_m_s"])
    assert {2.6, 2.7} <= closed_missing
    assert all(m.startswith("no near-upright steady motion at") and "\n" not in m for m in missing["message"])

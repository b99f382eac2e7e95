"""The slip model's build side: the compiled C against the NumPy oracle, the metadata written beside the library."""
import json

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.model import cache, slip
from whipple_kick.model.symbolic import slip_build
from whipple_kick.simulate import steady

# Spread of the random tyre states: forces [N] and moments [N m] for the
# thesis' form, patch slip and camber angles [rad] for the contact forms, carcass
# deflections [m] (up to 620 N rear: on and past the friction limit) and lagged cambers.
_TYRE_SPREAD = {"force_lag": (200.0, 200.0, 5.0, 5.0), "contact_patch": (0.6, 0.6, 0.3, 0.3),
                "slip_lag": (0.6, 0.6, 0.3, 0.3), "carcass": (0.015, 0.015, 0.3, 0.3)}


@pytest.mark.parametrize("transient", wk.transient.transients())
def test_c_agrees_with_numpy_oracle(rider_bike, gains, t03, transient):
    """100 random states, plate moving or not: C and the NumPy printing of the same expressions.

    Every state derivative (quadrature rates included, with the rear
    constraint's power while the plate moves or a rear slide is imposed)
    and every named output.
    """
    par = slip.model_parameters(rider_bike, t03, wk.tyres.load("T03", pressure_kpa=350),
                                slip.ModelOptions(tyre_transient=transient), gains=gains,
                                kick=dict(t0=0.0, duration=0.15, displacement=0.15))
    ss = steady.steady_state(par, 3.0)
    params = ss.params.replace(vsx_r=-0.2)   # a rear slide as the authors' plate stop leaves, in both printings
    rhs = slip.CompiledRHS(params)
    p = slip.parameter_vector(params)
    rng = np.random.default_rng(1)
    worst = 0.0
    # The carcass' patch slip inverts the steady curve, ill-conditioned near its peak (dF/da -> 0): two exact
    # inversions of one force (closed form + Newton in C, bracketed root finding in Python) agree there only to
    # ~eps F / (dF/da); measured 1.6e-9 relative on these states (the symbolic forms: ~1e-14).
    tol = 1e-8 if transient == "carcass" else 1e-10
    for _ in range(100):
        x = ss.x.copy()
        for name, spread in (("q3", 0.5), ("q4", 0.3), ("q7", 0.3), ("q5", 0.01), ("u1", 1.0), ("u2", 0.5),
                             ("u3", 1.0), ("u4", 1.0), ("u7", 1.0), ("u9", 0.05), ("u10", 0.05),
                             *zip(slip.PATCH_STATES, _TYRE_SPREAD[transient], strict=True)):
            x[slip.X[name]] += rng.uniform(-spread, spread)
        x[slip.X["q9"]] = rng.uniform(0.0, 0.01)
        x[slip.X["q10"]] = rng.uniform(0.0, 0.01)
        t = rng.uniform(-0.05, 0.2)
        dx_c, out_c = rhs.outputs(t, x)
        dx_n, out_n = slip_build.numpy_rhs(t, x, p, ss.params.model, with_outputs=True)
        # Same expressions, different evaluation order: agreement is limited
        # by the conditioning of the two small linear solves, ~1e-14 here.
        np.testing.assert_allclose(dx_c, dx_n, rtol=tol, atol=tol * np.abs(dx_n).max())
        np.testing.assert_allclose(out_c, out_n, rtol=tol, atol=tol * np.abs(out_n).max())
        worst = max(worst, np.abs(dx_c - dx_n).max() / np.abs(dx_n).max())
    assert worst < tol


def test_metadata_beside_the_library_describes_its_layouts():
    """Plain data written at build time: every state, parameter and output by position, with unit and description."""
    path = slip.library_path().with_suffix(".json")
    data = json.loads(path.read_text())
    assert data["layout"] == slip.metadata_layout()
    assert [s["name"] for s in data["states"]] == list(slip.STATE_NAMES)
    assert [p["name"] for p in data["parameters"]] == list(slip.PARAMETER_NAMES)
    assert [o["name"] for o in data["outputs"]] == list(slip.OUTPUT_NAMES)
    for entry in data["states"] + data["parameters"] + data["outputs"]:
        assert entry["unit"] and entry["description"], entry
    assert data["generated_with"]["sympy"] == cache.sympy_version()
    assert path.stat().st_mode & 0o777 == 0o600


def _entry_copy(tmp_path):
    """A private cache holding a copy of the current library and its metadata."""
    folder = tmp_path / "cache"
    folder.mkdir(mode=0o700)
    lib = slip.library_path()
    for source in (lib, lib.with_suffix(".json")):
        target = folder / source.name
        target.write_bytes(source.read_bytes())
        target.chmod(0o600)
    return folder, folder / lib.name


@pytest.mark.parametrize("damage", ["missing", "other layout", "not json"])
def test_library_without_matching_metadata_is_built_again(tmp_path, monkeypatch, damage):
    """A library whose metadata is missing or records other layouts is rebuilt, never loaded as it is."""
    folder, lib = _entry_copy(tmp_path)
    meta = lib.with_suffix(".json")
    if damage == "missing":
        meta.unlink()
    elif damage == "other layout":
        data = json.loads(meta.read_text())
        data["layout"]["outputs"] = data["layout"]["outputs"][:-1]
        meta.write_text(json.dumps(data))
    else:
        meta.write_text("{")
    good = slip.library_path()   # the user's cache, before switching to the copy
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(folder))
    builds = []

    def build_library(path, key, compiler, flags, part_names=(), delayed_reflex=False):   # stands in for the build
        builds.append(key)
        path.write_bytes(good.read_bytes())
        (folder / f"slip_{key}.json").write_text(good.with_suffix(".json").read_text())

    monkeypatch.setattr(slip_build, "build_library", build_library)
    lib_loaded = slip.compiled._library.__wrapped__(slip.layout.BASE, wk.transient.fingerprint())   # not the cached one
    assert len(builds) == 1 and json.loads(meta.read_text())["layout"] == slip.metadata_layout()
    assert lib_loaded.wk_slip_rhs is not None

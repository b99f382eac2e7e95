"""The tyre library against the thesis' Chapter 7 tables, and its API contract."""
import re
import shutil
import warnings

import numpy as np
import pytest

from whipple_kick.errors import InputError
from whipple_kick.library import tyres
from whipple_kick.model import magic_formula

DEG = np.pi / 180.0

# Thesis Table 7.8 as printed: (tyre, pressure kPa, Fz N) -> (B "1/rad", C, D N, E).
# T02 is left out: its Table 7.9 columns do not reproduce these (checked below).
TABLE_7_8 = {
    ("T01", 400, 411): ("11.108", "1.0000", "398.230", "0.5213"),
    ("T01", 400, 526): ("10.114", "1.0000", "546.033", "0.4988"),
    ("T03", 300, 343): ("10.6331", "1.5625", "321.118", "-0.3820"),
    ("T03", 300, 404): ("10.3936", "1.5625", "360.252", "-0.4420"),
    ("T03", 300, 488): ("10.0234", "1.5625", "405.258", "-0.5246"),
    ("T03", 400, 343): ("9.9666", "1.6000", "316.789", "-0.4213"),
    ("T03", 400, 404): ("9.7117", "1.6000", "365.284", "-0.4486"),
    ("T03", 400, 488): ("9.3031", "1.6000", "428.186", "-0.4861"),
    ("T03", 500, 343): ("13.8482", "1.0244", "348.391", "-0.7466"),
    ("T03", 500, 404): ("13.3350", "1.0244", "393.777", "-0.7026"),
    ("T03", 500, 488): ("12.5839", "1.0244", "448.085", "-0.6421"),
    ("T04", 300, 343): ("17.0600", "1.0000", "330.315", "-1.6132"),
    ("T04", 300, 404): ("16.6914", "1.0000", "373.278", "-1.3917"),
    ("T04", 300, 488): ("16.1005", "1.0000", "424.641", "-1.0866"),
    ("T04", 400, 343): ("10.8962", "1.6000", "310.432", "0.3024"),
    ("T04", 400, 404): ("10.7549", "1.6000", "353.128", "0.4336"),
    ("T04", 400, 488): ("10.4996", "1.6000", "405.738", "0.6143"),
    ("T04", 500, 343): ("15.3858", "1.0000", "370.962", "0.5264"),
    ("T04", 500, 404): ("15.0201", "1.0000", "399.133", "-1.3455"),
    ("T04", 500, 488): ("14.6632", "1.0000", "419.242", "-3.9231"),
    ("T05", 300, 343): ("11.3790", "1.5541", "385.168", "-0.8070"),
    ("T05", 300, 404): ("10.7231", "1.5541", "448.247", "-0.7371"),
    ("T05", 300, 488): ("9.7935", "1.5541", "532.432", "-0.641"),
    ("T05", 400, 343): ("10.6008", "1.6000", "426.654", "0.3200"),
    ("T05", 400, 404): ("10.8454", "1.6000", "455.165", "-0.5092"),
    ("T05", 400, 488): ("11.2969", "1.6000", "471.015", "-1.6511"),
}

# Measured cornering stiffness at zero camber, N/deg: thesis Tables 7.2 (T01),
# 7.3 (T02), 7.4 (T03), 7.5 (T04), 7.6 (T05). tyre -> (loads N, {kPa: values}).
MEASURED_STIFFNESS = {
    "T01": ((411.0, 526.0), {400: (85.1, 105.5)}),
    "T02": ((411.0, 449.0, 526.0), {300: (117.2, 127.4, 140.7), 400: (124.0, 136.3, 143.1)}),
    "T03": ((343.0, 404.0, 488.0), {300: (105.2, 113.6, 123.5), 400: (98.2, 108.1, 124.4),
                                    500: (86.6, 90.1, 111.6)}),
    "T04": ((343.0, 404.0, 488.0), {300: (100.1, 107.0, 123.4), 400: (81.7, 89.6, 101.7),
                                    500: (79.1, 114.4, 120.3)}),
    "T05": ((343.0, 404.0, 488.0), {300: (132.0, 145.0, 158.5), 400: (121.1, 136.8, 149.8)}),
}


def _half_unit(text):
    """Half a unit of the last printed digit of ``text``."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return 0.5 * 10.0 ** -decimals


def _coefficient_rounding(tyre, pressure):
    """Half a unit of the last printed digit of each Table 7.9 coefficient.

    Read from the parameter file's own text, which keeps the printed digits.
    """
    text = (tyres.TYRE_DIR / f"{tyre}.toml").read_text()
    block = text.split(f"[coefficients.table7_9.{pressure}]")[1].split("fy = [")[1].split("\n]")[0]
    values = re.findall(r"^\s*(-?[0-9.]+),", block, flags=re.MULTILINE)
    assert len(values) == 14
    return np.array([_half_unit(v) for v in values])


@pytest.mark.parametrize("key", sorted(TABLE_7_8), ids=lambda k: f"{k[0]}-{k[1]}-{k[2]}")
def test_table_7_9_reproduces_table_7_8(key):
    """Factors from Table 7.9's coefficients reproduce Table 7.8.

    Tolerances:
    * C: exactly (C = a0 is copied).
    * D, E: to the printed digits, i.e. within half a unit of Table 7.8's last
      digit PLUS the effect of Table 7.9 itself being rounded (e.g. a2 =
      1186.4 is known to +-0.05, which moves D by up to 0.05*Fz[kN] N,
      i.e. 0.02 N, more than Table 7.8's 0.0005 N). That bound is
      computed from the printed digits of each coefficient, not tuned.
    * B: Table 7.8 says 1/rad but converted B [1/deg] with a factor of 57
      instead of 180/pi = 57.2958 (0.52 % smaller). Confirmed: B*57 matches
      to 0.02 % (rounding of a3, a4 and D), B*180/pi only to 0.6 %, the
      acceptance tolerance.
    """
    tyre_name, pressure, fz = key
    b_txt, c_txt, d_txt, e_txt = TABLE_7_8[key]
    tyre = tyres.load(tyre_name, pressure)
    f = tyre.magic_formula_factors(fz)
    h = _coefficient_rounding(tyre_name, pressure)
    fz_kn = fz / 1000.0

    assert float(f["C"]) == float(c_txt)
    d_bound = _half_unit(d_txt) + h[1] * fz_kn**2 + h[2] * fz_kn
    assert abs(float(f["D"]) - float(d_txt)) <= d_bound
    e_bound = _half_unit(e_txt) + h[6] * fz_kn + h[7]
    assert abs(float(f["E"]) - float(e_txt)) <= e_bound
    assert float(f["B"]) * 57.0 == pytest.approx(float(b_txt), rel=2e-4)
    assert float(f["B"]) * 180.0 / np.pi == pytest.approx(float(b_txt), rel=6e-3)


def test_t02_columns_do_not_reproduce_table_7_8_and_warn():
    """The known inconsistency: Table 7.9's T02 D at 300 kPa, 343 N is 301 N,
    Table 7.8 prints 361.232 N (17 % off). Loading T02 must warn."""
    with pytest.warns(UserWarning, match="T02"):
        tyre = tyres.load("T02", 300)
    d = float(tyre.magic_formula_factors(343.0)["D"])
    assert abs(d / 361.232 - 1) > 0.15


def _fitted_stiffness_n_per_deg(tyre_name, pressure, loads):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # T02's known-inconsistency warning
        tyre = tyres.load(tyre_name, pressure)
    return tyre.cornering_stiffness(np.array(loads)) * DEG


def stiffness_deviation_table():
    """Rows (tyre, kPa, Fz, measured N/deg, fitted N/deg, deviation %) for docs/tyres.md."""
    rows = []
    for name, (loads, by_pressure) in MEASURED_STIFFNESS.items():
        for pressure, measured in by_pressure.items():
            fitted = _fitted_stiffness_n_per_deg(name, pressure, loads)
            for fz, m, f in zip(loads, measured, fitted, strict=True):
                rows.append((name, pressure, fz, m, f, 100.0 * (f / m - 1.0)))
    return rows


def test_stiffness_deviation_from_measurement_is_the_published_fit_error():
    """The fit errors against Tables 7.2-7.6 as published in docs/tyres.md.

    Nothing is tuned: this pins the numbers the docs quote (to their printed
    0.1 %), so a change to the data or formula that moves them fails here.
    The largest is T04 at 500 kPa and 343 N, +26.5 %.
    """
    rows = {(r[0], r[1], r[2]): r[5] for r in stiffness_deviation_table()}
    assert max(abs(v) for v in rows.values()) == pytest.approx(26.5, abs=0.05)
    assert rows[("T04", 500, 343.0)] == pytest.approx(26.5, abs=0.05)
    assert rows[("T03", 400, 404.0)] == pytest.approx(-7.9, abs=0.05)


@pytest.mark.parametrize("name", sorted(MEASURED_STIFFNESS))
def test_fitted_stiffness_rises_with_load_where_measurement_does(name):
    loads, by_pressure = MEASURED_STIFFNESS[name]
    for pressure, measured in by_pressure.items():
        fitted = _fitted_stiffness_n_per_deg(name, pressure, loads)
        rises = np.diff(measured) > 0
        assert np.all(np.diff(fitted)[rises] > 0), (name, pressure, fitted)


# -- the API -----------------------------------------------------------------

def test_available_lists_tyres_pressures_and_sets():
    listing = {name: (pressures, sets) for name, pressures, sets in tyres.available()}
    assert listing["T01"] == ((400.0,), ("table7_9",))
    assert listing["T03"] == ((300.0, 400.0, 500.0), ("table7_9", "chapter8"))
    assert set(listing) == {"T01", "T02", "T03", "T04", "T05"}


def test_properties_and_units():
    tyre = tyres.load("T03", 500)
    assert tyre.vertical_stiffness == 133000.0  # Table 8.5, 133 N/mm
    assert tyre.vertical_damping == 4000.0
    assert tyre.relaxation_length == 0.175
    assert tyre.crown_radius == 0.01
    assert tyre.friction_ratio == pytest.approx(1.03 / 0.79, rel=1e-12)
    [(weight, fy, mz)] = tyre.blend
    assert weight == 1.0 and fy.shape == (14,) and mz.shape == (18,)
    # the default T03 set: Table 7.9 F_y (C = 1.0244 at 500 kPa), Chapter 8 M_z
    chapter8 = tyres.load("T03", 500, coefficient_set="chapter8")
    assert fy[0] == 1.0244
    np.testing.assert_array_equal(mz, chapter8.blend[0][2])
    assert chapter8.blend[0][1][0] == 2.82190142692177


def test_interpolated_pressure_lies_between_its_neighbours():
    low, mid, high = (tyres.load("T03", p) for p in (300, 350, 400))
    assert [w for w, _, _ in mid.blend] == [0.5, 0.5]
    assert mid.vertical_stiffness == pytest.approx(93000.0)  # halfway 80 and 106 N/mm
    slip = np.linspace(-10, 10, 41) * DEG
    for method in ("lateral_force", "aligning_moment"):
        lo, mi, hi = (getattr(t, method)(slip, 2 * DEG, 600.0) for t in (low, mid, high))
        assert np.all((mi >= np.minimum(lo, hi) - 1e-12) & (mi <= np.maximum(lo, hi) + 1e-12))
    fz = np.array([343.0, 600.0])
    np.testing.assert_allclose(mid.cornering_stiffness(fz),
                               0.5 * (low.cornering_stiffness(fz) + high.cornering_stiffness(fz)))
    quarter = tyres.load("T03", 425)
    assert [w for w, _, _ in quarter.blend] == [0.75, 0.25]
    with pytest.raises(InputError, match="between measured pressures"):
        mid.magic_formula_factors(400.0)


def test_zero_or_negative_load_gives_zero_never_nan():
    tyre = tyres.load("T03", 400)
    fz = np.array([-50.0, 0.0, 1e-9, 500.0])
    force = tyre.lateral_force(0.1, 0.05, fz)
    moment = tyre.aligning_moment(0.1, 0.05, fz)
    assert force[0] == 0.0 and force[1] == 0.0 and moment[0] == 0.0 and moment[1] == 0.0
    assert np.all(np.isfinite(force)) and np.all(np.isfinite(moment))
    assert tyre.cornering_stiffness(0.0) == 0.0


def test_friction_modes():
    plain = tyres.load("T03", 400)
    plate = tyres.load("T03", 400, friction="plate")
    thesis = tyres.load("T03", 400, friction="thesis")
    k = 1.03 / 0.79
    assert plate.friction_scale == pytest.approx(k) and plate.curve_scale == 1.0
    assert thesis.curve_scale == 1.31917 and thesis.friction_scale == 1.0
    fz = np.array([343.0, 635.0])
    # plate: D*k and B/k, so stiffness kept (to O(Sh^2), 0.5 %), peak up by k
    np.testing.assert_allclose(plate.cornering_stiffness(fz), plain.cornering_stiffness(fz), rtol=5e-3)
    fp, f0 = plate.magic_formula_factors(fz), plain.magic_formula_factors(fz)
    np.testing.assert_allclose(fp["D"], k * f0["D"], rtol=1e-12)
    # thesis: the whole curve (and so the stiffness) times 1.31917
    slip = np.linspace(-10, 10, 21) * DEG
    np.testing.assert_allclose(thesis.lateral_force(slip, 0.0, 635.0),
                               1.31917 * plain.lateral_force(slip, 0.0, 635.0), rtol=1e-12)
    np.testing.assert_allclose(thesis.aligning_moment(slip, 0.0, 635.0),
                               1.31917 * plain.aligning_moment(slip, 0.0, 635.0), rtol=1e-12)
    np.testing.assert_allclose(thesis.cornering_stiffness(fz), 1.31917 * plain.cornering_stiffness(fz))


def test_tyres_without_moment_data():
    tyre = tyres.load("T04", 400)
    assert not tyre.has_aligning_moment
    with pytest.raises(InputError, match="T04 has no measured aligning-moment"):
        tyre.aligning_moment(0.1, 0.0, 400.0)
    with pytest.raises(InputError, match="missing_moment='zero'"):
        tyre.blend
    zero = tyres.load("T04", 400, missing_moment="zero")
    assert np.all(zero.aligning_moment(np.linspace(-1, 1, 9), 0.1, 400.0) == 0.0)
    assert zero.lateral_force(0.05, 0.0, 400.0) == tyre.lateral_force(0.05, 0.0, 400.0)


def test_symbolic_expression_matches_numpy():
    import sympy as sm
    tyre = tyres.load("T03", 350, friction="plate")
    s, c, f = sm.symbols("s c f")
    expr = tyre.lateral_force_expression(s, c, f)
    value = float(expr.subs({s: 0.07, c: -0.02, f: 640.0}))
    assert value == pytest.approx(float(tyre.lateral_force(0.07, -0.02, 640.0)), rel=1e-12)


@pytest.mark.parametrize("call, message", [
    (lambda: tyres.load("T09", 400), r"tyre = 'T09' is unknown; choose one of T01, T02"),
    (lambda: tyres.load("T03", 550), r"= 550 kPa is outside the allowed range \[300, 500\] kPa"),
    (lambda: tyres.load("T01", 300), r"= 300 kPa is outside the allowed range \[400, 400\] kPa"),
    (lambda: tyres.load("T03", float("nan")), r"= nan kPa is outside the allowed range"),
    (lambda: tyres.load("T03", 400, coefficient_set="x"), r"coefficient_set = 'x' does not exist"),
    (lambda: tyres.load("T04", 400, coefficient_set="chapter8"), r"does not exist for tyre T04"),
    (lambda: tyres.load("T03", 400, friction="ice"), r"friction = 'ice' is unknown"),
    (lambda: tyres.load("T03", 400).cornering_stiffness(-1.0),
     r"fz = -1.0 N is outside the allowed range \[0, inf\] N"),
    (lambda: tyres.load("T03", 400).magic_formula_factors(0.0),
     r"fz = 0.0 N is outside the allowed range \(0, inf\] N"),
    (lambda: tyres.load("T03", 400).lateral_force(0.1, 0.0, np.inf), r"fz = inf N"),
    (lambda: tyres.load("T03", 400).aligning_moment(np.nan, 0.0, 400.0), r"slip = nan rad"),
])
def test_user_mistakes_are_one_line_input_errors(call, message):
    with pytest.raises(InputError, match=message) as info:
        call()
    assert "\n" not in str(info.value)


# -- malformed files ------------------------------------------------------------

def _write_variant(tmp_path, replace=None, append="", name="T03"):
    """Copy T03.toml into tmp_path as ``name``.toml with one edit."""
    text = (tyres.TYRE_DIR / "T03.toml").read_text()
    if replace is not None:
        old, new = replace
        assert old in text
        text = text.replace(old, new, 1)
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace('name = "T03"', f'name = "{name}"') + append)
    return path


@pytest.mark.parametrize("replace, append, message", [
    (("    1.5625,     # a0", "    # a0 gone"), "", r"coefficients\.table7_9\.300\.fy: must hold 14 coefficients, got 13"),
    (('unit = "N/m", source = "thesis Table 8.5: K_z = 80', 'unit = "N/mm", source = "thesis Table 8.5: K_z = 80'),
     "", r"pressure\.300\.vertical_stiffness: unit must be 'N/m', got 'N/mm'"),
    (("value = 80000.0", "value = nan"), "", r"pressure\.300\.vertical_stiffness\.value: must be finite"),
    (("value = 80000.0", "value = -1.0"), "", r"vertical_stiffness: value -1.0 N/m must be > 0 N/m"),
    (("value = 80000.0", 'value = "stiff"'), "", r"vertical_stiffness\.value: must be a number"),
    (("[pressure.300]", "[pressure.abc]"), "", r"pressure\.abc: 'abc' is not a pressure in kPa"),
    (("[pressure.500]", "[pressure.600]"), "", r"coefficients\.table7_9\.500: no \[pressure\.500\] table"),
    (('angle_unit = "deg"', 'angle_unit = "rad"'), "", r"formula\.angle_unit: must be 'deg'"),
    (("    -729.3696,  # a1", "    inf,  # a1"), "", r"coefficients\.table7_9\.300\.fy\[1\]: must be finite"),
    (('mz_from = "chapter8"', 'mz_from = "nowhere"'), "", r"mz_from: set 'nowhere' has no mz coefficients"),
    (None, "\ncolour = \"red\"\n", r"colour: unknown key"),
    (("name = ", "nom = "), "", r"nom: unknown key"),
    (("[pressure.300]", "[pressure.300"), "", r"is not valid TOML"),
])
def test_malformed_file_names_file_key_and_problem(tmp_path, replace, append, message):
    path = _write_variant(tmp_path, replace, append, name="TX")
    with pytest.raises(InputError, match=message) as info:
        tyres.load("TX", 400, directory=tmp_path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_file_name_must_match_tyre_name(tmp_path):
    path = _write_variant(tmp_path, name="TX")
    shutil.move(path, tmp_path / "TY.toml")
    with pytest.raises(InputError, match=r"name: 'TX' must match the file name 'TY'"):
        tyres.load("TY", 400, directory=tmp_path)


def test_linear_tyre_is_linear_without_camber_force_or_moment():
    """The no-slip check tyre: F_y = -C F_z slip to 1e-6 up to 0.2 rad, nothing from camber."""
    tyre = tyres.linear_tyre(12.0, 0.05, 2e5)
    (_, fy, mz), = tyre.blend
    slip = np.linspace(-0.2, 0.2, 9)
    for fz in (50.0, 600.0, 1500.0):
        force = magic_formula.lateral_force_numpy(slip, 0.0, fz, fy)
        np.testing.assert_allclose(force, -12.0 * fz * slip, rtol=1e-6, atol=1e-9)
        assert np.all(magic_formula.lateral_force_numpy(0.0, np.array([-0.3, 0.3]), fz, fy) == 0.0)
        assert np.all(magic_formula.aligning_moment_numpy(slip, 0.1, fz, mz) == 0.0)
    with pytest.raises(InputError, match="cornering coefficient"):
        tyres.linear_tyre(-1.0, 0.05, 2e5)


def test_a_tyre_without_moment_data_is_told_by_its_flag_not_by_a_message(monkeypatch):
    """assembly.build_tyres decided "no M_z data" by finding "aligning-moment" in an error's text:
    any rewording of that message made T04 runs fail. It now reads Tyre.has_aligning_moment."""
    from whipple_kick.errors import InputError
    from whipple_kick.library import tyres
    from whipple_kick.simulate import assembly
    from whipple_kick.simulate.scenario import Scenario

    def reworded(self, mz):
        if mz is not None:
            return mz
        if self.missing_moment == "zero":
            return tyres.ZERO_MOMENT_COEFFICIENTS
        raise InputError(f"tyre {self.name}: no M_z fit")
    monkeypatch.setattr(tyres.Tyre, "_moment_coefficients", reworded)
    rear, front, notes = assembly.build_tyres(Scenario(tyre="T04").tyre_spec)
    assert not rear.has_aligning_moment and notes == ["T04 has no published aligning-moment data: M_z = 0"]
    assert all((mz == tyres.ZERO_MOMENT_COEFFICIENTS).all() for _, _, mz in rear.blend)
    rear, _, notes = assembly.build_tyres(Scenario(tyre="T03").tyre_spec)
    assert rear.has_aligning_moment and notes == []


def test_a_tyre_file_is_parsed_once_and_an_edited_one_afresh(tmp_path, monkeypatch):
    # A sweep loads the same tyre file for every case: read_tyre_file keeps the parsed file per content.
    path = _write_variant(tmp_path, name="TX")
    calls = []
    parse = tyres.parameters.parse_toml
    monkeypatch.setattr(tyres.parameters, "parse_toml", lambda *a: calls.append(a[0]) or parse(*a))
    first = tyres.load("TX", 400, directory=tmp_path)
    assert tyres.load("TX", 400, directory=tmp_path).lateral_force(0.05, 0.0, 600.0) == \
        first.lateral_force(0.05, 0.0, 600.0)
    assert calls == [path]
    # Same path and size, new content (as fast as a file system's time stamps tick): read afresh.
    path.write_text(path.read_text().replace("    -729.3696,  # a1", "    -729.3697,  # a1", 1))
    edited = tyres.load("TX", 300, directory=tmp_path)
    assert calls == [path, path]
    assert edited.lateral_force(0.05, 0.0, 600.0) != tyres.load("T03", 300).lateral_force(0.05, 0.0, 600.0)
    # The parsed file is shared between loads: its coefficients cannot be changed in place.
    fy = tyres.read_tyre_file(path).sets["table7_9"][300.0][0]
    with pytest.raises(ValueError, match="read-only"):
        fy[1] = 0.0

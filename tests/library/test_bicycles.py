"""Bicycle parameter files: every file loads, converts and round-trips; bad files are InputErrors."""

import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.model.benchmark import BENCHMARK_NAMES, MOORE_NAMES, from_moore, to_moore

SHIPPED = ("balanceassist_v1", "benchmark", "balanceassist_635N", "balanceassist_701N",
           "browser_with_rider")


def test_available_lists_every_shipped_file():
    assert set(SHIPPED) <= set(wk.bicycles.available())


@pytest.mark.parametrize("name", SHIPPED)
def test_every_file_loads_and_round_trips(name):
    bike = wk.bicycles.load(name)
    assert bike.name == name
    assert set(bike) == set(MOORE_NAMES)
    assert set(bike.benchmark) == set(BENCHMARK_NAMES)
    assert dict(bike) == dict(bike.moore)
    # Round trip through the other parameterisation: the conversion is exact
    # geometry, so only floating-point round-off (a few ulps of O(1) values) remains.
    # The converted form the Bicycle carries is exactly what the converters give.
    if bike.parameterisation == "moore":
        assert dict(bike.benchmark) == from_moore(bike.moore)
        given, back = bike.moore, to_moore(bike.benchmark)
    else:
        assert dict(bike.moore) == to_moore(bike.benchmark)
        given, back = bike.benchmark, from_moore(bike.moore)
    for key, value in given.items():
        assert back[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key
    assert "\n" not in bike.name and bike.source


def test_the_geometry_ranges_hold_every_known_bicycle():
    """The plausible ranges of GEOMETRY_RANGES hold the shipped sets and every bicycle BicycleParameters ships
    (the spread they are widened from): none of them is refused."""
    known = [wk.bicycles.load(name) for name in wk.bicycles.available()]
    try:
        from importlib import resources
        root = resources.files("bicycleparameters") / "app-data" / "bicycles"
        folders = sorted(p for p in root.iterdir() if (p / "Parameters").is_dir() and p.name != "Rigid")
    except (ImportError, FileNotFoundError):
        folders = []   # without the test extra: the shipped sets only
    import warnings

    from whipple_kick.library import bicycleparameters as bp
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", wk.errors.DefaultValueWarning)
        known += [bp.load(folder) for folder in folders]   # Rigid has bodies the Whipple model lacks
    assert len(known) >= 5 + 8 * bool(folders)
    for bike in known:
        for key, (low, high) in wk.bicycles.GEOMETRY_RANGES.items():
            assert low <= bike.benchmark[key] <= high, (bike.name, key)


def test_benchmark_file_holds_the_exact_meijaard_values():
    # Bitwise equality with the lead's transcription: both are exact decimal values (lam = pi/10).
    assert dict(wk.bicycles.load("benchmark").benchmark) == wk.benchmark.meijaard2007_parameters()


def test_balanceassist_v1_values_uncertainties_and_geometry():
    bike = wk.bicycles.load("balanceassist_v1")
    assert not bike.includes_rider and bike.parameterisation == "benchmark"
    # 33.1 kg in total (benchmarks.md; the thesis says 33 kg); mass sums are exact decimals to round-off.
    total = sum(bike.benchmark[k] for k in ("mR", "mB", "mH", "mF"))
    assert total == pytest.approx(33.12, abs=1e-12)
    assert bike.benchmark["g"] == 9.80665
    assert bike.uncertainties["w"] == 0.008 and bike.uncertainties["lam"] == 0.026
    assert "g" not in bike.uncertainties          # the source gives none
    assert set(bike.geometry) == set(wk.bicycles.SEATING_UNITS)
    assert bike.geometry["lamst"] == 1.2164944886400477


@pytest.mark.parametrize("name", ["balanceassist_635N", "balanceassist_701N", "browser_with_rider"])
def test_rider_included_sets_keep_their_tyre_placeholders(name):
    bike = wk.bicycles.load(name)
    assert bike.includes_rider and bike.parameterisation == "moore"
    assert bike.tyre_placeholders["c_af"] == 11.46
    assert bike.tyre_placeholders["s_yr"] == 0.175
    assert set(bike.tyre_placeholders).isdisjoint(bike)   # metadata, not model parameters


def test_published_moore_values_are_kept_verbatim():
    bike = wk.bicycles.load("balanceassist_635N")
    assert bike["mc"] == 83.9 and bike["ic31"] == 3.214818 and bike["d3"] == 0.0705000000001252


def test_unknown_name_is_an_input_error():
    with pytest.raises(InputError, match=r"unknown bicycle 'nope'.*balanceassist_v1"):
        wk.bicycles.load("nope")


GOOD = (wk.bicycles.BICYCLE_DIR / "benchmark.toml").read_text()


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('w    = { value = 1.02,', 'w    = { value = "x",'), r"parameters\.w\.value: must be a number"),
    (lambda t: t.replace('unit = "kg",     source = "meijaard2007" }\nIBxx', 'unit = "g",     source = "meijaard2007" }\nIBxx'), "parameters.mB: unit must be 'kg'"),
    (lambda t: t.replace('source = "meijaard2007" }\nIRyy', 'source = "nowhere" }\nIRyy'), "source 'nowhere' is not a key"),
    (lambda t: t.replace('IFyy = { value = 0.28,               unit = "kg m^2", source = "meijaard2007" }\n', ''), "parameters: missing IFyy"),
    (lambda t: t + 'extra = { value = 1.0, unit = "m", source = "meijaard2007" }\n', "parameters: unknown keys extra"),
    (lambda t: t.replace('mF   = { value = 3.0,', 'mF   = { value = -3.0,'), "mF: value -3.0 kg must be > 0 kg"),
    (lambda t: t.replace('IBxz = { value = 2.4,', 'IBxz = { value = 6.0,'), "IBxz: value 6.0 kg m\\^2 makes the B inertia tensor indefinite"),
    (lambda t: t.replace('parameterisation = "benchmark"', 'parameterisation = "other"'), "parameterisation: must be"),
    (lambda t: t.replace('w    = { value = 1.02,', 'w    = { value = nan,'), "must be finite"),
    (lambda t: t.replace('[parameters]', '[parameters'), "not valid TOML"),
    # Issue 40 item 8: a trail of metres, a wheelbase or a wheel in the wrong unit (mm, cm read as m) were accepted.
    (lambda t: t.replace('c    = { value = 0.08,', 'c    = { value = 5.0,'),
     r"c: trail 5\.0 m is outside the plausible range \[-0\.2, 0\.5\] m of a bicycle"),
    (lambda t: t.replace('w    = { value = 1.02,', 'w    = { value = 102.0,'), r"w: wheelbase 102\.0 m .*\[0\.5, 2\.5\] m"),
    (lambda t: t.replace('rR   = { value = 0.3,', 'rR   = { value = 0.03,'), r"rR: rear wheel radius 0\.03 m .*\[0\.1, 0\.6\] m"),
])
def test_malformed_file_is_an_input_error_naming_file_and_key(tmp_path, edit, message):
    """One line, ``<file>: <key>: <problem>`` (the one format of :mod:`whipple_kick.library.parameters`)."""
    path = tmp_path / "broken.toml"
    text = edit(GOOD)
    assert text != GOOD
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        wk.bicycles.load(str(path))
    assert "broken.toml" in str(info.value) and "\n" not in str(info.value)


def test_authors_presets_carry_the_load_they_are_labelled_with():
    """Thesis Table 8.3's rider B and C loads select the Table 8.4 gains of the presets with rider."""
    assert wk.bicycles.load("balanceassist_635N").thesis_rear_load_n == 635.0
    assert wk.bicycles.load("balanceassist_701N").thesis_rear_load_n == 701.0
    assert wk.bicycles.load("browser_with_rider").thesis_rear_load_n is None
    assert wk.bicycles.load("balanceassist_v1").thesis_rear_load_n is None


def test_a_load_label_needs_a_set_with_rider(tmp_path):
    path = tmp_path / "labelled.toml"
    text = GOOD.replace('includes_rider = true', 'includes_rider = false\nthesis_rear_load = { value = 635.0, '
                        'unit = "N", source = "meijaard2007" }')
    assert text != GOOD
    path.write_text(text)
    with pytest.raises(InputError, match="thesis_rear_load: labels a set that includes its rider"):
        wk.bicycles.load(str(path))

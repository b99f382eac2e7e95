"""The parameter files as package data, and the one validator every parameter file goes through."""
import pathlib

import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import parameters

REPOSITORY_PARAMETERS = pathlib.Path(__file__).resolve().parents[2] / "parameters"


@pytest.mark.parametrize("kind", parameters.KINDS)
def test_shipped_files_are_the_repository_parameter_files(kind):
    """importlib.resources finds the files of the top-level parameters/ folder, byte for byte."""
    shipped = parameters.toml_files(parameters.shipped(kind))
    in_repository = parameters.toml_files(REPOSITORY_PARAMETERS / kind)
    assert list(shipped) == list(in_repository) and shipped
    for name, path in shipped.items():
        assert path.read_bytes() == in_repository[name].read_bytes(), name


def test_the_loaders_read_the_shipped_folders():
    assert parameters.shipped("tyres") == wk.tyres.TYRE_DIR
    assert parameters.shipped("bicycles") == wk.bicycles.BICYCLE_DIR
    assert parameters.shipped("riders") == wk.riders.RIDER_DIR
    assert [name for name, _, _ in wk.tyres.available()] == ["T01", "T02", "T03", "T04", "T05"]
    assert "balanceassist_v1" in wk.bicycles.available() and wk.riders.available() == ["jason"]


def test_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="kind must be one of bicycles, experiments, riders, tyres"):
        parameters.shipped("wheels")


GOOD = {"value": 2.5, "unit": "m", "source": "tape"}


@pytest.mark.parametrize("entry, options, message", [
    ({**GOOD, "value": "x"}, {}, r"f\.toml: a\.value: must be a number, got 'x'"),
    ({**GOOD, "value": True}, {}, r"a\.value: must be a number, got True"),
    ({**GOOD, "value": float("inf")}, {}, r"a\.value: must be finite, got inf"),
    ({**GOOD, "unit": "mm"}, {}, r"a: unit must be 'm', got 'mm'"),
    ({"value": 1.0, "unit": "m"}, {}, r"a: missing field 'source'"),
    ({**GOOD, "colour": "red"}, {}, r"a: unknown field\(s\) \['colour'\]; allowed: value, unit, source"),
    ({**GOOD, "uncertainty": 0.1}, {}, r"a: unknown field\(s\) \['uncertainty'\]"),
    ({**GOOD, "uncertainty": -0.1}, {"uncertainty": True}, r"a\.uncertainty: value -0.1 m must be >= 0 m"),
    ({**GOOD, "source": ""}, {}, r"a\.source: must be a non-empty string"),
    (GOOD, {"sources": {"book": "A book"}}, r"a: source 'tape' is not a key of \[sources\] \(book\)"),
    ({**GOOD, "value": 0.0}, {"low": 0.0, "low_open": True}, r"a: value 0.0 m must be > 0 m"),
    ({**GOOD, "value": -1.0}, {"low": 0.0}, r"a: value -1.0 m must be >= 0 m"),
    (3.0, {}, r"a: must be a table, got 3.0"),
])
def test_quantity_rules_are_one_line_errors_naming_file_and_key(entry, options, message):
    with pytest.raises(InputError, match=message) as info:
        parameters.quantity("f.toml", "a", entry, "m", **options)
    assert "\n" not in str(info.value)


def test_quantity_returns_value_and_uncertainty():
    assert parameters.quantity("f.toml", "a", GOOD, "m") == (2.5, None)
    assert parameters.quantity("f.toml", "a", {**GOOD, "source": "book", "uncertainty": 0.5}, "m",
                               sources={"book": "A book"}, uncertainty=True) == (2.5, 0.5)
    values, spreads = parameters.quantities("f.toml", "t", {"a": GOOD, "b": {**GOOD, "unit": "s"}}, None)
    assert values == {"a": 2.5, "b": 2.5} and spreads == {}


def test_quantities_refuses_unknown_and_missing_keys():
    with pytest.raises(InputError, match=r"f\.toml: t: unknown keys c; allowed: a, b"):
        parameters.quantities("f.toml", "t", {"a": GOOD, "c": GOOD}, {"a": "m", "b": "m"})
    with pytest.raises(InputError, match=r"f\.toml: t: missing b"):
        parameters.quantities("f.toml", "t", {"a": GOOD}, {"a": "m", "b": "m"})
    assert parameters.quantities("f.toml", "t", {"a": GOOD}, {"a": "m", "b": "m"}, complete=False)[0] == {"a": 2.5}


def test_tyre_and_bicycle_files_follow_the_same_rules(tmp_path):
    """The same mistake (a wrong unit) gives the same one-line message in a tyre file and a bicycle file."""
    tyre = (wk.tyres.TYRE_DIR / "T03.toml").read_text().replace('name = "T03"', 'name = "TX"')
    tyre = tyre.replace('unit = "N/m", source = "thesis Table 8.5: K_z = 80', 'unit = "N/mm", source = "x', 1)
    (tmp_path / "TX.toml").write_text(tyre)
    bike = (wk.bicycles.BICYCLE_DIR / "benchmark.toml").read_text()
    bike = bike.replace('unit = "kg",     source = "meijaard2007" }\nIBxx', 'unit = "g",     source = "meijaard2007" }\nIBxx')
    (tmp_path / "bike.toml").write_text(bike)
    with pytest.raises(InputError, match=r"TX\.toml: pressure\.300\.vertical_stiffness: unit must be 'N/m', got 'N/mm'"):
        wk.tyres.load("TX", 400, directory=tmp_path)
    with pytest.raises(InputError, match=r"bike\.toml: parameters\.mB: unit must be 'kg', got 'g'"):
        wk.bicycles.load(str(tmp_path / "bike.toml"))


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(InputError, match=r"parameter file .*nothing\.toml does not exist"):
        parameters.load_toml(tmp_path / "nothing.toml")
    (tmp_path / "bad.toml").write_text("[a\n")
    with pytest.raises(InputError, match=r"bad\.toml is not valid TOML"):
        parameters.load_toml(tmp_path / "bad.toml")

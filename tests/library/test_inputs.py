"""The kick plate's motion: built-in profiles and tabulated plate motions (read through pandas)."""
import math
import re

import numpy as np
import pytest

import whipple_kick as wk
from whipple_kick.errors import InputError
from whipple_kick.library import inputs
from whipple_kick.library.inputs import kick_of
from whipple_kick.simulate.scenario import Scenario


def _write_table(path, t, y, header="time,y"):
    lines = ([header] if header else []) + [f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


_BAD_TABLES = {
    "missing-file": (None, ["missing.csv", "does not exist"]),
    "one-row": ("time,y\n0,0\n", ["1 data row", "at least 2"]),
    "no-rows": ("time,y\n", ["0 data rows", "at least 2"]),
    "empty": ("", ["no rows"]),
    "missing-column": ("time,x\n0,0\n1,1\n", ["no column 'y'", "time, x"]),
    "non-numeric": ("time,y\n0,0\n0.1,abc\n", ["line 3", "'abc'", "column y", "not a number"]),
    "non-finite": ("time,y\n0,0\n0.1,inf\n", ["line 3", "y = inf", "not finite"]),
    "non-increasing": ("time,y\n0,0\n0.1,0.1\n0.1,0.2\n", ["line 4", "0.1 s", "increase strictly"]),
    "decreasing": ("time,y\n0,0\n0.1,0.1\n0.05,0.2\n", ["line 4", "0.05 s", "increase strictly"]),
    "ragged": ("time,y\n0,0\n0.1\n", ["line 3", "column y is empty"]),
    "too-many-cells": ("time,y\n0,0,5\n", ["is not a delimited table", "Expected 2 fields in line 2, saw 3"]),
    "not-utf8": (b"time,y\n0,\xff\n", ["is not a UTF-8 text file"]),
    "three-columns-no-header": ("0,0,1\n0.1,0.1,1\n", ["3 columns and no header", "exactly two"]),
    "after-the-run": ("time,y\n0,0\n7,0.1\n", ["[0, 7] s", "[-0.5, 6] s"]),
    "before-the-run": ("time,y\n-1,0\n0.1,0.1\n", ["[-1, 0.1] s", "[-0.5, 6] s"]),
}


def _timing(scenario):
    kick = kick_of(scenario)
    return kick.duration, kick.peak_acceleration, kick.displacement


def test_kick_timing_variants():
    """Duration, peak acceleration and travel of the built-in profiles: 2 D/T^2 and 10/sqrt(3) D/T^2."""
    assert _timing(Scenario()) == pytest.approx((0.15, 13.3333333, 0.15))
    dur, acc, d = _timing(Scenario(kick_accel=35.0))
    assert acc == 35.0 and dur == pytest.approx(math.sqrt(2 * 0.15 / 35.0)) and d == 0.15
    dur, acc, d = _timing(Scenario(kick_accel=35.0, kick_profile="smooth"))
    assert dur == pytest.approx(math.sqrt(10 / math.sqrt(3) * 0.15 / 35.0))
    assert _timing(Scenario(kick_direction="left"))[2] == -0.15
    with pytest.raises(InputError, match="not both"):
        kick_of(Scenario(kick_accel=30.0, kick_duration=0.1))
    # "table" is a profile, but it needs its file.
    with pytest.raises(InputError, match="needs a kick table"):
        kick_of(Scenario(kick_profile="table"))
    with pytest.raises(InputError, match="unknown; choose one of constant, smooth, table"):
        kick_of(Scenario(kick_profile="fast"))
    with pytest.raises(InputError, match=r"kick duration = 7 s is longer than the run duration 6 s"):
        kick_of(Scenario(kick_duration=7.0))


def test_the_model_is_given_the_kick_it_describes():
    """What the compiled model's parameters receive: the profile's code, or a table's plate at rest at its first y."""
    assert kick_of(Scenario(kick_direction="left")).model_kick() == {
        "t0": 0.0, "duration": 0.15, "displacement": -0.15, "profile": inputs.KICK_PROFILES["constant"]}
    summary = kick_of(Scenario(kick_profile="smooth")).summary("right")
    assert summary["profile"] == "smooth" and summary["peak_acceleration_m_s2"] == pytest.approx(10 / math.sqrt(3) / 0.15 * 0.15 / 0.15)
    assert "table" not in summary


def test_header_less_table_is_time_then_y(tmp_path):
    plain = _write_table(tmp_path / "plain.csv", [0.0, 0.05, 0.1], [0.0, 0.03, 0.05], header=None)
    named = _write_table(tmp_path / "named.csv", [0.0, 0.05, 0.1], [0.0, 0.03, 0.05], header="y,time")
    a = kick_of(Scenario(kick_profile="table", kick_table=plain)).table
    np.testing.assert_array_equal(a.times, [0.0, 0.05, 0.1])
    np.testing.assert_array_equal(a.y, [0.0, 0.03, 0.05])
    # With a header the columns are found by name, in any order.
    b = kick_of(Scenario(kick_profile="table", kick_table=named)).table
    np.testing.assert_array_equal(b.times, [0.0, 0.03, 0.05])
    np.testing.assert_array_equal(b.y, [0.0, 0.05, 0.1])


def test_table_read_through_pandas_keeps_file_lines_in_messages(tmp_path):
    """Comments (whole lines and trailing), blank lines, units in the header and extra columns: the rows
    are read by pandas and a bad cell is still named by its line in the file."""
    path = tmp_path / "rig.csv"
    path.write_text("# plate of the test rig\n\nTime [s], y (m), note\n0.0,0.0,a  # start\n\n0.1,0.15,b\n0.2,x,c\n")
    with pytest.raises(InputError, match=r"line 7: 'x' in column y is not a number"):
        inputs.load_kick_table(path)
    path.write_text("# plate of the test rig\n\nTime [s], y (m), note\n0.0,0.0,a  # start\n\n0.1,0.15,b\n")
    times, y = inputs.load_kick_table(path)
    np.testing.assert_array_equal(times, [0.0, 0.1])
    np.testing.assert_array_equal(y, [0.0, 0.15])
    kick = kick_of(Scenario(kick_profile="table", kick_table=str(path), kick_direction="left"))
    assert (kick.start, kick.duration, kick.displacement) == (0.0, pytest.approx(0.1), pytest.approx(-0.15))


@pytest.mark.parametrize("content, fragments", _BAD_TABLES.values(), ids=_BAD_TABLES.keys())
def test_bad_tables_are_one_line_input_errors(content, fragments, tmp_path):
    path = tmp_path / ("missing.csv" if content is None else "kick.csv")
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        path.write_text(content)
    with pytest.raises(InputError) as info:
        wk.assembly.preflight(Scenario(kick_profile="table", kick_table=str(path)))
    message = str(info.value)
    assert "\n" not in message and path.name in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_table_conflicts_with_the_other_kick_fields(tmp_path):
    t = np.linspace(0.0, 0.15, 16)
    path = _write_table(tmp_path / "smooth.csv", t, 0.15 * (t / 0.15) ** 2)
    for changes, fragment in (({"kick_profile": "smooth"}, "needs kick_profile 'table'"),
                              ({"kick_accel": 30.0}, "kick peak acceleration = 30.0 m/s^2 conflicts"),
                              ({"kick_duration": 0.1}, "kick duration = 0.1 s conflicts"),
                              ({"kick_displacement": 0.1}, "kick displacement = 0.1 m conflicts"),
                              ({"piecewise": False}, "piecewise = False")):
        base = {"kick_profile": "table", "kick_table": path, **changes}
        with pytest.raises(InputError, match=re.escape(fragment)):
            Scenario(**base).validate()


def test_cubic_segments_are_the_clamped_spline():
    """Each segment reproduces the table points and the plate starts and stops at rest (y' = 0 at both ends)."""
    t = np.array([0.0, 0.05, 0.1, 0.15])
    y = np.array([0.0, 0.02, 0.09, 0.15])
    segments = inputs.cubic_segments(t, y)
    assert [(a, b) for a, b, _ in segments] == [(0.0, 0.05), (0.05, 0.1), (0.1, 0.15)]
    for (a, b, c), y0, y1 in zip(segments, y[:-1], y[1:], strict=True):
        tau = b - a
        assert c[0] == pytest.approx(y0, abs=1e-15)
        assert c[0] + c[1] * tau + c[2] * tau**2 + c[3] * tau**3 == pytest.approx(y1, abs=1e-15)
    assert segments[0][2][1] == 0.0
    a, b, c = segments[-1]
    assert c[1] + 2 * c[2] * (b - a) + 3 * c[3] * (b - a) ** 2 == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(InputError, match="increase strictly"):
        inputs.cubic_segments([0.0, 0.0], [0.0, 1.0])

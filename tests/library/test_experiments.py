"""The thesis' kick-plate measurements as data: every number against this test's own transcription.

The tables below are typed from the thesis as printed (Dell'Orto 2025,
Tables 8.3, 8.6-8.9 and Sections 8.3-8.6), independently of the TOML file;
the test compares every value of parameters/experiments/kickplate_2025.toml
with them, exactly (both are the printed decimals).
"""
import math

import pytest

from whipple_kick.errors import InputError
from whipple_kick.library import experiments
from whipple_kick.simulate import analysis

# Printed rows, columns 300 / 400 / 500 kPa, then the two % variations of the last column.
TABLE_8_6 = {   # F_z = 570 N; % variation 300 vs 400 (300 vs 500)
    "last_peak_time": (0.41, 0.45, 0.46, -9, -11),
    "log_dec_13": (0.46, 0.32, 0.56, +44, -17),
    "zeta_13": (0.07, 0.05, 0.09, +43, -17),
    "log_dec_24": (3.49, 3.59, 0.83, -3, +73),
    "zeta_24": (0.49, 0.50, 0.30, -2, +59),
    "log_dec_35": (1.16, 1.25, 1.11, -7, +4),
    "zeta_35": (0.18, 0.20, 0.17, -7, +4),
    "period": (0.18, 0.22, 0.19, -18, -6),
}
TABLE_8_7 = {   # F_z = 635 N; % variation 400 vs 300 (400 vs 500)
    "last_peak_time": (0.42, 0.36, 0.43, -14, -16),
    "log_dec_13": (0.66, 0.72, 0.92, +10, -22),
    "zeta_13": (0.10, 0.11, 0.15, +10, -28),
    "log_dec_24": (1.54, 1.41, 2.47, -8, -40),
    "zeta_24": (0.24, 0.22, 0.37, -7, -40),
    "log_dec_35": (0.83, 1.76, 0.54, +112, +215),
    "zeta_35": (0.13, 0.27, 0.09, +106, +214),
    "period": (0.18, 0.19, 0.17, +2, +12),
}
TABLE_8_8 = {   # F_z = 701 N; % variation 500 vs 300 (500 vs 400); no peaks #3-#5 rows
    "last_peak_time": (0.46, 0.46, 0.26, -43, -43),
    "log_dec_13": (0.52, 0.89, 1.18, +128, +32),
    "zeta_13": (0.08, 0.14, 0.18, +125, +31),
    "log_dec_24": (0.38, 0.43, 2.73, +627, +538),
    "zeta_24": (0.06, 0.07, 0.40, +568, +487),
    "period": (0.15, 0.17, 0.20, +28, +18),
}
TABLES = {570.0: (TABLE_8_6, 300.0, (400.0, 500.0), (6, 6, 6)),
          635.0: (TABLE_8_7, 400.0, (300.0, 500.0), (6, 6, 6)),
          701.0: (TABLE_8_8, 500.0, (300.0, 400.0), (6, 6, 4))}
# Table 8.9: printed load, best pressure, % recovery time reduction.
TABLE_8_9 = {570.0: (520.0, 300.0, -10.0), 635.0: (635.0, 400.0, -15.0), 701.0: (701.0, 500.0, -43.0)}
# Table 8.3: mass [kg], F_z front [N], F_z rear [N].
TABLE_8_3 = {"A": (52.0, 265.0, 570.0), "B": (61.0, 287.0, 635.0), "C": (70.0, 309.0, 701.0)}
# Sections 8.3, 8.5: conditions and processing.
CONDITIONS = {"speed_min": 1.92, "speed_max": 2.0, "plate_displacement": 0.150, "plate_acceleration_min": 30.0,
              "plate_acceleration_max": 35.0, "plate_acceleration_peak_max": 40.0, "cylinder_force": 1600.0,
              "cylinder_force_uncertainty": 50.0, "kick_duration": 0.15, "wheel_on_plate_min": 0.20,
              "wheel_on_plate_max": 0.22, "plate_length": 0.5, "cylinder_force_max": 2000.0,
              "rider_reaction_delay": 0.04, "tests_per_pressure": 12.0}
PROCESSING = {"imu_rate": 100.0, "lowpass_cutoff": 20.0, "trials_averaged": 3.0, "peak_threshold": 0.08,
              "spectrum_max": 25.0, "yaw_band_low": 5.0, "yaw_band_high": 6.0, "record_length": 1.0,
              "peak_window": 0.5}
PRESSURES = (300.0, 400.0, 500.0)


@pytest.fixture(scope="module")
def exp():
    return experiments.load()


def test_every_printed_table_value_is_in_the_file(exp):
    assert exp.loads == [570.0, 635.0, 701.0] and exp.pressures == list(PRESSURES)
    assert len(exp.cases) == 9
    for fz, (table, reference, others, last_numbers) in TABLES.items():
        for k, p in enumerate(PRESSURES):
            case = exp.case(fz, p)
            assert case.case == f"{fz:g}N_{p:g}kPa"
            assert case.last_peak_number == last_numbers[k]
            assert case.values == {metric: row[k] for metric, row in table.items()}
            assert all("thesis Table 8." in case.sources[m] for m in case.values)
        var = exp.variations[fz]
        assert var["reference_kpa"] == reference
        expected = {f"{metric}_vs_{other:g}kPa": row[3 + j]
                    for metric, row in table.items() for j, other in enumerate(others)}
        assert {k: v for k, v in var.items() if k != "reference_kpa"} == expected


def test_table_8_9_riders_conditions_and_processing(exp):
    for fz, (printed, best, reduction) in TABLE_8_9.items():
        assert exp.best[fz]["printed_load"] == printed
        assert exp.best[fz]["fz_n"] == fz
        assert exp.best[fz]["best_pressure"] == best
        assert exp.best[fz]["recovery_time_reduction"] == reduction
    for key, (mass, front, rear) in TABLE_8_3.items():
        assert (exp.riders[key]["mass"], exp.riders[key]["fz_front"], exp.riders[key]["fz_rear"]) == (mass, front, rear)
        assert exp.riders[key]["rear_share"] == 0.75          # "25 / 75", an estimate (Table 8.3)
    assert exp.conditions == CONDITIONS                      # nothing more, nothing less
    assert exp.processing == PROCESSING
    assert exp.spectrum_peak_hz == {570.0: 5.0, 635.0: 6.0, 701.0: 5.0}


def test_table_8_9_follows_from_the_last_peak_times(exp):
    """Table 8.9's best pressures are the shortest last-peak times; its % is the mean of the other two.

    Tolerance 0.5 %: the table prints whole per cents.
    """
    assert experiments.best_pressures(exp) == {fz: row[1] for fz, row in TABLE_8_9.items()}
    for fz, (_, _, reduction) in TABLE_8_9.items():
        assert experiments.mean_reduction(exp, fz) == pytest.approx(reduction, abs=0.5)


def test_the_printed_inconsistencies_are_found_and_noted(exp):
    """eq. 8.3 applied to every printed δ, and every printed % recomputed, within the printing's rounding."""
    found = experiments.inconsistencies(exp)
    assert [(f.get("case") or f["load"], f["metric"], f["printed"]) for f in found] == [
        ("570N_500kPa", "zeta_24", 0.30),
        (570.0, "log_dec_24_vs_500kPa", 73),
        (635.0, "log_dec_24_vs_500kPa", -40),
        (635.0, "log_dec_35_vs_500kPa", 215),
    ]
    # An independent recomputation of the first: eq. 8.3 of 0.83 is 0.131, far from the printed 0.30.
    assert analysis.damping_ratio(0.83) == pytest.approx(0.83 / math.sqrt(4 * math.pi ** 2 + 0.83 ** 2))
    assert analysis.damping_ratio(0.83) == pytest.approx(0.131, abs=5e-4)
    # Every computed inconsistency is also written down in the file's [[notes]], with its printed value.
    noted = " ".join(n["where"] + " " + n["printed"] for n in exp.notes)
    for printed in ("0.30", "+73%", "-40%", "+215%", "520 N"):
        assert printed in noted


def test_a_consistent_table_has_no_inconsistency(exp):
    """The check is not trigger-happy: eq. 8.3's own output and exact ratios pass."""
    import dataclasses
    cases = {}
    for name, case in exp.cases.items():
        values = dict(case.values)
        for zeta, delta in experiments.ZETA_OF.items():
            if zeta in values:
                values[zeta] = round(analysis.damping_ratio(values[delta]), 2)
        cases[name] = dataclasses.replace(case, values=values)
    variations = {}
    for fz, table in exp.variations.items():
        ref = table["reference_kpa"]
        variations[fz] = {"reference_kpa": ref}
        for key in table:
            if key != "reference_kpa":
                metric, other = key.rsplit("_vs_", 1)
                a = cases[experiments.case_name(fz, ref)].values[metric]
                b = cases[experiments.case_name(fz, float(other[:-3]))].values[metric]
                variations[fz][key] = round(100 * (a / b - 1))
    clean = dataclasses.replace(exp, cases=cases, variations=variations)
    assert experiments.inconsistencies(clean) == []


def test_the_printed_times_run_from_peak_one(exp):
    """Evenly spaced peaks put peak #1 at -0.115 to +0.085 s on the tables' clock.

    With the kick at 0, peak #1 could not come before the first response
    (0.04 s, Section 8.5.1); six of the nine cases put it before the kick.
    """
    t1 = experiments.implied_first_peak_times(exp)
    assert t1["570N_300kPa"] == pytest.approx(0.41 - 5 * 0.18 / 2)
    assert t1["701N_500kPa"] == pytest.approx(0.26 - 3 * 0.20 / 2)
    assert min(t1.values()) == pytest.approx(-0.115) and max(t1.values()) == pytest.approx(0.085)
    assert sum(v < experiments.FIRST_RESPONSE_S for v in t1.values()) == 8
    assert sum(v < 0 for v in t1.values()) == 6


def test_file_errors_are_one_line(tmp_path, exp):
    text = exp.path.read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('last_peak_time = { value = 0.41, unit = "s"', 'last_peak_time = { value = 0.41, unit = "ms"', 1))
    with pytest.raises(InputError, match=r"measured\.570N_300kPa\.last_peak_time: unit must be 's'") as info:
        experiments.load(str(bad))
    assert "\n" not in str(info.value)
    bad.write_text(text.replace('[measured."570N_300kPa"]', '[measured."571N_300kPa"]'))
    with pytest.raises(InputError, match="name must be '570N_300kPa'"):
        experiments.load(str(bad))
    bad.write_text(text.replace('format = "whipple_kick experiment, version 1"', 'format = "x"'))
    with pytest.raises(InputError, match="format"):
        experiments.load(str(bad))
    with pytest.raises(InputError, match="unknown; choose one of kickplate_2025"):
        experiments.load("nope")
    with pytest.raises(InputError, match="no measured case at 600 N"):
        exp.case(600.0, 400.0)
    assert experiments.available() == ["kickplate_2025"]

"""An uncertainty study's P(best) as the page shows it: the study's rows at the load, none interpolated."""
import math
import pathlib

import pandas as pd
import pytest

from whipple_kick.errors import InputError
from whipple_kick.explorer import study

STUDY = pathlib.Path(__file__).resolve().parents[2] / "docs" / "uncertainty_study"


def test_the_rows_at_a_computed_load_are_the_files():
    rows = study.p_best(STUDY, 635.0)
    table = pd.read_csv(STUDY / study.P_BEST_FILE)
    for criterion, shown in rows.items():
        at = table[(table["fz_n"] == 635.0) & (table["criterion"] == criterion)]
        assert [r["p"] for r in shown] == list(at["p"])
        assert [r["pressure"] for r in shown] == [
            "none recovers" if math.isnan(p) else f"{p:g} kPa" for p in at["pressure_kpa"]]
        assert [r["measured_best"] for r in shown] == list(at["measured_best"])
        assert sum(r["p"] for r in shown) == pytest.approx(1.0, abs=1e-12)   # the pressures and "none" share all rows
    assert list(rows) == ["settling", "last_peak"]


def test_a_load_the_study_did_not_compute_has_no_rows():
    assert study.p_best(STUDY, 650.0) is None
    assert study.loads(STUDY) == [570.0, 635.0, 701.0]


def test_a_folder_without_the_table_is_one_line(tmp_path):
    with pytest.raises(InputError, match=r"has no p_best\.csv"):
        study.check_folder(tmp_path)
    (tmp_path / study.P_BEST_FILE).write_text("fz_n,p\n635,0.5\n")
    with pytest.raises(InputError, match="lacks the column"):
        study.check_folder(tmp_path)

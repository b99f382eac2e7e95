"""The study scripts' own output (scripts/ is not a package: imported by path)."""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "scripts"))

import thesis_figures


def _summary(time_s, fell=False):
    return {"fell": fell, "fall_time_s": 1.25 if fell else None, "fall_reason": "roll" if fell else None,
            "recovery": {"time_s": time_s}}


def test_thesis_figures_says_when_a_run_did_not_recover():
    """A run that never settled reads "not recovered within the run" (before: "recovery ... None s")."""
    line = thesis_figures.run_line(_summary(None, fell=True))
    assert line == "fell at 1.250 s (roll); recovery (yaw, roll, steer rates within 5 %) not recovered within the run"
    assert "None" not in thesis_figures.run_line(_summary(None))
    assert thesis_figures.run_line(_summary(2.5)).endswith("within 5 %) 2.500 s")

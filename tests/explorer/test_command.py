"""The console script's refusals, and a plain run that loads nothing of the explorer nor of its web library."""
import subprocess
import sys

from tests.conftest import run_console
from whipple_kick.explorer import server


def test_a_plain_run_imports_nothing_of_the_explorer():
    code = ("import sys, whipple_kick as wk; wk.run(wk.Scenario(duration=0.2, output_rate=100.0)); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('tornado', 'selenium') "
            "or m.startswith('whipple_kick.explorer')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.strip() == "[]"


def test_bad_options_are_one_line_and_status_2(capsys, tmp_path):
    for argv, words in ((["--study", str(tmp_path)], "has no p_best.csv"),
                        (["--port", "70000"], "outside the allowed range [0, 65535]"),
                        (["--workers", "0"], "must be a whole number >= 1"),
                        (["--speeds", "3:1:1"], "STOP 1 m/s is below START 3 m/s")):
        status, out, err = run_console(server.main, argv, capsys)
        assert status == 2 and out == "" and err.count("\n") == 1 and words in err, (argv, err)

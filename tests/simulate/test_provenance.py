"""Provenance: every summary.json and sweep manifest says which code, where, when and from which input files."""
import datetime
import hashlib
import pathlib
import subprocess
import sys

import pytest

import whipple_kick as wk
from whipple_kick.simulate import provenance

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_summary_carries_the_provenance(base):
    """Issue 25 acceptance: package and dependency versions, Python, platform, date, host, the git commit of this
    checkout, and the SHA-256 of each input file (here the shipped bicycle, rider and tyre files)."""
    rec = base.summary["provenance"]
    assert rec["versions"]["whipple_kick"] == wk.__version__
    for name in ("numpy", "scipy", "pandas", "matplotlib", "python", "platform"):
        assert rec["versions"][name]
    age = datetime.datetime.now(datetime.timezone.utc) - datetime.datetime.fromisoformat(rec["date_utc"])
    assert datetime.timedelta(0) <= age < datetime.timedelta(hours=2)
    assert rec["host"]
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
    assert rec["git"]["commit"] == head.stdout.strip() and isinstance(rec["git"]["dirty"], bool)
    assert set(rec["input_files"]) == {"bicycle", "rider", "tyre"}
    for entry in rec["input_files"].values():
        assert entry["sha256"] == hashlib.sha256(pathlib.Path(entry["path"]).read_bytes()).hexdigest()
    assert pathlib.Path(rec["input_files"]["tyre"]["path"]).name == "T03.toml"


def test_kick_table_is_recorded_by_absolute_path_and_hash(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    pathlib.Path("plate.csv").write_text("time,y\n0,0\n0.15,0.15\n")
    files = provenance.input_files(wk.Scenario(kick_profile="table", kick_table="plate.csv"))
    assert files["kick_table"] == {"path": str(tmp_path / "plate.csv"),
                                   "sha256": hashlib.sha256(b"time,y\n0,0\n0.15,0.15\n").hexdigest()}
    assert "tyre" not in provenance.input_files(wk.Scenario(), custom_tyres=True)


def test_a_resolved_path_is_kept_while_the_file_it_names_is_the_same(tmp_path, monkeypatch):
    """Kept per process (a sweep's every case records the same files), yet a link pointed at another file, or a
    relative name in another folder, resolves afresh: the file it names has another stat."""
    from whipple_kick import fileio
    monkeypatch.setattr(fileio, "SETTLED_S", -1.0)   # every file counts as settled: the kept answer is used
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "plate.csv").write_text(f"time,y\n0,0\n0.15,0.15 # {folder}\n")
    link = tmp_path / "link.csv"
    link.symlink_to(tmp_path / "a" / "plate.csv")
    assert provenance.resolved(link) == provenance.resolved(link) == str(tmp_path / "a" / "plate.csv")
    link.unlink()
    link.symlink_to(tmp_path / "b" / "plate.csv")
    assert provenance.resolved(link) == str(tmp_path / "b" / "plate.csv")
    for folder in ("a", "b"):
        monkeypatch.chdir(tmp_path / folder)
        assert provenance.resolved(pathlib.Path("plate.csv")) == str(tmp_path / folder / "plate.csv")


def test_no_git_commit_outside_a_checkout(tmp_path):
    assert provenance.git_state(tmp_path) is None


def test_sweep_manifest_carries_the_provenance(default_run):
    import json

    folder, _ = default_run
    rec = json.loads((folder / "manifest.json").read_text())["provenance"]
    assert rec["versions"]["whipple_kick"] == wk.__version__ and rec["git"]["commit"]
    assert "tyre" in rec["input_files"] and rec["date_utc"]


@pytest.mark.parametrize("script", ["simulate", "stability", "recommend-pressure", "compare", "whipple-benchmark"])
def test_every_command_has_version(script):
    done = subprocess.run([str(pathlib.Path(sys.executable).parent / script), "--version"], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0 and done.stdout == f"{script} (whipple_kick {wk.__version__})\n", done.stderr


def test_citation_file_names_the_version_and_the_thesis():
    """CITATION.cff (read as text: no YAML parser is a dependency) carries the package version and the thesis."""
    text = (REPO / "CITATION.cff").read_text()
    assert f"version: {wk.__version__}\n" in text and "cff-version: 1.2.0" in text
    assert "Bicycle tyre lateral characteristics and their effect on bicycle dynamics" in text


def test_git_is_asked_once_per_process(monkeypatch):
    # A sweep runs thousands of cases in a process; the code it runs is the code it imported.
    calls = []
    monkeypatch.setattr(provenance, "git_state", lambda: calls.append(1) or {"commit": "c" * 40, "dirty": False})
    provenance._own_git_state.cache_clear()
    try:
        first = provenance.record()
        first["git"]["dirty"] = True      # each record has its own copy
        assert provenance.record()["git"] == {"commit": "c" * 40, "dirty": False}
        assert len(calls) == 1
    finally:
        provenance._own_git_state.cache_clear()   # the next record asks the real git again

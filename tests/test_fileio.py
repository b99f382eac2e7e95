"""File I/O: atomic writes, CSV written as pandas writes it (exact floats), CSV read through pandas."""
import io
import os

import numpy as np
import pandas as pd
import pytest

from whipple_kick import fileio
from whipple_kick.errors import InputError


def _bits(frame):
    return frame.to_numpy(dtype=np.float64).view(np.int64)


def _awkward_frame():
    rng = np.random.default_rng(0)
    raw = rng.integers(0, 2**63 - 1, size=2000, dtype=np.int64).view(np.float64)
    raw = raw[np.isfinite(raw)]
    special = np.array([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
                        -1.7976931348623157e308, 0.1 + 0.2, np.nextafter(1.0, 2.0), 1e16, 123456789012345678.0,
                        1 / 3, -2.5, 1.0])
    n = len(special)
    return raw, pd.DataFrame({
        "time": np.arange(n) * 1e-3,
        "random": raw[:n],
        "special": special,
        "zeros": np.zeros(n),                                  # must stay a float column
        "negative zeros": np.full(n, -0.0),
        "whole": np.arange(n, dtype=float),
    })


def test_csv_is_pandas_own_text_and_reads_back_bit_for_bit(tmp_path):
    """write_csv writes exactly DataFrame.to_csv(index=False)'s bytes, and read_csv returns every bit."""
    raw, frame = _awkward_frame()
    path = tmp_path / "t.csv"
    fileio.write_csv(frame, path)
    reference = io.StringIO()
    frame.to_csv(reference, index=False, lineterminator="\n")
    assert path.read_text() == reference.getvalue()
    back = pd.read_csv(path)
    assert list(back.columns) == list(frame.columns) and (back.dtypes == np.float64).all()
    assert np.array_equal(_bits(back), _bits(frame))
    # Longer than one write chunk (2000 rows), every random bit pattern; one column alone.
    pairs = raw[: len(raw) // 2 * 2].reshape(-1, 2)
    many = pd.concat([pd.DataFrame({"a": pairs[:, 0], "b": pairs[:, 1]})] * 3, ignore_index=True)
    assert len(many) > 2000
    fileio.write_csv(many, path)
    assert np.array_equal(_bits(pd.read_csv(path)), _bits(many))
    assert path.read_text() == many.to_csv(index=False, lineterminator="\n")
    fileio.write_csv(many[["a"]], path)
    assert path.read_text() == many[["a"]].to_csv(index=False, lineterminator="\n")


def test_csv_of_other_tables_goes_through_to_csv(tmp_path):
    frame = pd.DataFrame({"time": [0.0, 0.1], "x": [np.nan, 1.5], "n": [1, 2], "mode": ["weave", "capsize"]})
    path = tmp_path / "t.csv"
    fileio.write_csv(frame, path)
    assert path.read_text() == frame.to_csv(index=False, lineterminator="\n")
    empty = pd.DataFrame({"a": np.zeros(0)})
    fileio.write_csv(empty, path)
    assert path.read_text() == "a\n"


def test_atomic_write_leaves_the_old_file_when_the_writer_fails(tmp_path):
    path = tmp_path / "summary.json"
    fileio.write_atomic(path, "old\n")
    with pytest.raises(RuntimeError), fileio.atomic_path(path) as tmp:
        tmp.write_text("half of the new")
        raise RuntimeError("interrupted")
    assert path.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]   # no temporary left


def test_atomic_write_private_and_bytes(tmp_path):
    path = tmp_path / "entry.bin"
    fileio.write_atomic(path, b"\x00\x01", private=True)
    assert path.read_bytes() == b"\x00\x01" and path.stat().st_mode & 0o777 == 0o600
    assert fileio.temporary_name(path).name == f".entry.bin.{os.getpid()}.tmp"


@pytest.mark.parametrize("content, message", [
    (None, r"kick table '.*missing\.csv' does not exist"),
    (b"\xff\xfe\x00 not utf-8", r"is not a UTF-8 text file"),
    (b"", r"has no rows"),
    (b'a,b\n1,2\n3,"4\n', r"is not a delimited table"),
])
def test_read_csv_problems_are_one_line_input_errors(tmp_path, content, message):
    path = tmp_path / "missing.csv"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(InputError, match=message) as info:
        fileio.read_csv(path, "kick table")
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match="is not a file"):
        fileio.read_csv(tmp_path, "kick table")


def test_read_csv_reads_through_pandas(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("\ufefftime,y\n# a comment\n0.0,1.5\n0.1,2.5\n")
    frame = fileio.read_csv(path, "table", comment="#")
    assert list(frame.columns) == ["time", "y"] and frame["y"].tolist() == [1.5, 2.5]


def test_csv_to_significant_digits_is_to_csv_float_format_and_round_trips(tmp_path):
    """With significant_digits=13 (trajectory.csv) the text is to_csv's with float_format="%.13g", and
    pandas.read_csv returns every value within the stated relative bound 0.5 * 10**(1 - 13) = 5e-13 (plus
    the parser's last-bit rounding, 2 ulp)."""
    raw, frame = _awkward_frame()
    pairs = raw[: len(raw) // 2 * 2].reshape(-1, 2)
    many = pd.concat([frame[["random", "special"]].set_axis(["a", "b"], axis=1),
                      pd.DataFrame({"a": pairs[:, 0], "b": pairs[:, 1]})] * 3, ignore_index=True)
    assert len(many) > 2000   # more than one formatting chunk
    path = tmp_path / "t.csv"
    fileio.write_csv(many, path, significant_digits=13)
    assert path.read_text() == many.to_csv(index=False, lineterminator="\n", float_format="%.13g")
    back = pd.read_csv(path).to_numpy()
    exact = many.to_numpy()
    error = np.abs(back - exact)
    bound = (5e-13 + 4 * np.finfo(float).eps) * np.abs(exact)
    assert (error <= bound).all()
    # The bound is met, not loose: the worst value uses a good part of it (1e-13 of 5e-13 at least).
    assert np.max(error / np.abs(np.where(exact == 0, 1.0, exact))) > 1e-13
    # Not every bit: this is a rounding, so a repr-exact write differs from it.
    fileio.write_csv(many, path)
    assert np.array_equal(pd.read_csv(path).to_numpy(), exact)


def test_docstring_examples_leave_no_temporary_folder(tmp_path, monkeypatch):
    """Issue 31 item 20: three examples (fileio.atomic_path, provenance.sha256, Scenario.to_file) made a
    ``tempfile.mkdtemp()`` folder per test run and never removed it. Run with the temporary folder redirected,
    they leave it empty; and no example in the package calls mkdtemp again."""
    import doctest
    import pathlib
    import tempfile

    import whipple_kick
    from whipple_kick import fileio
    from whipple_kick.simulate import provenance, scenario
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.chdir(tmp_path)
    for module in (fileio, provenance, scenario):
        result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
        assert result.failed == 0 and result.attempted > 0, module.__name__
    assert list((tmp_path / "tmp").iterdir()) == []
    package = pathlib.Path(whipple_kick.__file__).parent
    # Examples only (doctest lines): the explorer's server makes its own working folder and removes it at exit.
    examples = [p.name for p in package.rglob("*.py")
                if any(">>>" in line and "mkdtemp(" in line for line in p.read_text().splitlines())]
    assert examples == []


class _Later:
    """A stand-in for fileio's ``time`` module an hour ahead: every file counts as settled (cached by its stat)."""

    @staticmethod
    def time_ns():
        import time
        return time.time_ns() + 3600 * 10**9


def _restamp_later(path, old):
    """Let the file system's clock move past ``old``'s stamps (a coarse tick is at most ~10 ms), so that a write
    that follows changes the ctime, as any write at least a tick later does."""
    import time
    while time.time_ns() <= max(old.st_mtime_ns, old.st_ctime_ns) + 20_000_000:
        time.sleep(0.005)


def test_settled_key_refuses_a_recent_change(tmp_path):
    """A file changed within SETTLED_S has no key (a change within the same timestamp tick could keep its stat);
    one changed earlier has its stat as key, and a missing file none."""
    path = tmp_path / "a.toml"
    path.write_text("x = 1\n")
    assert fileio.settled_key(path) is None
    assert fileio.settled_key(tmp_path / "missing.toml") is None


def test_file_hash_cache_sees_an_edit_of_the_same_size(tmp_path, monkeypatch):
    """The provenance hash of a parameter file is read once per process while the file is unchanged, and read
    again after an edit between two runs, also one of the same size with the mtime set back (the ctime moves)."""
    from whipple_kick.simulate import provenance
    monkeypatch.setattr(fileio, "time", _Later)
    path = tmp_path / "tyre.toml"
    path.write_bytes(b"a = 1\n")
    first = provenance.sha256(path)
    assert provenance._HASHES[str(path)][1] == first   # cached
    assert provenance.sha256(path) == first
    old = os.stat(path)
    _restamp_later(path, old)
    path.write_bytes(b"a = 2\n")
    os.utime(path, ns=(old.st_atime_ns, old.st_mtime_ns))   # the mtime back; the size the same
    second = provenance.sha256(path)
    assert second != first
    assert second == provenance.hashlib.sha256(b"a = 2\n").hexdigest()


def test_folder_listing_cache_sees_a_new_file(tmp_path, monkeypatch):
    """The parameter files of a folder are listed once per process while it is unchanged; a file added, or
    removed, between two runs is seen (the folder's stat moves)."""
    from whipple_kick.library import parameters
    monkeypatch.setattr(fileio, "time", _Later)
    (tmp_path / "T01.toml").write_text("x = 1\n")
    assert list(parameters.toml_files(tmp_path)) == ["T01"]
    assert str(tmp_path) in parameters._LISTINGS   # cached
    listing = parameters.toml_files(tmp_path)
    listing["other"] = None   # a caller's copy: the cache is not changed through it
    assert list(parameters.toml_files(tmp_path)) == ["T01"]
    _restamp_later(tmp_path, os.stat(tmp_path))
    (tmp_path / "T02.toml").write_text("x = 2\n")
    assert list(parameters.toml_files(tmp_path)) == ["T01", "T02"]
    _restamp_later(tmp_path, os.stat(tmp_path))
    (tmp_path / "T01.toml").unlink()
    assert list(parameters.toml_files(tmp_path)) == ["T02"]

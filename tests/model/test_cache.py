"""Generated-code cache: private, keyed by content, safe under concurrent builds."""
import os
import subprocess
import sys

import pytest

from whipple_kick.errors import CacheError, InputError
from whipple_kick.model import cache, compiler
from whipple_kick.model.slip import compiled


def test_cache_folder_is_private(tmp_path, monkeypatch):
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(tmp_path / "c"))
    folder = cache.cache_dir()
    assert folder.stat().st_mode & 0o777 == 0o700


def test_cache_folder_writable_by_others_is_refused(tmp_path, monkeypatch):
    folder = tmp_path / "shared"
    folder.mkdir()
    folder.chmod(0o777)
    monkeypatch.setenv("WHIPPLE_KICK_CACHE", str(folder))
    with pytest.raises(CacheError, match="not private"):
        cache.cache_dir()


def test_cached_file_writable_by_others_is_not_loaded(tmp_path):
    path = tmp_path / "x.py"
    path.write_text("")
    path.chmod(0o666)
    with pytest.raises(CacheError, match="writable by others"):
        cache.check_private_file(path)


def test_hash_changes_with_source_and_options():
    """The key names the SymPy version the code is generated with, read without importing SymPy."""
    import importlib.metadata
    assert cache.sympy_version() == importlib.metadata.version("sympy")
    a = cache.source_hash(["symbolic/derivation"], extra="x")
    assert a == cache.source_hash(["symbolic/derivation"], extra="x")
    assert a != cache.source_hash(["symbolic/derivation"], extra="y")
    assert a != cache.source_hash(["symbolic/derivation", "slip/layout"], extra="x")


def test_missing_compiler_is_a_clear_error(monkeypatch):
    """No compiler is the machine's set-up, not an input error: its own class (a BuildError), one line that says
    to install one."""
    from whipple_kick.errors import BuildError, CompilerNotFoundError
    monkeypatch.setenv("CC", "no-such-compiler-xyz")
    with pytest.raises(CompilerNotFoundError, match=r"CC=.no-such-compiler-xyz.*install a C compiler") as info:
        compiler.find()
    assert not isinstance(info.value, InputError) and isinstance(info.value, BuildError)
    monkeypatch.delenv("CC")
    monkeypatch.setenv("PATH", "")
    with pytest.raises(CompilerNotFoundError, match=r"no C compiler found.*install a C compiler") as info:
        compiler.find()
    assert "\n" not in str(info.value)


def test_concurrent_builds_share_one_library(tmp_path):
    """Two processes building into the same empty cache both succeed; one library results.

    Each process builds through the whole path (the lock, the build line, the compiler, the metadata)
    but takes the generated C from the warm cache instead of repeating the SymPy derivation (25 s of
    the 33 s this test took): what is under test is the concurrency, not the derivation, which every
    cold cache and tests/model/test_slip_build.py exercise.
    """
    env = dict(os.environ, WHIPPLE_KICK_CACHE=str(tmp_path / "cache"))
    warm_c = compiled.library_path().with_suffix(".c")
    code = ("from whipple_kick.model.symbolic import slip_build\n"
            f"slip_build.c_source = lambda *model: open({str(warm_c)!r}).read()\n"
            "from whipple_kick import slip, lsoda\n"
            "lib = slip.library(); print('ok')\n")
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    # The builder warns (a PerformanceWarning, not a print) what it does and how long it takes; the process that
    # waits says nothing.
    said = [line for _, err in outs for line in err.splitlines() if "Warning:" in line]
    assert len(said) == 1 and "PerformanceWarning: building the slip model" in said[0], outs
    assert "20-60 s" in said[0]
    libraries = sorted(f.name for f in (tmp_path / "cache").iterdir() if f.suffix == ".so")
    assert len(libraries) == 1, libraries
    leftovers = [f.name for f in (tmp_path / "cache").iterdir() if f.name.endswith(".tmp")]
    assert not leftovers


def test_every_generator_is_part_of_its_own_cache_key():
    """A module that writes generated code is hashed into that code's key: editing what it writes
    rebuilds the entry (classic.py was not in its own key, so a change to _generate_source reused the
    stale module unless someone remembered to bump a layout string)."""
    from whipple_kick.model import classic, geometry
    slip_modules = tuple(f"slip/{p.stem}" for p in (cache._PACKAGE_DIR / "slip").glob("*.py"))
    # (the layout module read by its full name: the package also exports names from its modules)
    from whipple_kick.model.slip.layout import _SOURCES as SLIP_SOURCES
    for sources, name in ((classic._SOURCES, "classic"), (geometry._SOURCES, "geometry"),
                          (SLIP_SOURCES, "symbolic/slip_build"), *((SLIP_SOURCES, m) for m in slip_modules)):
        assert name in sources, name

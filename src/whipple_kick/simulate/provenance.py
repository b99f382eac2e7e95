"""Where a result came from: package and dependency versions, Python, platform, date, host, git commit, input files.

:func:`record` is the ``provenance`` section of every run's summary.json
and of every sweep folder's manifest.json: enough to say which code, on
which machine, from which input files (by SHA-256: a kick table or a
bicycle file edited after the run no longer matches) made a result. The git
commit is recorded when the package runs from a git checkout (two ``git``
calls of about 10 ms together, once per process: the code a process runs is
the code it imported; None outside a checkout, without git, or if it
fails).

Example
-------
>>> rec = record()
>>> sorted(rec)[:4], rec["versions"]["whipple_kick"] == __import__("whipple_kick").__version__
(['date_utc', 'git', 'host', 'input_files'], True)
"""
import datetime
import functools
import hashlib
from importlib import metadata
import pathlib
import platform
import socket
import subprocess

from whipple_kick import fileio
from whipple_kick.library import bicycles, parameters, riders, tyres

from .scenario import _is_path

#: Distributions whose versions are recorded (the package and what its results depend on).
DEPENDENCIES = ("whipple_kick", "numpy", "scipy", "pandas", "sympy", "control", "matplotlib", "yeadon")
#: The package's source folder (a git checkout's ``src/whipple_kick`` in a development install).
PACKAGE_DIR = pathlib.Path(__file__).resolve().parent
#: Seconds the git query may take before it is given up (then the commit is None).
GIT_TIMEOUT_S = 2.0


@functools.cache
def versions() -> dict:
    """Python, platform and the :data:`DEPENDENCIES`' installed versions (None for one not installed).

    Read once per process (about 20 ms: the installed distributions are searched).

    Example
    -------
    >>> versions()["python"] == platform.python_version()
    True
    """
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for name in DEPENDENCIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def git_state(folder=PACKAGE_DIR):
    """``{"commit": sha, "dirty": bool}`` of the git checkout the package runs from, or None outside one.

    Only a checkout of this package counts (its top level holds
    ``src/whipple_kick``), not some other repository that happens to contain
    an installed copy. ``dirty`` is true when tracked files differ from the
    commit (the result may not be reproducible from the commit alone).

    Example
    -------
    >>> state = git_state()
    >>> state is None or len(state["commit"]) == 40
    True
    """
    def git(*args):
        done = subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True,
                              timeout=GIT_TIMEOUT_S, check=False)
        return done.stdout.strip() if done.returncode == 0 else None

    try:
        found = git("rev-parse", "--show-toplevel", "HEAD")
        if found is None or len(found.splitlines()) != 2:
            return None
        top, commit = found.splitlines()
        if not (pathlib.Path(top) / "src" / "whipple_kick").is_dir():
            return None
        status = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):   # no git, or it hangs
        return None
    return {"commit": commit, "dirty": None if status is None else bool(status)}


@functools.cache
def _own_git_state():
    """:func:`git_state` of the package's checkout, asked once per process (about 10 ms; a sweep runs thousands of cases).

    A process runs the code it imported, so the first answer describes it
    (a commit or edit made later does not change the running code).
    """
    return git_state()


def sha256(path) -> str:
    """SHA-256 of a file's bytes, as hex.

    Example
    -------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:   # removed afterwards
    ...     path = pathlib.Path(folder) / "empty.csv"
    ...     _ = path.write_bytes(b"")
    ...     sha256(path)[:16]
    'e3b0c44298fc1c14'
    """
    # Read once per process while the file stays as it was (its settled stat: any write changes it): a
    # sweep's every case records the hashes of the same few parameter files.
    return fileio.read_once(_HASHES, path, _file_digest)


def _file_digest(path):
    """SHA-256 hex digest of the file at ``path``, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


#: :func:`sha256`'s digests: path -> (the file's settled key, hex digest).
_HASHES = {}


#: The package's folders whose Python makes a run's result (the equations, the parameter sets and their readers,
#: one run from scenario to summary); a sweep's records are those summaries, flattened (simulate/results.py).
RESULT_CODE = ("model", "library", "simulate")


def _read_source(path) -> bytes:
    """The bytes of one file :func:`code_hash` covers (a seam for tests that change the code)."""
    return pathlib.Path(path).read_bytes()


def result_sources() -> list:
    """The files :func:`code_hash` covers: the ``*.py`` of :data:`RESULT_CODE` and the shipped parameter files."""
    files = [p for folder in RESULT_CODE for p in (PACKAGE_DIR.parent / folder).rglob("*.py")]
    files += [p for kind in ("bicycles", "riders", "tyres", "experiments")
              for p in parameters.shipped(kind).rglob("*.toml")]
    return sorted(files)


@functools.cache
def code_hash() -> str:
    """SHA-256 (20 hex digits) of the code and data that make a run's result: :func:`result_sources`.

    Two processes with the same hash compute the same result from the same
    scenario (with the same dependencies and compiled model: the sweep
    folder also records ``model_hash``). Read once per process (about 60
    files, about 50 ms): a process runs the code it imported.

    Example
    -------
    >>> len(code_hash()), code_hash() == code_hash()
    (20, True)
    """
    digest = hashlib.sha256()
    top = PACKAGE_DIR.parent.parent
    for path in result_sources():
        name = path.relative_to(top) if path.is_relative_to(top) else path.name
        digest.update(f"{name}\n".encode())
        digest.update(hashlib.sha256(_read_source(path)).digest())
    return digest.hexdigest()[:20]


def input_files(scenario, custom_tyres=False) -> dict:
    """The files a scenario's run reads: role -> ``{"path": absolute path, "sha256": hex}``.

    The bicycle file (shipped or the user's), the Yeadon rider file the
    scenario names (seated on a bicycle without rider), the tyre file (not
    for custom tyre objects) and the kick table. A file that does not exist is left out (the run itself
    reports it).
    """
    candidates = {
        "bicycle": (pathlib.Path(scenario.bicycle) if _is_path("bicycle", scenario.bicycle)
                    else parameters.toml_files(bicycles.BICYCLE_DIR).get(scenario.bicycle)),
        "rider": parameters.toml_files(riders.RIDER_DIR).get(scenario.rider),
        "tyre": None if custom_tyres else parameters.toml_files(tyres.TYRE_DIR).get(scenario.tyre),
        "kick_table": None if scenario.kick_table is None else pathlib.Path(scenario.kick_table),
    }
    return {role: {"path": resolved(path), "sha256": sha256(path)}
            for role, path in candidates.items() if path is not None and path.is_file()}


def resolved(path) -> str:
    """The absolute path of ``path`` with its symbolic links resolved (:meth:`pathlib.Path.resolve`), as a string.

    Resolved once per process while the file it names stays as it was (its settled stat: a link pointed at
    another file names another inode): a sweep's every case records the same few parameter files.
    """
    return fileio.read_once(_RESOLVED, path, lambda p: str(pathlib.Path(p).resolve()))


#: :func:`resolved`'s paths: path -> (the file's settled key, the resolved path).
_RESOLVED = {}


def record(files=None) -> dict:
    """The provenance section: versions, date (UTC, ISO 8601), host, git state, and the input ``files``.

    Parameters
    ----------
    files : dict, optional
        :func:`input_files` of the run (default none).
    """
    git = _own_git_state()
    return {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "host": socket.gethostname(),
        "versions": dict(versions()),
        "git": None if git is None else dict(git),
        "input_files": files or {},
    }

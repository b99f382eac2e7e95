"""Per-user cache of generated code, keyed by a hash of what it was generated from.

Generated code is a build artefact. It lives in ``$WHIPPLE_KICK_CACHE`` or
``$XDG_CACHE_HOME/whipple_kick`` (default ``~/.cache/whipple_kick``), in a
folder created with private permissions (0700) and refused if another user
can write to it. Several processes may build the same entry at once: a file
lock serialises the builders and each entry is written to a temporary name
and renamed into place, so a reader never sees a half-written file. A cache
folder that cannot be created, written or trusted is a one-line
:class:`~whipple_kick.errors.CacheError` naming the folder, what is wrong and
how to fix it.

Nothing here imports SymPy: the cache key names the SymPy version the entry
was generated with through :mod:`importlib.metadata`, so a warm run finds
its entries without loading the derivation's libraries.
"""
import contextlib
import errno
import fcntl
import functools
import hashlib
import importlib.metadata
import importlib.util
import os
import pathlib
import platform
import stat
import sys

from whipple_kick import fileio
from whipple_kick.errors import CacheError

_PACKAGE_DIR = pathlib.Path(__file__).resolve().parent


def cache_dir():
    """Return the private cache folder, creating it if needed.

    Raises
    ------
    CacheError
        The folder cannot be created, is not owned by this user or is
        writable by others.
    """
    root = os.environ.get("WHIPPLE_KICK_CACHE")
    if root:
        path = pathlib.Path(root)
    else:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        path = pathlib.Path(base) / "whipple_kick"
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        info = path.stat()
    except OSError as exc:
        raise CacheError(f"cache folder {path} cannot be created: {exc.strerror or exc}; "
                         f"{_FIX}") from None
    if info.st_uid != os.getuid() or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        # Another user could plant code there that this process would load and run.
        raise CacheError(
            f"cache folder {path} is not private to this user (owner uid {info.st_uid}, "
            f"mode {oct(info.st_mode & 0o777)}): others could change the code it holds; "
            f"chmod 700 it, remove it, or {_FIX}"
        )
    return path


#: How to fix an unusable cache folder, the end of every CacheError message.
_FIX = "set WHIPPLE_KICK_CACHE to a private writable folder (e.g. export WHIPPLE_KICK_CACHE=$HOME/.whipple_kick_cache)"
#: Errors of writing a cache entry that are the folder's, not the build's.
_FOLDER_ERRORS = (errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOSPC, errno.EDQUOT)


def source_hash(module_names, extra=""):
    """Hash of the package's source files that a build depends on.

    Parameters
    ----------
    module_names : iterable of str
        Module file stems in the package (e.g. ``"derivation"``).
    extra : str
        Anything else the build depends on (options, compiler flags).
    """
    digest = hashlib.sha256()
    for name in sorted(module_names):
        digest.update(name.encode())
        digest.update((_PACKAGE_DIR / f"{name}.py").read_bytes())
    digest.update(f"sympy {sympy_version()}; python {sys.version_info[:2]}; "
                  f"{platform.machine()}; {extra}".encode())
    return digest.hexdigest()[:20]


@functools.cache
def sympy_version():
    """Version of the installed SymPy, read from its metadata (SymPy itself is not imported)."""
    try:
        return importlib.metadata.version("sympy")
    except importlib.metadata.PackageNotFoundError:   # pragma: no cover - sympy is a dependency
        return "not installed"


@contextlib.contextmanager
def locked(path):
    """Hold an exclusive lock on ``path.lock`` while building ``path``."""
    lock_path = pathlib.Path(str(path) + ".lock")
    fd = os.open(lock_path, os.O_CREAT | os.O_RDWR, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


def check_private_file(path):
    """Refuse to load a cached file another user could have written."""
    info = pathlib.Path(path).stat()
    if info.st_uid != os.getuid() or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise CacheError(f"cached file {path} is writable by others; refusing to load it; remove it, "
                         f"or {_FIX}")


def _manifest_path(path):
    return pathlib.Path(str(path) + ".sha256")


def _fingerprint(path):
    """``"<size> <sha256>"`` of a file's bytes."""
    data = pathlib.Path(path).read_bytes()
    return f"{len(data)} {hashlib.sha256(data).hexdigest()}"


def intact(path):
    """Whether the cache entry at ``path`` exists and matches its manifest (size and SHA-256).

    The manifest is written after the entry, atomically, so an entry
    without one was never finished; one that no longer matches was cut
    short or changed on disk (a truncated shared library would crash the
    process with SIGBUS when loaded, so it is checked before loading).
    """
    try:
        check_private_file(_manifest_path(path))
        return _manifest_path(path).read_text().strip() == _fingerprint(path)
    except OSError:
        return False


def build_once(name, build):
    """Path of the cache entry ``name``, building it with ``build(path)`` if absent or damaged.

    ``build`` must write the complete entry to the path it is given (a
    temporary name in the cache folder); it is renamed into place
    atomically and its size and SHA-256 recorded in ``<name>.sha256``
    (:func:`intact`). An entry that does not match its manifest is built
    again. Concurrent builders of the same entry wait on a lock, and the
    second finds the entry already built.
    """
    path = cache_dir() / name
    if not intact(path):
        try:
            with locked(path):
                if not intact(path):
                    _manifest_path(path).unlink(missing_ok=True)
                    with fileio.atomic_path(path, private=True) as tmp:
                        build(tmp)
                    fileio.write_atomic(_manifest_path(path), _fingerprint(path) + "\n", private=True)
        except OSError as exc:   # a CacheError (errno None) is re-raised below as it is
            if exc.errno not in _FOLDER_ERRORS:
                raise
            raise CacheError(f"cache folder {path.parent} cannot be written ({exc.strerror or exc}) to build "
                             f"{name}; make it writable, or {_FIX}") from None
    check_private_file(path)
    return path


def load_module(path, module_name):
    """Import a generated Python module (a cache entry) from ``path``."""
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    spec.loader.exec_module(module)
    return module

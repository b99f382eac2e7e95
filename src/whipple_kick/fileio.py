"""File input and output, one way each: atomic writes, folder locks, and CSV through pandas.

Every file the package writes (cache entries, sweep folders, the results of
``simulate`` and ``stability``) is written to a temporary name in the same
folder and renamed into place (:func:`write_atomic`, :func:`atomic_path`),
so a reader never sees half a file, whatever interrupts the writer. Tables
are CSV as pandas writes and reads them: :func:`write_csv` writes exactly
the text of ``DataFrame.to_csv(index=False)`` (faster for the all-float
trajectory), :func:`read_csv` reads with ``pandas.read_csv`` and turns a
file that cannot be read into a one-line :class:`~whipple_kick.errors.InputError`.
A folder a command writes into is held by one process at a time
(:func:`take_lock`).

The locks are ``fcntl.flock`` (POSIX), as is the rest of the package (the
compiled model is a shared library built by the C compiler and loaded with
ctypes). The ``filelock`` package was not used: it truncates the lock file
on every attempt to take it, which would erase the holder's pid that the
refusal message names.
"""
from collections.abc import Iterator
import contextlib
import fcntl
import os
import pathlib
import time

import numpy as np
import pandas as pd

from .errors import InputError

#: A file or folder changed less than this long ago [s] has no :func:`settled_key`: a change within the file
#: system's timestamp granularity (a clock tick, some milliseconds) could leave its stat as it was ("racy" stat).
SETTLED_S = 2.0


def settled_key(path) -> tuple | None:
    """What a per-process cache of a file's (or folder's) contents may key on: its stat, or None.

    ``(device, inode, size, mtime_ns, ctime_ns)``: any write changes the ctime, which no program can set back (the
    mtime it can). None where the path cannot be stat'ed, or changed within :data:`SETTLED_S` of now (or in the
    future): then a later change could keep the same stamps, so the caller reads afresh.
    """
    try:
        st = os.stat(path)
    except OSError:
        return None
    age_ns = time.time_ns() - max(st.st_mtime_ns, st.st_ctime_ns)
    if not age_ns >= SETTLED_S * 1e9:   # recent, or stamped in the future
        return None
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)


def read_once(store, path, compute):
    """``compute(path)``, kept in ``store`` (a dict: path -> (key, value)) while ``path``'s :func:`settled_key`
    stays the same; computed afresh, and not kept, where there is no settled key."""
    key = settled_key(path)
    cached = store.get(str(path))
    if key is not None and cached is not None and cached[0] == key:
        return cached[1]
    value = compute(path)
    if key is not None:
        store[str(path)] = (key, value)
    return value


def temporary_name(path) -> pathlib.Path:
    """A hidden temporary name next to ``path``, unique to this process: ``.<name>.<pid>.tmp``."""
    path = pathlib.Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


@contextlib.contextmanager
def atomic_path(path, *, private: bool = False) -> Iterator[pathlib.Path]:
    """Yield a temporary path to write ``path``'s contents to; rename it into place on success.

    The temporary file is removed if the block raises (the target is left
    as it was). ``private`` makes the file readable and writable by its
    owner only (0600), before it appears under its name.

    Example
    -------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as name:   # removed afterwards, as every example's files
    ...     folder = pathlib.Path(name)
    ...     with atomic_path(folder / "table.txt") as tmp:
    ...         _ = tmp.write_text("a,b\\n")
    ...     (folder / "table.txt").read_text()
    'a,b\\n'
    """
    path = pathlib.Path(path)
    tmp = temporary_name(path)
    try:
        yield tmp
        if private:
            os.chmod(tmp, 0o600)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def stale_temporaries(folder, names) -> list[pathlib.Path]:
    """Hidden temporaries (:func:`temporary_name`) of the files ``names`` in ``folder``, of any process.

    Whoever holds the folder's lock (:func:`take_lock`) knows them to be
    left by a writer that was killed (SIGKILL, power loss) before it could
    remove them.
    """
    folder = pathlib.Path(folder)
    return [p for name in names for p in folder.glob(f".{name}.*.tmp") if p.name[len(name) + 2:-4].isdigit()]


def take_lock(path, busy: str) -> int:
    """Take an exclusive lock (``flock``) on the file ``path`` and write our pid into it.

    The operating system drops the lock when its holder dies, so a lock
    left by a killed process is simply taken over. Returns the open file
    descriptor (:func:`release_lock` releases it).

    Parameters
    ----------
    path : path-like
        The lock file (created if absent).
    busy : str
        The refusal message; ``{pid}`` is replaced by the holder's pid.

    Raises
    ------
    InputError
        Another process holds the lock (``busy``).
    """
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise InputError(busy.replace("{pid}", holder)) from None
        # A holder that removes the file on release (release_lock with a path) may have
        # removed the one we opened just before we locked it: then take the new one.
        with contextlib.suppress(FileNotFoundError):
            if os.stat(path).st_ino == os.fstat(fd).st_ino:
                break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    return fd


def release_lock(fd: int, path=None) -> None:
    """Release a lock of :func:`take_lock` and close its descriptor; with ``path``, remove the lock file first."""
    if path is not None:
        # Removed while still held, so nobody takes the lock on a file about to vanish.
        with contextlib.suppress(OSError):
            os.unlink(path)
    # LOCK_UN releases the lock even where forked processes (pool workers) still hold the descriptor.
    with contextlib.suppress(OSError):
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


def write_atomic(path, data: str | bytes, *, private: bool = False) -> None:
    """Write text or bytes to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path, private=private) as tmp:
        if isinstance(data, bytes):
            tmp.write_bytes(data)
        else:
            tmp.write_text(data)


def csv_text_rows(values: np.ndarray, significant_digits: int | None = None) -> Iterator[str]:
    """Lines of CSV text for a 2-D float array.

    Each float is its ``repr`` (pandas' own float text, every bit kept), or
    with ``significant_digits`` the ``%.{n}g`` text (``to_csv``'s
    ``float_format``), about 2.5 times faster to write for 13 digits.
    """
    if significant_digits is not None:
        line = ",".join([f"%.{significant_digits}g"] * values.shape[1]) + "\n"
        for start in range(0, len(values), 2000):   # bounded memory for long runs
            yield "".join([line % tuple(row) for row in values[start:start + 2000].tolist()])
        return
    for start in range(0, len(values), 2000):
        # str() of a list of floats writes each float's repr in C, about as fast as
        # formatting can be in Python; finite floats' reprs hold no '[', ',' or ' '.
        text = str(values[start:start + 2000].tolist())
        yield text[2:-2].replace("], [", "\n").replace(", ", ",") + "\n"


def write_csv(frame, path, *, significant_digits: int | None = None) -> None:
    """Write a DataFrame as CSV without its index, atomically: the text of ``frame.to_csv(index=False)``.

    An all-finite float64 frame (a trajectory) is formatted by
    :func:`csv_text_rows`, about twice as fast as ``to_csv`` and the same
    bytes (``tests/test_fileio.py``); every float is its ``repr``, so
    ``pandas.read_csv`` gives back the identical table. Anything else goes
    through ``to_csv`` itself. With ``significant_digits`` the floats are
    written to that many significant digits (the text of ``to_csv`` with
    ``float_format="%.{n}g"``): a relative round-off of at most
    0.5 * 10**(1 - n) per value, for tables whose values are not exact to the
    last bit anyway (an integrated trajectory).

    Parameters
    ----------
    frame : pandas.DataFrame
    path : path-like
    significant_digits : int, optional
        Significant digits of every float; None: all (each float's repr).
    """
    values = frame.to_numpy()
    fast = all(str(t) == "float64" for t in frame.dtypes) and bool(np.isfinite(values).all())
    with atomic_path(path) as tmp:
        if not fast:
            float_format = None if significant_digits is None else f"%.{significant_digits}g"
            frame.to_csv(tmp, index=False, lineterminator="\n", float_format=float_format)
            return
        with open(tmp, "w", newline="") as fh:
            fh.write(frame.iloc[:0].to_csv(index=False, lineterminator="\n"))   # pandas' own header
            fh.writelines(csv_text_rows(values, significant_digits))


def read_csv(path, what: str, *, name: str | None = None, **options):
    """Read a CSV file with ``pandas.read_csv``; a file that cannot be read is a one-line InputError.

    Parameters
    ----------
    path : path-like
    what : str
        What the file is, for the message (e.g. ``"kick table"``).
    name : str, optional
        How the message names the file (default ``path`` as given).
    **options
        Passed to ``pandas.read_csv`` (e.g. ``comment="#"``, ``header=None``).

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    InputError
        The file does not exist, is not a file, is not UTF-8 text, is empty
        or is not a delimited table.
    """
    p = pathlib.Path(path)
    label = f"{what} {str(path) if name is None else name!r}"
    if not p.is_file():
        raise InputError(f"{label} {'is not a file' if p.exists() else 'does not exist'}")
    try:
        return pd.read_csv(p, encoding="utf-8-sig", **options)
    except UnicodeDecodeError:
        raise InputError(f"{label} is not a UTF-8 text file") from None
    except pd.errors.EmptyDataError:
        raise InputError(f"{label} has no rows") from None
    except pd.errors.ParserError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{label} is not a delimited table: {first}") from None
    except OSError as exc:
        raise InputError(f"{label} cannot be read: {exc.strerror or exc}") from None

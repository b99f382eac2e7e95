"""The C compiler: which one to use, and the one call that turns a C file into a shared library.

Both compiled artefacts go through here: the slip model
(:func:`whipple_kick.model.symbolic.slip_build.build_library`) and the
integrator's call extension (:func:`whipple_kick.model.rhs_call.module`).
Each keeps its own flags and cache key; what they share is how the compiler
is found (``$CC``, else ``cc``, ``gcc`` or ``clang`` on PATH) and how a
failure is reported (one line naming the compiler, the full output saved).
"""
import os
import shutil
import subprocess

from whipple_kick import fileio
from whipple_kick.errors import BuildError, CompilerNotFoundError

#: Flags of the slip model's library. -O3 (measured by ``scripts/bench_sweep.py flags``): 0.83x the
#: integration's instructions of -O2 and 0.94x its wall time, trajectories bit-identical (-std=c99, not gnu99,
#: keeps GCC from contracting a*b+c into an FMA). -march=native (0.75x with AVX2, -O3 -march=x86-64-v3; 0.86x
#: wall) is not used: the code would be CPU-specific (the CPU in the cache key, SIGILL on another CPU sharing
#: the cache, a compiler that may refuse it) and valgrind cannot run its AVX-512, which the instruction counts
#: rely on. -fno-math-errno: the math functions need not set errno, so GCC may treat them as pure (keep a result,
#: inline sqrt); values are unchanged (rows, trajectories and summaries of 14 scenarios bit-identical), and a
#: thesis case's integration took 288.3 M instructions instead of 291.1 M, its outputs 41.2 M instead of 42.8 M.
MODEL_FLAGS = ("-O3", "-fno-math-errno", "-fPIC", "-shared", "-std=c99")
#: Flags of the call extension (:mod:`whipple_kick.model.rhs_call`, which adds its include folders): a few
#: lines of glue, left at -O2.
EXTENSION_FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99")


def find():
    """Path of the C compiler: $CC if set (must exist), else cc, gcc or clang on PATH.

    Raises
    ------
    CompilerNotFoundError
        None found (one line: install one or set CC).
    """
    requested = os.environ.get("CC")
    if requested:
        cc = shutil.which(requested)
        if not cc:
            raise CompilerNotFoundError(f"CC={requested!r} is not an executable C compiler: install a C compiler "
                                        "(e.g. gcc) or set CC to one")
        return cc
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        raise CompilerNotFoundError("no C compiler found (looked for cc, gcc, clang on PATH): install a C compiler "
                                    "(e.g. gcc) or set CC to one")
    return cc


def compile_shared(compiler, flags, source, output, libraries=(), log=None):
    """Compile the C file ``source`` into the shared library ``output``.

    Parameters
    ----------
    compiler : str
        Path of the C compiler (:func:`find`).
    flags : sequence of str
        Compiler flags (before ``-o``).
    source, output : pathlib.Path
        The C file and the library to write.
    libraries : sequence of str
        Linker arguments after the source (e.g. ``("-lm",)``).
    log : pathlib.Path, optional
        Where to save the compiler's full output on a failure (private file).

    Raises
    ------
    BuildError
        The compiler failed: one line naming it, its exit status and last line of output, and the log.
    """
    proc = subprocess.run([compiler, *flags, "-o", str(output), str(source), *libraries],
                          capture_output=True, text=True, check=False)
    if proc.returncode == 0:
        return
    last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
    where = ""
    if log is not None:
        fileio.write_atomic(log, proc.stdout + proc.stderr, private=True)
        where = f"; its output is in {log}"
    raise BuildError(f"the C compiler {compiler} failed (exit status {proc.returncode}: {last[:200]}){where}; "
                     "install a working gcc or set CC")

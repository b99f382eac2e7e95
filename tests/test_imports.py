"""The package's import structure: imports at the top of each module, no circles.

The rule (the package's docstring, ``whipple_kick/__init__.py``): an import inside a function is kept only
where it keeps a slow or optional package out of a run that does not use it; everything else is imported
at the top of its module, and the modules' top-level imports form no circle. These tests read the source
(Python's ``ast``), so they fail on a new function-level import or a new circle without running anything.
"""
import ast
import pathlib

import pytest

import whipple_kick

PACKAGE = pathlib.Path(whipple_kick.__file__).parent

#: Packages a function may import (each keeps out of a warm run what the run does not use): SymPy (the
#: model's build on a cache miss), python-control (the control-analysis API), matplotlib and Pillow (the
#: figures), imageio-ffmpeg (mp4 animations, optional), Tornado and Selenium (the explorer, optional), Dask
#: (a sweep on a cluster, optional), SALib, scikit-learn and emcee (the uncertainty study and the
#: calibration), SciPy's signal package (about 0.9 s of import; the measurements' spectra and filters), and
#: the package's own modules that import SymPy at their top (the symbolic derivation and code generation).
LAZY = ("sympy", "control", "matplotlib", "PIL", "imageio_ffmpeg", "tornado", "selenium", "dask", "distributed",
        "SALib", "sklearn", "emcee", "scipy.signal", "whipple_kick.model.symbolic")
#: The command-line module imports a command's own studies and figures when that command runs, so that a
#: ``simulate`` does not load the sweeps, the calibration or the figures it does not draw.
CLI_LAZY = ("whipple_kick.studies", "whipple_kick.figures", "whipple_kick.library.priors",
            "whipple_kick.library.uncertain")
#: Yeadon, imported where a rider is built from its measurements (library/riders.py, bicycleparameters.py).
YEADON = ("yeadon",)


def _modules():
    """Every module of the package: dotted name -> (path, whether it is a package's __init__)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


MODULES = _modules()


def _targets(module, is_package, node):
    """The dotted names an import statement loads (a package's submodule where ``from p import m`` names one)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = node.module or ""
    if node.level:
        package = module if is_package else module.rsplit(".", 1)[0]
        parts = package.split(".")[:len(package.split(".")) - node.level + 1]
        base = ".".join([*parts, base] if base else parts)
    return [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base for a in node.names]


def _imports(path):
    """(import node, whether it is inside a function) for every import statement of the module at ``path``."""
    found = []

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                found.append((child, in_function))
            else:
                visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))
    visit(ast.parse(path.read_text()), False)
    return found


def _within(name, prefixes):
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_a_function_imports_only_what_keeps_a_slow_or_optional_package_out():
    """Every function-level import loads one of :data:`LAZY` (or, in cli.py, one of :data:`CLI_LAZY`; where a
    rider is built, Yeadon); anything else belongs at the top of its module."""
    misplaced = []
    for module, (path, is_package) in MODULES.items():
        allowed = LAZY + (CLI_LAZY if module == "whipple_kick.cli" else ()) + (
            YEADON if module in ("whipple_kick.library.riders", "whipple_kick.library.bicycleparameters") else ())
        for node, in_function in _imports(path):
            if in_function and not all(_within(t, allowed) for t in _targets(module, is_package, node)):
                misplaced.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {ast.unparse(node)}")
    assert not misplaced, "imports to move to the module's top:\n" + "\n".join(misplaced)


def _graph():
    """Module -> the package's modules its top-level imports load (their parent packages included, not its own)."""
    graph = {m: set() for m in MODULES}
    for module, (path, is_package) in MODULES.items():
        own = {".".join(module.split(".")[:i]) for i in range(1, module.count(".") + 1)}
        for node, in_function in _imports(path):
            if in_function:
                continue
            for target in _targets(module, is_package, node):
                parts = target.split(".")
                graph[module] |= {".".join(parts[:i]) for i in range(1, len(parts) + 1)} & set(MODULES) - own - {module}
    return graph


def test_the_top_level_imports_form_no_circle():
    """Depth-first search for a back edge: a module that imports, through others, itself."""
    graph, state, path = _graph(), {}, []

    def visit(module):
        state[module] = "open"
        path.append(module)
        for target in sorted(graph[module]):
            if state.get(target) == "open":
                pytest.fail("import circle: " + " -> ".join([*path[path.index(target):], target]))
            if target not in state:
                visit(target)
        path.pop()
        state[module] = "done"

    for module in sorted(graph):
        if module not in state:
            visit(module)


def test_the_checks_see_a_circle_and_a_lazy_import(tmp_path, monkeypatch):
    """The two checks above fail where they should: on a module pair that imports each other at the top, and
    on a function that imports a light module."""
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("from pkg import b\n")
    (package / "b.py").write_text("import json\n\nfrom pkg import a\n\n\ndef f():\n    import math\n")
    monkeypatch.setitem(globals(), "PACKAGE", package)
    monkeypatch.setitem(globals(), "MODULES", _modules())
    assert set(MODULES) == {"pkg", "pkg.a", "pkg.b"} and _graph()["pkg.a"] == {"pkg.b"}
    with pytest.raises(pytest.fail.Exception, match=r"import circle: pkg.a -> pkg.b -> pkg.a"):
        test_the_top_level_imports_form_no_circle()
    with pytest.raises(AssertionError, match=r"pkg/b.py:7: import math"):
        test_a_function_imports_only_what_keeps_a_slow_or_optional_package_out()

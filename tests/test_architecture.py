"""The package's shape, read from its source: wings that import only downwards, and no import circles.

The wings, lowest first: ``model`` < ``library`` < ``simulate`` < ``figures`` < ``studies`` < ``cli`` < ``explorer``
(the web app at the top: it may import every wing, and none imports it);
``errors`` and ``fileio`` lie beneath them all, and the package's ``__init__`` (a lazy facade, importing
nothing at import time) above. Every import counts, also one inside a function: a lazy import still ties
the two modules together.
"""
import ast
import pathlib

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / "src" / "whipple_kick"
RANK = {"errors": 0, "fileio": 0, "model": 1, "library": 2, "simulate": 3, "figures": 4, "studies": 5, "cli": 6, "explorer": 7}


def _modules():
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts = parts[:-1]
        out[".".join(["whipple_kick", *parts])] = (path, is_package)
    return out


def import_graph():
    """``{module: set of package modules it imports}``, from the source text (nothing is imported)."""
    modules = _modules()
    graph = {}
    for name, (path, is_package) in modules.items():
        edges = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                # ``from package import module`` depends on the module; the package only when a name is taken
                # from the package itself.
                submodules = [f"{target}.{alias.name}" for alias in node.names if f"{target}.{alias.name}" in modules]
                targets = submodules + ([target] if len(submodules) < len(node.names) else [])
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                continue
            edges.update(t for t in targets if t in modules and t != name and t != "whipple_kick")
        graph[name] = edges
    return graph


def wing(module):
    """The wing a module belongs to (its first name under the package), or None for the package itself."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_every_module_has_a_wing():
    stray = [m for m in import_graph() if wing(m) is not None and wing(m) not in RANK and wing(m) != "parameter_files"]
    assert not stray, stray


def test_lower_wings_never_import_higher_ones():
    upward = [(m, t) for m, targets in import_graph().items() for t in targets
              if wing(m) in RANK and wing(t) in RANK and RANK[wing(t)] > RANK[wing(m)]]
    assert not upward, upward


def _cycles(graph):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circles():
    # A package's __init__ that gathers its modules' names would close a circle with each module that
    # imports a sibling through the package; the graph keeps those edges, so such a circle fails too.
    assert _cycles(import_graph()) == []


def test_the_circle_finder_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_public_names_work_from_the_package_top():
    import whipple_kick as wk

    for name in ("run", "Scenario", "Result", "sweep", "InputError", "SimulationError"):
        assert getattr(wk, name) is not None
    for name in ("stability", "tyres", "plotting", "experiments", "validation", "riders", "bicycles", "results"):
        assert getattr(wk, name).__name__.startswith("whipple_kick.")
    import whipple_kick.simulate.simulation  # a wing's import must not replace wk.run
    assert callable(wk.run)

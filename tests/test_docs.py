"""The documentation site's sources (docs/): navigation and the gallery's figure scraper.

The site itself is built by .ci/run (``python -m sphinx -W``); these checks say sooner, and
in the tests' words, what would break that build.
"""
import pathlib
import re
import sys

import pytest

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"


def _toctree_entries():
    text = (DOCS / "index.rst").read_text(encoding="utf-8")
    entries = set()
    for block in re.findall(r"\.\. toctree::\n((?:[ \t]+.*\n|\n)+)", text):
        entries |= {line.strip() for line in block.splitlines() if line.strip() and not line.strip().startswith(":")}
    return entries


def test_every_markdown_page_is_in_the_site_navigation():
    """A page in docs/ that no toctree lists is a warning, so an error, in the -W build: list it in index.rst."""
    pages = {p.stem for p in DOCS.glob("*.md")}
    missing = sorted(pages - _toctree_entries())
    assert pages and not missing, f"docs/index.rst lists no toctree entry for {missing}"


def test_every_toctree_entry_is_a_page():
    entries = _toctree_entries()
    generated = {"auto_examples/index"}   # sphinx-gallery writes it at build time
    absent = sorted(e for e in entries - generated
                    if not (DOCS / f"{e}.md").exists() and not (DOCS / f"{e}.rst").exists())
    assert not absent


def test_gallery_scraper_shows_each_bare_figure_once_and_leaves_pyplot_figures():
    """whipple_kick's plots are bare Figures (no pyplot), which sphinx-gallery's own scraper cannot see."""
    pytest.importorskip("sphinx_gallery")   # the docs extra
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    import matplotlib.pyplot as plt

    sys.path.insert(0, str(DOCS))
    try:
        import gallery_figures
    finally:
        sys.path.remove(str(DOCS))

    bare = Figure()
    FigureCanvasAgg(bare)
    bare.add_subplot().plot([0, 1])
    managed = plt.figure()
    written = []

    def paths():
        while True:
            written.append(str(DOCS.parent / "build" / f"never_{len(written)}.png"))
            yield written[-1]

    def scrape(example_globals):
        saved = []
        block_vars = {"src_file": "example.py", "example_globals": example_globals, "image_path_iterator": paths()}
        original = Figure.savefig
        Figure.savefig = lambda fig, path, **kw: saved.append((fig, path))   # nothing written to disk
        try:
            rst = gallery_figures.scrape(None, block_vars, {"src_dir": str(DOCS)})
        finally:
            Figure.savefig = original
        return saved, rst

    saved, rst = scrape({"fig": bare, "other": managed, "x": 1})
    assert [fig for fig, _ in saved] == [bare] and "never_0.png" in rst
    plt.close(managed)   # closed by pyplot (no manager now): still not taken for a bare figure
    saved, rst = scrape({"fig": bare, "other": managed})
    assert saved == [] and rst == ""


def test_attributes_sharing_a_description_get_one_entry_each():
    """``fz_n, rider_mass_kg : float or None`` under Attributes: Sphinx would read ``fz_n,`` as a type."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_conf", DOCS / "conf.py")
    conf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conf)
    sys.path.remove(str(DOCS))   # conf.py puts docs/ on the path for the gallery's scraper
    lines = [":ivar bicycle: Bicycle set.", ":vartype bicycle: str",
             ":ivar fz_n, rider_mass_kg: Rear load [N] or", "    the rider's mass [kg].",
             ":vartype fz_n, rider_mass_kg: float or None", "Notes"]
    assert conf._split_shared_fields(lines) == [
        ":ivar bicycle: Bicycle set.", ":vartype bicycle: str",
        ":ivar fz_n: Rear load [N] or", "    the rider's mass [kg].",
        ":ivar rider_mass_kg: Rear load [N] or", "    the rider's mass [kg].",
        ":vartype fz_n: float or None", ":vartype rider_mass_kg: float or None", "Notes"]


def test_the_readme_and_docstrings_say_what_the_code_does():
    """Issue 40 item 16: the README said the compiled C agrees with the NumPy printing to 1e-12 (the test holds it
    to 1e-10, and 1e-8 for the carcass tyre), and the fast path's stop signal said it stops at the roll limit only."""
    from whipple_kick.simulate import lsoda
    readme = " ".join((DOCS.parent / "README.md").read_text(encoding="utf-8").split())
    test = (DOCS.parent / "tests" / "model" / "test_slip_build.py").read_text(encoding="utf-8")
    assert 'tol = 1e-8 if transient == "carcass" else 1e-10' in test
    claim = re.search(r"its compiled C agrees with a NumPy printing of the same expressions to ([^;]*);", readme)
    assert claim and "1e-10" in claim[1] and "1e-8 for the carcass tyre" in claim[1] and "1e-12" not in claim[1]
    assert "steer limit" in lsoda._PastTheLimit.__doc__ and "roll limit" in lsoda._PastTheLimit.__doc__


def test_citation_names_the_developers_and_no_invented_person():
    """Issue 40 item 16: CITATION.cff named a placeholder ("the whipple_kick authors"). Its authors are the one
    entity the project knows, "the whipple_kick developers": no person is invented, and the thesis author (the
    source of the model and data) is a reference, not an author of the software. Its version is the package's."""
    yaml = pytest.importorskip("yaml")
    root = DOCS.parent
    citation = yaml.safe_load((root / "CITATION.cff").read_text(encoding="utf-8"))
    assert citation["authors"] == [{"name": "the whipple_kick developers"}]
    version = re.search(r'^version = "([^"]+)"', (root / "pyproject.toml").read_text(encoding="utf-8"), re.MULTILINE)[1]
    assert citation["version"] == version
    assert any(ref["authors"][0].get("family-names") == "Dell'Orto" for ref in citation["references"])


def test_stated_build_and_validate_times_give_both_measurements():
    """Issue 40 item 17: the docs stated a 20-30 s build, a 23 s first run and a 6 s ``validate`` that a newcomer
    measured at 42-62 s, 38.6 s and 14.5 s. Each place now gives both measurements and where each was made, and
    the unqualified 20-30 s is gone from the docs and from the build's own message."""
    root = DOCS.parent
    readme = (root / "README.md").read_text(encoding="utf-8")
    assert "38.6 s" in readme and "42-62 s" in readme and "timing.build_cold_s" in readme
    assert "14.5 s" in (DOCS / "commands.md").read_text(encoding="utf-8")
    assert "42-62 s" in (DOCS / "riders.md").read_text(encoding="utf-8")
    stale = [p.name for p in [root / "README.md", *DOCS.glob("*.md"), *(root / "src").rglob("*.py")]
             if "20-30 s" in p.read_text(encoding="utf-8")]
    assert stale == []

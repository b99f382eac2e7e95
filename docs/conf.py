"""Sphinx configuration of the whipple_kick documentation site.

Build (offline, warnings as errors)::

    pip install -e ".[docs]"
    python -m sphinx -W --keep-going -b html docs docs/_build/html

The API reference is generated from the NumPy-style docstrings (autodoc,
autosummary, napoleon), the Markdown pages beside this file are read by
myst-parser, and the example gallery (``docs/examples/``) is run by
sphinx-gallery at every build, so every figure on its pages is made by the
current code.
"""
import os
import pathlib
import re
import sys

import whipple_kick

HERE = pathlib.Path(__file__).resolve().parent
# gallery_figures.py (the gallery's scraper for the project's bare matplotlib Figures) sits beside this file.
sys.path.insert(0, str(HERE))
# Matplotlib draws into files only (no display on CI); set before any example imports pyplot.
os.environ.setdefault("MPLBACKEND", "Agg")

project = "whipple_kick"
author = "the whipple_kick authors"
copyright = "the whipple_kick authors, BSD-3-Clause"  # noqa: A001 -- Sphinx's own name for it
release = whipple_kick.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",       # the API reference from the docstrings
    "sphinx.ext.autosummary",   # one page per module of the wings, generated at build time
    "sphinx.ext.napoleon",      # the docstrings' NumPy sections (Parameters, Returns, Example, Attributes)
    "sphinx.ext.mathjax",       # equations in the docstrings and pages
    "sphinx.ext.viewcode",      # "[source]" links: the code beside its docstring
    "myst_parser",              # the existing Markdown pages (docs/*.md)
    "sphinx_gallery.gen_gallery",  # the examples, executed at build time
]

# The Markdown pages beside conf.py are the site's chapters; the README is not part of the site.
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "examples/README.txt", "examples/*.py",
                    "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5", "auto_examples/*.codeobj.json"]

# --- MyST: the Markdown pages --------------------------------------------------------------------------
# CommonMark plus tables, as GitHub renders the pages; no $...$ math, so a dollar sign stays a dollar sign.
myst_enable_extensions = []
# Headings get anchors so that "page.md#heading" links resolve (as GitHub renders them).
myst_heading_anchors = 4

# --- API reference ---------------------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = False   # each object once, in the module it lives in
autodoc_default_options = {
    "members": True,
    "show-inheritance": True,
    "member-order": "bysource",
    # A module's __all__ may re-export names from elsewhere (simulation.py: Scenario, Result): each object is
    # documented once, in the module that defines it, so that cross-references have one target.
    "ignore-module-all": True,
}
autodoc_typehints = "description"
# Lazy imports and optional packages: nothing is mocked; every module must import with the docs extra.
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
# "Attributes" as a field list: as attribute entries they would describe the dataclass fields a second time.
napoleon_use_ivar = True
napoleon_custom_sections = [("Example", "Examples")]   # the project writes "Example" for one example
# Type names in docstrings ("array_like", "ndarray", "DataFrame") are prose here, not cross-references:
# without network access the other projects' inventories (intersphinx) cannot be fetched.
nitpicky = False
add_module_names = False

# --- Example gallery -------------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",       # every plot_*.py runs at build time
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    # An example that raises fails the build (the -W flag makes its warning an error as well).
    "abort_on_example_error": True,
    # whipple_kick draws on bare Figures (no pyplot), which gallery_figures.py finds; pyplot's as usual.
    # This order: gallery_figures must see a pyplot figure before the matplotlib scraper closes it.
    "image_scrapers": ("gallery_figures", "matplotlib"),
    "show_memory": False,
    # Only what an example prints is shown, not the repr of a block's last expression (ax.legend() ...).
    "capture_repr": (),
    "plot_gallery": "True",
}

# --- HTML ------------------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"whipple_kick {release}"
html_static_path = []
# The figures the Markdown pages show (kick.gif, stability.png ...) sit beside them and are copied as images.


def _napoleon_except_data(app, what, name, obj, options, lines):
    """Napoleon, except on the one-line ``#:`` comments of module constants and attributes.

    Napoleon reads such a docstring's first line as ``type: description``, and the project's
    comments say ``Rider models: the LQR ...`` (a label, not a type): it rendered "Rider models"
    as the constant's type and dropped it from the summary.
    """
    from sphinx.ext import napoleon

    if what not in ("data", "attribute"):
        napoleon._process_docstring(app, what, name, obj, options, lines)
        lines[:] = _split_shared_fields(lines)


def _split_shared_fields(lines):
    """One ``:ivar:`` entry per name where an Attributes section gives several (``fz_n, rider_mass_kg : float``).

    Sphinx reads ``:ivar fz_n, rider_mass_kg:`` as the variable ``rider_mass_kg`` of type ``fz_n,``;
    each name gets the shared description and type instead (Parameters sections are split by napoleon).
    """
    out, i = [], 0
    while i < len(lines):
        shared = re.match(r":(ivar|vartype) (\w+(?:, \w+)+):(.*)$", lines[i])
        if shared is None:
            out.append(lines[i])
            i += 1
            continue
        field, names, text = shared.groups()
        end = i + 1
        while end < len(lines) and lines[end].startswith(" "):   # the description's continuation lines
            end += 1
        for one in names.split(", "):
            out += [f":{field} {one}:{text}", *lines[i + 1:end]]
        i = end
    return out


def setup(app):
    from sphinx.ext import napoleon

    ours = [listener.id for listener in app.events.listeners["autodoc-process-docstring"]
            if listener.handler is napoleon._process_docstring]
    if not ours:   # a Sphinx that wires napoleon differently: fail here, not with wrongly typed constants
        raise RuntimeError("docs/conf.py: napoleon's autodoc-process-docstring listener was not found")
    for listener_id in ours:
        app.disconnect(listener_id)
    app.connect("autodoc-process-docstring", _napoleon_except_data)

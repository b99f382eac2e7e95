"""sphinx-gallery image scraper for the project's own figures.

whipple_kick draws on bare :class:`matplotlib.figure.Figure` objects with
their own Agg canvas (no pyplot: no display needed, no global state), which
sphinx-gallery's matplotlib scraper cannot see: it only knows the figures
pyplot manages. This scraper looks for Figure objects in an example's
global names after each code block and puts every one it has not shown yet
on the page, so an example reads as a user would write it
(``fig = response_figure(...)``) with no gallery-only calls.

conf.py names this module in ``image_scrapers``; sphinx-gallery imports it
and calls :func:`_get_sg_image_scraper`.
"""
from matplotlib.figure import Figure

#: ids of the figures already shown, per example file (a figure kept in a later block is shown once).
_SHOWN = {}


def scrape(block, block_vars, gallery_conf, **kwargs):
    """Save the example's new bare Figures and return the reST that shows them."""
    from sphinx_gallery.scrapers import figure_rst

    shown = _SHOWN.setdefault(block_vars["src_file"], set())
    paths = []
    for value in list(block_vars["example_globals"].values()):
        if not isinstance(value, Figure) or id(value) in shown:
            continue
        shown.add(id(value))
        # A pyplot figure (it has a manager until pyplot closes it) is the matplotlib scraper's, which
        # runs after this one (conf.py's order): seen here, it is never taken for a bare Figure later.
        if value.canvas.manager is None:
            path = next(block_vars["image_path_iterator"])
            value.savefig(path, dpi=100)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])


def _get_sg_image_scraper():
    return scrape

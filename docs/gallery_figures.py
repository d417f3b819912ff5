"""A sphinx-gallery image scraper for the figures the package builds itself.

``biped_sim.plots`` draws on :class:`matplotlib.figure.Figure` objects made directly (no pyplot state), so the
gallery's matplotlib scraper, which reads pyplot's open figures, does not see them. This one shows every such
figure that a tutorial's code block leaves in a variable, once. It runs before the matplotlib scraper, so that
it can tell pyplot's figures (which that scraper shows, then closes) from the package's.
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst


class PackageFigures:
    """The scraper: remembers which figures it has shown, so that each appears after the block that made it."""

    def __init__(self) -> None:
        self.shown: list[Figure] = []  # kept, not their ids: a collected figure's id could be reused

    def __repr__(self) -> str:  # sphinx-gallery keys its cache on the scrapers' repr
        return "PackageFigures"

    def __call__(self, block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
        figures = [value for value in block_vars["example_globals"].values() if isinstance(value, Figure)]
        paths = []
        for figure in figures:
            if any(figure is seen for seen in self.shown):
                continue
            self.shown.append(figure)
            if figure.canvas.manager is not None:
                continue  # pyplot's: the matplotlib scraper, which runs next, shows it (and closes it)
            path = next(block_vars["image_path_iterator"])
            figure.savefig(path, dpi=150)
            paths.append(path)
        return figure_rst(paths, gallery_conf["src_dir"])

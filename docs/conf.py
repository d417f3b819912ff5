"""Sphinx configuration of the biped-sim documentation site (``make docs``).

Sphinx with MyST (pages in Markdown), autodoc and autosummary (the API reference from the docstrings),
napoleon (the few NumPy-style sections) and sphinx-gallery: the tutorials are plain Python scripts in
``docs/examples/`` that also run on their own, executed by the build and rendered with their figures into
``docs/tutorials/`` (generated, ignored by git). sphinx-gallery rather than myst-nb: no Jupyter kernel to
start, a tutorial is a script a user can run and diff, and the build is faster. Math is rendered by MathJax,
which the reader's browser loads: the build itself needs no network.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS.parent / "src"))
sys.path.insert(0, str(DOCS))

import apigen  # noqa: E402  (docs/apigen.py, beside this file)
from docstrings import literal_if_unclean  # noqa: E402
from gallery_figures import PackageFigures  # noqa: E402

apigen.write_pages(DOCS / "api" / "generated")

project = "biped-sim"
author = "the biped-sim authors"
copyright = "2026, the biped-sim authors"
release = version = "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "examples", "**/*.ipynb", "**/*.py.md5", "**/*.codeobj.json"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"show-inheritance": False}
autosummary_generate = True
autodoc_mock_imports = ["mujoco"]  # the bench extra: its module is documented without it
napoleon_google_docstring = False
napoleon_numpy_docstring = True

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "tutorials",
    "filename_pattern": r"/tutorial_",  # every tutorial is executed
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "show_signature": False,
    "image_scrapers": (PackageFigures(), "matplotlib"),  # this order: see gallery_figures.py
}

html_theme = "furo"
html_title = "biped-sim"
html_static_path: list[str] = []
# a relative :mod: reference that two packages could satisfy (``.ground``) resolves to one of them: not an error
suppress_warnings = ["config.cache", "ref.python"]


def setup(app: object) -> None:
    """Docstrings that are not valid reStructuredText are shown verbatim (docs/docstrings.py)."""
    app.connect("autodoc-process-docstring", literal_if_unclean)  # type: ignore[attr-defined]

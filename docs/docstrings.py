"""Docstrings that are not valid reStructuredText are shown as written, not half-parsed.

The code's docstrings are written to be read as text (in the source and by ``help()``): most are also valid
reStructuredText, some are not (``|x|`` for an absolute value reads as a substitution, an indented formula as a
block quote). autodoc parses each as reStructuredText, and with warnings as errors one such docstring would stop
the build. This hook parses each docstring alone first; one that docutils warns about
is shown as a literal block instead: verbatim, which is how it was written to be read.
"""

from __future__ import annotations

import inspect
import io
from typing import Any

from docutils.core import publish_doctree


def is_clean(text: str, env: Any) -> bool:
    """Whether docutils parses ``text`` without a warning or an error (Sphinx's roles resolved through ``env``, as
    autodoc is reading a page when it calls the hook)."""
    stream = io.StringIO()
    settings = {"report_level": 2, "halt_level": 5, "warning_stream": stream, "file_insertion_enabled": False}
    try:
        publish_doctree(text, settings_overrides={**settings, "env": env})
    except Exception:  # a docstring docutils cannot even parse is shown verbatim
        return False
    return not stream.getvalue()


def foreign(obj: Any) -> bool:
    """Whether ``obj`` is a class or function of another package (a name a module imports): autodoc asks for its
    docstring while it sorts a module's members, but does not document it, and parsing it here would register what
    it describes (numpydoc attributes: scipy's BDF and Radau list the same ones) in the page's module."""
    module = getattr(obj, "__module__", None)
    return (
        (inspect.isclass(obj) or inspect.isroutine(obj))
        and isinstance(module, str)
        and module.split(".")[0] != "biped_sim"
    )


def literal_if_unclean(app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    """``autodoc-process-docstring``: replace ``lines`` (in place) by a literal block when they are not clean."""
    if not lines or foreign(obj) or is_clean("\n".join(lines), app.env):
        return
    body = ["   " + line if line.strip() else "" for line in lines]
    lines[:] = ["::", "", *body, ""]

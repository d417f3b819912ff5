"""The API reference's pages, written at each build from the package tree, so that it follows the code.

One page per package of ``biped_sim``: the package's docstring (what it is for), then its exports (its
``__all__``, the public API that ``tests/test_public_api.py`` pins), then each of its modules with the members
they define (exports excluded: they are documented once, under the package's name). The top-level page is
``biped_sim`` itself. A module added to a package appears at the next build, with no page to edit.
"""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path
from types import ModuleType

ROOT_PACKAGE = "biped_sim"


def packages() -> list[str]:
    """``biped_sim`` and its packages (not plain modules), in import order of the tree."""
    root = importlib.import_module(ROOT_PACKAGE)
    names = [ROOT_PACKAGE]
    for info in pkgutil.walk_packages(root.__path__, prefix=f"{ROOT_PACKAGE}."):
        if info.ispkg:
            names.append(info.name)
    return names


def top_modules() -> list[str]:
    """The plain modules directly under ``biped_sim`` (``plots``, ``animate``, ...)."""
    root = importlib.import_module(ROOT_PACKAGE)
    return [
        f"{ROOT_PACKAGE}.{info.name}"
        for info in pkgutil.iter_modules(root.__path__)
        if not info.ispkg and not info.name.startswith("_")
    ]


def exports(package: ModuleType) -> list[str]:
    """The package's deliberate exports: its ``__all__`` (none when it declares none)."""
    return list(getattr(package, "__all__", []))


def directive(name: str, argument: str, options: dict[str, str]) -> list[str]:
    """An autodoc directive, in an ``eval-rst`` block: autodoc writes reStructuredText, which MyST would
    otherwise show as text."""
    lines = ["```{eval-rst}", f".. {name}:: {argument}"]
    lines += [f"   :{key}: {value}".rstrip() for key, value in options.items()]
    return [*lines, "```", ""]


def export_entries(package: ModuleType) -> list[str]:
    """autodoc entries for each exported name, under the package's name."""
    lines: list[str] = []
    for name in exports(package):
        obj = getattr(package, name)
        full = f"{package.__name__}.{name}"
        # no-index: the object is indexed once, under its module (a package re-exports it, and an export may share
        # its name with a module, as ``biped_sim.simulate``)
        if isinstance(obj, type):
            lines += directive("autoclass", full, {"members": "", "no-index": ""})
        elif callable(obj):
            lines += directive("autofunction", full, {"no-index": ""})
        else:
            lines += directive("autodata", full, {"annotation": "", "no-index": ""})
    return lines


def module_names(package: ModuleType) -> list[str]:
    """The package's own modules (its subpackages get their own pages)."""
    return [
        f"{package.__name__}.{info.name}"
        for info in pkgutil.iter_modules(package.__path__)
        if not info.ispkg and info.name != "__main__"
    ]


def module_entries(module_name: str, exported: set[str]) -> list[str]:
    """A module's section: its docstring and the members it defines, less the package's exports."""
    options = {"members": ""}
    if exported:
        options["exclude-members"] = ", ".join(sorted(exported))
    return [f"## `{module_name}`", "", *directive("automodule", module_name, options)]


def package_page(package_name: str) -> str:
    """The Markdown page of one package."""
    package = importlib.import_module(package_name)
    lines = [f"# `{package_name}`", "", *directive("automodule", package_name, {"no-members": ""})]
    names = exports(package)
    if names:
        lines += ["## Exports", "", *export_entries(package)]
    if package_name == ROOT_PACKAGE:
        modules = top_modules()
    else:
        modules = module_names(package)
    for module_name in modules:
        lines += module_entries(module_name, set(names))
    return "\n".join(lines)


def write_pages(out_dir: Path) -> list[str]:
    """Write one page per package into ``out_dir`` (removing the pages of packages gone); their names."""
    out_dir.mkdir(parents=True, exist_ok=True)
    names = [name for name in packages() if name != f"{ROOT_PACKAGE}.cli"]  # the CLI: its --help and the guides
    for old in out_dir.glob("*.md"):
        if old.stem not in names:
            old.unlink()
    for name in names:
        page, text = out_dir / f"{name}.md", package_page(name)
        if not page.is_file() or page.read_text(encoding="utf-8") != text:  # unchanged: Sphinx need not reread it
            page.write_text(text, encoding="utf-8")
    return names

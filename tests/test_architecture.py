"""The house rules, checked: the layer contract, no import cycles, functions and modules of a readable size."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from importlinter.cli import lint_imports

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "biped_sim"
MAX_FUNCTION_LINES = 100
MAX_MODULE_LINES = 450


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def sources() -> dict[str, Path]:
    return {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def imported_modules(path: Path, modules: set[str]) -> set[str]:
    """biped_sim modules that ``path`` imports anywhere (module level or inside functions)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [f"{node.module}.{alias.name}" for alias in node.names] + [node.module]
        else:
            continue
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), and self-imports."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for succ in graph[node]:
            if succ not in index:
                visit(succ)
                low[node] = min(low[node], low[succ])
            elif succ in on_stack:
                low[node] = min(low[node], index[succ])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1 or node in graph[node]:
                cycles.append(sorted(component))

    for node in graph:
        if node not in index:
            visit(node)
    return cycles


def test_layer_contract_holds() -> None:
    assert lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True, no_logo=True) == 0


def test_no_import_cycles_among_modules() -> None:
    files = sources()
    modules = set(files)
    # a package's __init__ re-exporting its own modules is not a cycle of the design: leave parents out
    graph = {
        name: {m for m in imported_modules(path, modules) if not name.startswith(m + ".") and m != name}
        for name, path in files.items()
    }
    assert import_cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert import_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_modules_stay_small() -> None:
    long = {name: n for name, path in sources().items() if (n := len(path.read_text().splitlines())) > MAX_MODULE_LINES}
    assert long == {}


def test_functions_fit_on_a_screen() -> None:
    long = []
    for name, path in sources().items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    long.append(f"{name}.{node.name}: {length} lines")
    assert long == []


@pytest.mark.parametrize("name", ["plots", "report.figures", "cli.run_commands", "testing"])
def test_compiled_cache_key_ignores_modules_without_compiled_code(name: str) -> None:
    from biped_sim._compiled_cache import compiled_sources

    compiled = {module_name(path) for path in compiled_sources()}
    assert f"biped_sim.{name}" in sources()  # the module exists: a renamed one would pass below for nothing
    assert "biped_sim.multibody.planar" in compiled  # the key does cover the compiled core
    assert "biped_sim.rigid.kernels" in compiled  # and compiled code outside it (its kernels import no numba)
    assert f"biped_sim.{name}" not in compiled


def _calls(path: Path) -> list[ast.Call]:
    return [node for node in ast.walk(ast.parse(path.read_text())) if isinstance(node, ast.Call)]


def _called(call: ast.Call) -> str:
    return call.func.id if isinstance(call.func, ast.Name) else getattr(call.func, "attr", "")


def test_the_api_names_arguments_and_config_keys_not_command_line_options() -> None:
    """An error raised below the CLI names what a Python caller passed; the CLI maps it to its option."""
    flagged = [
        f"{name}:{call.lineno}"
        for name, path in sources().items()
        if not name.startswith("biped_sim.cli")
        for call in _calls(path)
        if _called(call) in ("ConfigError", "ArgumentError")
        and call.args
        and isinstance(call.args[0], ast.Constant)
        and str(call.args[0].value).startswith("--")
    ]
    assert flagged == []


def test_a_config_variant_is_made_by_derive_only() -> None:
    """No module but the config's own edits a dumped config and validates it again: ``config.derive`` does."""
    editing = [
        name
        for name, path in sources().items()
        if not name.startswith("biped_sim.config")
        and "config_from_dict(" in path.read_text()
        and "model_dump(" in path.read_text()
    ]
    assert editing == []

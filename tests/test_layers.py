"""Architecture checks (DESIGN.md): math layers never print, plot, read files or
import the shells (CLI, plots, HMI, file I/O) above them."""

from __future__ import annotations

import ast
import pathlib

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1] / "src" / "trajkit"

#: Packages/modules that are shells or I/O: math code must not import them.
SHELLS = ("trajkit.cli", "trajkit.plot", "trajkit.hmi", "trajkit.io")
#: Modules that are allowed to do I/O or print.
SHELL_DIRS = ("cli", "plot", "hmi", "io")
#: Bottom-level helpers allowed to touch files (atomic writes for exports), and
#: ``python -m trajkit`` (the command line's entry point, a shell).
IO_HELPERS = ("_atomicio.py", "__main__.py")
FORBIDDEN_IMPORTS = ("matplotlib", "plotly", "rich", "fastapi", "uvicorn", "typer")


def _math_modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG)
        if rel.parts[0] in SHELL_DIRS or rel.name in IO_HELPERS:
            continue
        yield path, rel


def _resolve(rel: pathlib.Path, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = ["trajkit", *rel.parts[:-1]]
    if rel.name == "__init__.py":
        pass
    up = node.level - 1
    parts = base[: len(base) - up] if up else base
    return ".".join(parts + ([node.module] if node.module else []))


@pytest.mark.parametrize("path,rel", list(_math_modules()), ids=lambda x: str(x))
def test_math_module_is_pure(path, rel):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            assert node.func.id not in ("print", "open", "input"), (
                f"{rel}:{node.lineno} calls {node.func.id}() in a math module"
            )
        if isinstance(node, ast.Import):
            for alias in node.names:
                assert not alias.name.startswith(FORBIDDEN_IMPORTS), (
                    f"{rel}:{node.lineno} imports {alias.name}"
                )
                assert not alias.name.startswith(SHELLS), f"{rel}:{node.lineno} imports {alias.name}"
        if isinstance(node, ast.ImportFrom):
            mod = _resolve(rel, node)
            assert not mod.startswith(FORBIDDEN_IMPORTS), f"{rel}:{node.lineno} imports {mod}"
            assert not mod.startswith(SHELLS), f"{rel}:{node.lineno} imports {mod}"


def test_library_has_null_handler():
    import logging

    import trajkit  # noqa: F401

    handlers = logging.getLogger("trajkit").handlers
    assert any(isinstance(h, logging.NullHandler) for h in handlers)

"""Every ``from X import name`` inside a function of the project's packages names something X
has. Such an import runs only when its function does, so a renamed or removed helper breaks a
rarely run command at run time, not when the module is imported (the top-level imports fail at
import already)."""

from __future__ import annotations

import ast
import importlib
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("lms200", "sim", "features", "slam", "experiments")


def _project_imports() -> list[tuple[str, int, str, str]]:
    """(file, line, module, name) of every from-import of a project module inside a function."""
    found = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            tree = ast.parse(path.read_text(encoding="utf-8"))
            local = [n for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                     for n in ast.walk(f) if isinstance(n, ast.ImportFrom)]
            for node in {id(n): n for n in local}.values():
                if node.level:  # relative: from the file's package upwards
                    base = parts[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                if module.split(".")[0] not in PACKAGES:
                    continue
                found += [(str(path.relative_to(ROOT)), node.lineno, module, a.name) for a in node.names if a.name != "*"]
    return found


def test_every_from_import_of_a_project_module_resolves() -> None:
    imports = _project_imports()
    assert len(imports) > 100
    missing = []
    for file, line, module, name in imports:
        mod = importlib.import_module(module)
        submodule = hasattr(mod, "__path__") and importlib.util.find_spec(f"{module}.{name}") is not None
        if not hasattr(mod, name) and not submodule:
            missing.append(f"{file}:{line}: from {module} import {name}")
    assert not missing, missing

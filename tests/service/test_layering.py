"""Layers of the service: routers import nothing from one another; ``core/`` (settings, database,
tokens, logs) imports neither the repository nor the engine's diagnosis (pvlib at import)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

SERVICE = Path(__file__).resolve().parents[2] / "service"


def imported_modules(path: Path, package: str) -> set[str]:
    """Absolute names of the modules a file imports (relative imports resolved in ``package``)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")
            base = base[: len(base) - node.level + 1] if node.level else []
            module = ".".join([*base, *([node.module] if node.module else [])])
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)
    return names


def test_routers_import_nothing_from_other_routers():
    routes = SERVICE / "api" / "routes"
    names = {p.stem for p in routes.glob("*.py")} - {"__init__"}
    assert {"jobs", "calibrations", "diagnoses"} <= names
    for path in routes.glob("*.py"):
        imported = imported_modules(path, "service.api.routes")
        others = {f"service.api.routes.{n}" for n in names - {path.stem}}
        assert not imported & others, f"{path.name} imports {sorted(imported & others)}"


def test_core_imports_neither_the_repository_nor_the_diagnosis():
    for path in (SERVICE / "core").glob("*.py"):
        imported = imported_modules(path, "service.core")
        assert "service.repository" not in imported, path.name
        assert not any(m.startswith("rcengine.diagnose") for m in imported), path.name
    # What loading the settings brings in, in a fresh interpreter.
    code = (
        "import sys, service.core.config, service.core.db, service.core.security; "
        "print(sorted(m for m in ('pvlib', 'rcengine.diagnose', 'service.repository') "
        "if m in sys.modules))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert loaded == "[]"

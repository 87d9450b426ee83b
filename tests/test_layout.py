"""The code's layout rules, read from the source itself: no function body over 60 lines (its
docstring excluded) in the engine or the service, and a flat engine top level of at most 16
modules (the rest lives in packages)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_BODY_LINES = 60
MAX_TOP_LEVEL_MODULES = 16


def _body_lines(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Source lines from the first statement after the docstring to the end of the last one."""
    body = function.body
    if ast.get_docstring(function, clean=False) is not None:
        body = body[1:]
    if not body:
        return 0
    return body[-1].end_lineno - body[0].lineno + 1


def _long_functions(package: str) -> list[str]:
    long = []
    for path in sorted((ROOT / package).rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = _body_lines(node)
                if lines > MAX_BODY_LINES:
                    where = path.relative_to(ROOT)
                    long.append(f"{where}:{node.lineno} {node.name} ({lines} lines)")
    return long


SAMPLE = '''
def documented(x):
    """A docstring
    over two lines."""
    y = (
        x
    )
    return y


def undocumented(x):
    y = x
    return y
'''


def test_body_lines_exclude_the_docstring_and_count_to_the_last_statement():
    documented, undocumented = ast.parse(SAMPLE).body
    assert _body_lines(documented) == 4
    assert _body_lines(undocumented) == 2


@pytest.mark.parametrize("package", ["rcengine", "service"])
def test_no_function_body_over_60_lines(package):
    assert (ROOT / package).is_dir()
    assert _long_functions(package) == []


def test_engine_top_level_has_at_most_16_modules():
    modules = sorted(p.name for p in (ROOT / "rcengine").glob("*.py"))
    assert "__init__.py" in modules
    assert len(modules) <= MAX_TOP_LEVEL_MODULES, modules

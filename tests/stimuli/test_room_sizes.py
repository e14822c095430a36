"""Rooms of a readable size (issue 40): no module of the package over 600 lines, no
function over 100, counted on the source with :mod:`ast`.

The allow-lists name what is over today and still being moved; they only shrink.
An entry that is no longer over its limit fails too, so a fixed room leaves the list.
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PARTS = ("stimuli", "render", "study", "analysis")
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 100

#: modules over the limit that another change is splitting (path relative to the root);
#: empty: every module of the package is at most 600 lines
MODULES_BEING_MOVED: set[str] = set()
#: functions over the limit still to be split into named steps ("path:qualified name");
#: empty: every function of the package is at most 100 lines, and a new one must be too
FUNCTIONS_BEING_SPLIT: set[str] = set()


def package_files(root: Path) -> list[Path]:
    """The root modules (``errors.py``, …) and every module of the four parts."""
    files = [p for p in root.glob("*.py") if p.name != "conftest.py"]
    return files + [p for part in PARTS for p in sorted((root / part).rglob("*.py"))]


def long_modules(root: Path, limit: int = MAX_MODULE_LINES) -> dict[str, int]:
    """path → line count, of every module over ``limit`` lines."""
    out = {}
    for p in package_files(root):
        n = len(p.read_text().splitlines())
        if n > limit:
            out[p.relative_to(root).as_posix()] = n
    return out


def long_functions(root: Path, limit: int = MAX_FUNCTION_LINES) -> dict[str, int]:
    """"path:qualified name" → lines (decorators excluded, docstring included), of
    every function or method over ``limit`` lines; nested functions count on their own
    and inside their parent."""
    out = {}
    for p in package_files(root):
        rel = p.relative_to(root).as_posix()

        def visit(node, prefix):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    name = f"{prefix}{child.name}"
                    if not isinstance(child, ast.ClassDef):
                        n = child.end_lineno - child.lineno + 1
                        if n > limit:
                            out[f"{rel}:{name}"] = n
                    visit(child, name + ".")
                else:
                    visit(child, prefix)
        visit(ast.parse(p.read_text(), str(p)), "")
    return out


def test_no_module_over_600_lines():
    found = long_modules(ROOT)
    new = {m: n for m, n in found.items() if m not in MODULES_BEING_MOVED}
    assert not new, "modules over 600 lines (split into named siblings): " + repr(new)
    stale = MODULES_BEING_MOVED - set(found)
    assert not stale, "no longer over 600 lines, take off the allow-list: " + repr(sorted(stale))


def test_no_function_over_100_lines():
    found = long_functions(ROOT)
    new = {f: n for f, n in found.items() if f not in FUNCTIONS_BEING_SPLIT}
    assert not new, "functions over 100 lines (split into named steps): " + repr(new)
    stale = FUNCTIONS_BEING_SPLIT - set(found)
    assert not stale, "no longer over 100 lines, take off the allow-list: " + repr(sorted(stale))


def test_the_counts_see_a_long_module_and_a_long_nested_function(tmp_path):
    """The counter itself, on a toy tree: a 601-line module, a 101-line inner closure."""
    for part in PARTS:
        (tmp_path / part).mkdir()
    (tmp_path / "stimuli" / "big.py").write_text("x = 1\n" * 601)
    body = "".join(f"        y{i} = {i}\n" for i in range(99))
    (tmp_path / "render" / "f.py").write_text(
        "def outer():\n    def inner():\n" + body + "        return 0\n    return inner\n")
    assert long_modules(tmp_path) == {"stimuli/big.py": 601}
    assert long_functions(tmp_path) == {"render/f.py:outer": 103, "render/f.py:outer.inner": 101}
    assert long_functions(tmp_path, limit=101) == {"render/f.py:outer": 103}

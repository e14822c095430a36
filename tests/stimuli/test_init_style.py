"""One ``__init__`` style (issue 40): a package's ``__init__`` imports its names plainly,
or, where import time matters, hands them to :func:`flipstudy._lazy.attach`; no package
rolls its own ``__getattr__`` or module class."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PARTS = ("stimuli", "render", "study", "analysis")


def own_lazy_loading(path: Path) -> list[str]:
    """What in one ``__init__`` loads names its own way: a module ``__getattr__`` or
    ``__dir__``, a module-level ``importlib`` or ``types`` import, a module class swap
    (a function's own ``importlib``, the CLI's command families, is not name loading)."""
    out = []
    tree = ast.parse(path.read_text(), str(path))
    for node in [*tree.body, *(n for n in ast.walk(tree) if isinstance(n, ast.Attribute))]:
        if isinstance(node, ast.FunctionDef) and node.name in ("__getattr__", "__dir__"):
            out.append(f"def {node.name} (line {node.lineno})")
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            if any(m in ("importlib", "types") for m in mods):
                out.append(f"import {', '.join(mods)} (line {node.lineno})")
        if isinstance(node, ast.Attribute) and node.attr == "__class__" and isinstance(node.ctx, ast.Store):
            out.append(f"a module class swap (line {node.lineno})")
    return out


def test_every_package_init_imports_plainly_or_attaches():
    inits = [ROOT / "__init__.py"] + [p for part in PARTS for p in sorted((ROOT / part).rglob("__init__.py"))]
    found = {str(p.relative_to(ROOT)): own_lazy_loading(p) for p in inits}
    assert not {k: v for k, v in found.items() if v}, found


def test_the_check_sees_a_hand_made_lazy_init(tmp_path):
    p = tmp_path / "__init__.py"
    p.write_text("import importlib\n\ndef __getattr__(name):\n    return importlib.import_module(name)\n")
    assert own_lazy_loading(p) == ["import importlib (line 1)", "def __getattr__ (line 3)"]


def test_the_lazy_packages_load_nothing_heavy_and_keep_function_names():
    """``import flipstudy`` and the lazy parts load no numpy; a name loads on first use;
    importing the submodule ``flipstudy.stimuli.analyse`` leaves ``analyse`` the function."""
    code = ("import sys, flipstudy, flipstudy.stimuli, flipstudy.render, flipstudy.stimuli.control\n"
            "print('numpy' in sys.modules)\n"
            "import flipstudy.stimuli.analyse\n"
            "print(callable(flipstudy.stimuli.analyse), flipstudy.render.stage.__module__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True", "flipstudy.render.staging"]

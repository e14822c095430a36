"""Doctests of the package, imported as ``flipstudy.…`` (pytest's own import would not).

``python -m pytest`` collects ``tests/`` and, with ``--doctest-modules`` (see
``[tool.pytest.ini_options]`` in pyproject.toml), the docstring examples of the
package's folders.  The repository's top level *is* the package ``flipstudy``
(setuptools' ``package-dir``), but its folder is named after the checkout, so
pytest would import ``stimuli/body.py`` as a second, top-level ``stimuli.body``
(``flipstudy.stimuli.body`` holding other class objects).  Here each doctest
module of the package is imported under its installed name instead, from the
installation that must point at this checkout (``pip install -e .``).
"""
from __future__ import annotations

import importlib
from pathlib import Path

import pytest
from _pytest.doctest import DoctestModule

ROOT = Path(__file__).resolve().parent
PARTS = ("stimuli", "render", "study", "analysis")


def package_module_name(path: Path) -> str | None:
    """``flipstudy.…`` of a source file of the package, ``None`` for any other file."""
    rel = path.resolve().relative_to(ROOT) if path.resolve().is_relative_to(ROOT) else None
    if rel is None or rel.suffix != ".py" or (len(rel.parts) > 1 and rel.parts[0] not in PARTS):
        return None
    if len(rel.parts) == 1 and rel.name != "__init__.py":
        return None
    parts = list(rel.with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(["flipstudy", *parts])


class PackageDoctestModule(DoctestModule):
    """A doctest module imported by its name in the installed package."""

    def _getobj(self):
        name = package_module_name(self.path)
        try:
            mod = importlib.import_module(name)
        except ImportError as e:
            raise self.CollectError(f"cannot import {name} ({self.path}): {e}") from e
        origin = Path(mod.__file__).resolve()
        if origin != self.path.resolve():
            raise self.CollectError(
                f"{name} is installed from {origin}, not from this checkout ({self.path}): "
                f"run `pip install -e .` here")
        return mod


@pytest.hookimpl(wrapper=True)
def pytest_collect_file(file_path: Path, parent):
    collected = yield
    if package_module_name(file_path) is None:
        return collected
    return [PackageDoctestModule.from_parent(parent, path=file_path)
            if type(c) is DoctestModule else c for c in collected]

"""Doctests of the package, imported as ``flipstudy.…`` (pytest's own import would not).

``python -m pytest`` collects ``tests/`` and, with ``--doctest-modules`` (see
``[tool.pytest.ini_options]`` in pyproject.toml), the docstring examples of the
package's folders.  The repository's top level *is* the package ``flipstudy``
(setuptools' ``package-dir``), but its folder is named after the checkout, so
pytest would import ``stimuli/body.py`` as a second, top-level ``stimuli.body``
(``flipstudy.stimuli.body`` holding other class objects).  Here each doctest
module of the package, and each package ``__init__.py`` that pytest imports to
set up a package's tests, is imported under its installed name instead, from the
installation that must point at this checkout (``pip install -e .``).
"""
from __future__ import annotations

import importlib
from pathlib import Path

import pytest
from _pytest.doctest import DoctestModule

ROOT = Path(__file__).resolve().parent
PARTS = ("stimuli", "render", "study", "analysis", "vocab")   # the four parts and the floor


def package_module_name(path: Path) -> str | None:
    """``flipstudy.…`` of a source file of the package, ``None`` for any other file."""
    rel = path.resolve().relative_to(ROOT) if path.resolve().is_relative_to(ROOT) else None
    if rel is None or rel.suffix != ".py" or (len(rel.parts) > 1 and rel.parts[0] not in PARTS):
        return None
    if len(rel.parts) == 1 and rel.name not in ("__init__.py", "errors.py", "results.py"):
        return None
    parts = list(rel.with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(["flipstudy", *parts])


def import_installed(node, path: Path):
    """The module of ``path`` imported as ``flipstudy.…``; a collection error when
    it cannot be imported or the installed package is another checkout."""
    name = package_module_name(path)
    try:
        mod = importlib.import_module(name)
    except ImportError as e:
        raise node.CollectError(f"cannot import {name} ({path}): {e}") from e
    origin = Path(mod.__file__).resolve()
    if origin != path.resolve():
        raise node.CollectError(f"{name} is installed from {origin}, not from this checkout ({path}): "
                                f"run `pip install -e .` here")
    return mod


class PackageDoctestModule(DoctestModule):
    """A doctest module imported by its name in the installed package."""

    def _getobj(self):
        return import_installed(self, self.path)


class InstalledModule(pytest.Module):
    """A file of the package named on the command line (or in ``testpaths``), which
    pytest collects as a test module whatever its name, imported by its installed name."""

    def _getobj(self):
        return import_installed(self, self.path)


class InstalledPackage(pytest.Package):
    """A package folder whose ``__init__.py`` is imported by its installed name
    (pytest's ``Package.setup`` imports it to look for ``setup_module``, of
    which the package has none)."""

    def setup(self) -> None:
        import_installed(self, self.path / "__init__.py")


@pytest.hookimpl(wrapper=True)
def pytest_collect_file(file_path: Path, parent):
    collected = yield
    if package_module_name(file_path) is None:
        return collected
    swap = {DoctestModule: PackageDoctestModule, pytest.Module: InstalledModule}
    return [swap[type(c)].from_parent(parent, path=file_path) if type(c) in swap else c
            for c in collected]


def pytest_collection_modifyitems(config, items):
    # the repository root's Package is made by a hook of its parent folder, which
    # this conftest does not reach: its packages are switched here, before setup
    for node in {n for item in items for n in item.listchain()}:
        if type(node) is pytest.Package and package_module_name(node.path / "__init__.py"):
            node.__class__ = InstalledPackage
    # tests marked slow run only when asked for (-m slow, or any -m naming them)
    if "slow" not in (config.getoption("markexpr", "") or ""):
        skip = pytest.mark.skip(reason="slow: run with -m slow")
        for item in items:
            if item.get_closest_marker("slow"):
                item.add_marker(skip)

"""The one way a package of flipstudy loads its public names on first use.

A package ``__init__`` imports its names plainly, unless importing them costs what
a command that does not need them should not pay (measured: ``import
flipstudy.study.cli`` 0.05 s; the names of ``flipstudy.stimuli`` eagerly 0.6 s,
those of ``flipstudy.render`` 1.2 s, of ``flipstudy.stimuli.control`` 0.8 s: scipy,
PyVista).  Those packages, ``flipstudy.stimuli.edit`` (whose motion operations
render re-exports: its algorithms cost 0.2 s more) and the root call :func:`attach`
with each public name
and the module it is defined in (the mapping of ``lazy_loader.attach``, without the
dependency)::

    attach(__name__, {".motion": ["Clip", "load_bvh"], ".body": ["Body"]})

The name is imported on first use and kept in the package.  Importing a submodule of
the same name as a function (``flipstudy.stimuli.analyse``, the module, beside
``analyse``, the function) leaves the package's name the function, as an eager import
would.
"""
from __future__ import annotations

import importlib
import sys
import types


class _LazyPackage(types.ModuleType):
    """A package whose names of ``_LAZY_NAMES`` (name → module) load on first use."""

    def __getattr__(self, name: str):
        where = self.__dict__.get("_LAZY_NAMES", {})
        if name not in where:
            raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name], self.__name__), name)
        self.__dict__[name] = value
        return value

    def __setattr__(self, name: str, value) -> None:
        # importing the submodule flipstudy.stimuli.analyse binds it here; the name
        # stays the function analyse(), as when it was imported eagerly
        if name in self.__dict__.get("_LAZY_NAMES", {}) and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)

    def __dir__(self):
        return sorted(set(self.__dict__) | set(self.__dict__.get("_LAZY_NAMES", {})))


def attach(package: str, names: dict[str, list[str] | tuple[str, ...]]) -> list[str]:
    """Make the names of ``names`` (module, relative to ``package`` or absolute → its
    names) attributes of ``package`` loaded on first use; returns them, in order (for
    ``__all__``).

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : dict of str to list of str
        Module → the public names defined there.

    Returns
    -------
    list of str

    Examples
    --------
    >>> import flipstudy.stimuli as s
    >>> "Clip" in dir(s), type(s).__name__
    (True, '_LazyPackage')
    """
    mod = sys.modules[package]
    where = dict(mod.__dict__.get("_LAZY_NAMES", {}))
    for module, attrs in names.items():
        for a in attrs:
            where[a] = module
    mod.__dict__["_LAZY_NAMES"] = where
    mod.__class__ = _LazyPackage
    return [a for attrs in names.values() for a in attrs]

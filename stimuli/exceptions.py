"""Transitional: the error family now lives in :mod:`flipstudy.errors` at the
package root; this module re-exports it until every importer has moved."""
from flipstudy.errors import *  # noqa: F401,F403
from flipstudy.errors import __all__  # noqa: F401

"""The one family of user errors: every error a user can act on (a bad file, a
design field, a refused edit) is a :class:`FlipstudyError`, whose message names
the file and line, or the field, and what was expected.  The CLI prints these in
one line; any other exception is a bug and is shown with its traceback.

The concrete classes keep ``ValueError`` as a second base so code written
against the older classes (``except ValueError``) still catches them.
"""
from __future__ import annotations


class FlipstudyError(Exception):
    """Base of every flipstudy user error (see :mod:`stimuli.exceptions`)."""


class FlipstudyValueError(FlipstudyError, ValueError):
    """A user error that is also a ``ValueError`` (bad value in a file or field)."""


__all__ = ["FlipstudyError", "FlipstudyValueError"]

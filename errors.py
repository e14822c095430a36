"""The one family of user errors: every error a user can act on (a bad file, a
design field, a refused edit) is a :class:`FlipstudyError`, whose message names
the file and line, or the field, and what was expected.  The CLI prints these in
one line; any other exception is a bug and is shown with its traceback.

The concrete classes keep ``ValueError`` as a second base so code written
against the older classes (``except ValueError``) still catches them.
"""
from __future__ import annotations


class FlipstudyError(Exception):
    """Base of every flipstudy user error (see :mod:`flipstudy.errors`).

    Example
    -------
    >>> from flipstudy import FlipstudyError, load_bvh
    >>> try:
    ...     load_bvh("no-such-file.bvh")
    ... except FlipstudyError as e:
    ...     print(type(e).__name__, "|", e)
    BVHError | no-such-file.bvh: cannot read file: ...
    """


class FlipstudyValueError(FlipstudyError, ValueError):
    """A user error that is also a ``ValueError`` (bad value in a file or field)."""


class FlipstudyFileNotFoundError(FlipstudyError, FileNotFoundError):
    """A file or folder the user named (or a step before this one should have made) is absent."""


class FlipstudyFileExistsError(FlipstudyError, FileExistsError):
    """An output the user named exists and would be replaced (``--force`` not given)."""


class FlipstudyOSError(FlipstudyError, OSError):
    """A file the user named cannot be read or written (the message names it and why)."""


class FlipstudyStateError(FlipstudyError, RuntimeError):
    """A file is in a state this flipstudy cannot use (e.g. a newer schema version)."""


class StyleError(FlipstudyValueError):
    """An invalid render style (:class:`flipstudy.render.style.Style`): the message
    names the style file (when read from one), the key, the allowed values and the
    value given; ``key`` is the field, ``detail`` the message without file and key."""

    def __init__(self, message: str, key: str | None = None, detail: str | None = None):
        super().__init__(message)
        self.key = key
        self.detail = detail if detail is not None else message.split(": ", 1)[-1]


class ManifestError(FlipstudyValueError):
    """A study's ``manifest.csv`` that is not what a build writes (a missing or
    unknown column, a cell that is not a number, a file it names that is missing
    or changed); the message names the file, line and column."""


class CalibrationError(FlipstudyValueError):
    """A calibration file (``flipstudy calibrate``, ``score --calibration``) that cannot be
    read or used: the message names the file and the field."""


__all__ = ["CalibrationError", "FlipstudyError", "FlipstudyValueError", "FlipstudyFileNotFoundError",
           "FlipstudyFileExistsError", "FlipstudyOSError", "FlipstudyStateError", "StyleError",
           "ManifestError"]


class MotionFileError(FlipstudyValueError):
    """A joint-position array, an AMASS/SMPL ``.npz``, a layout file or a body-model
    file that is not what its reader expects (shape, NaN frames, unknown layout, a
    missing ``--body-model``): the message names the file and what was expected."""


__all__ += ["MotionFileError"]

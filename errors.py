"""The one family of user errors: every error a user can act on (a bad file, a
design field, a refused edit) is a :class:`FlipstudyError`, whose message names
the file and line, or the field, and what was expected.  The CLI prints these in
one line; any other exception is a bug and is shown with its traceback.

Every user-error class of the four parts is defined here (grouped by the part
that raises it), so no part imports another only for its errors.  The concrete
classes keep a built-in second base (``ValueError``, ``OSError``, …) so code
written against the older classes (``except ValueError``) still catches them.
Every class is named ``…Error``; the eleven that were not (``StudyLocked``,
``NeedsExport``, ``Conflict``, …) keep their old names as aliases (:data:`OLD_NAMES`).
"""
from __future__ import annotations


class FlipstudyError(Exception):
    """Base of every flipstudy user error (see :mod:`flipstudy.errors`).

    Examples
    --------
    >>> from flipstudy import FlipstudyError, load_bvh
    >>> try:
    ...     load_bvh("no-such-file.bvh")
    ... except FlipstudyError as e:
    ...     print(type(e).__name__, "|", e)
    BVHError | no-such-file.bvh: cannot read file: ...
    """

    #: how ``flipstudy``'s ``main()`` reports it: exit status and the word before the message
    exit_status: int = 1
    label: str = "error: "


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


class FlipstudyUsageError(FlipstudyError, ValueError):
    """Options that together ask for nothing or for a contradiction: a usage error,
    exit status 2 as argparse's."""

    exit_status = 2


# ---- stimuli: motion in, stimuli out


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



class BVHError(FlipstudyError, ValueError):
    """A malformed BVH file: the message names the file, the line and what was expected.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    line : int or None
        Its line (1-based), or None when the problem is the whole file.
    message : str
        What was found and what was expected.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import load_bvh
    >>> from flipstudy.errors import BVHError
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     bad = pathlib.Path(tmp) / "bad.bvh"
    ...     _ = bad.write_text("HIERARCHY\\nROOT Hips\\n")
    ...     try:
    ...         load_bvh(bad)
    ...     except BVHError as e:
    ...         print(e.line is not None, isinstance(e, ValueError))
    True True
    """

    def __init__(self, path, line: int | None, message: str):
        self.path = str(path)
        self.line = line
        where = f"{self.path}" + (f", line {line}" if line is not None else "")
        super().__init__(f"{where}: {message}")


class BodyMappingError(FlipstudyError, ValueError):
    """A skeleton whose joints cannot be mapped to the body's segments (the message names them)."""


class DesignError(FlipstudyError, ValueError):
    """An invalid study design; the message names the file and field."""


class SynthError(FlipstudyError, ValueError):
    """Parameters for which no consistent motion exists (the message says which).

    Examples
    --------
    >>> from flipstudy import builtin
    >>> try:
    ...     builtin("backflip", height=2.5, crouch_depth=0.1, flight_time=0.3)
    ... except SynthError as e:
    ...     print(str(e)[:59])
    take-off: the legs cannot put the centre of mass on the pla
    """


class StimulusError(FlipstudyError, ValueError):
    """A stimulus that cannot be made or whose measured error misses the nominal."""


class AnimatorEditError(FlipstudyError, ValueError):
    """An edit that cannot be made (bad joints or times)."""


class FlipEditError(FlipstudyError, ValueError):
    """A flip edit (more flips, a join in flight) that cannot be made; the message says why.

    Examples
    --------
    >>> from flipstudy import builtin
    >>> from flipstudy.stimuli.edit import multiflip
    >>> try:
    ...     multiflip(builtin("backflip"), 7)
    ... except FlipEditError as e:
    ...     print(e)
    flips must be a whole number from 1 to 6, got 7
    """


class ConcatError(FlipstudyError, ValueError):
    """Two motions that cannot be concatenated; the message says why.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate
    >>> c = builtin("backflip")
    >>> try:
    ...     concatenate(c, c, max_cost=1e-3)
    ... except ConcatError as e:
    ...     print(str(e)[:36])
    the motions are too different to ble
    """


class StudyLockedError(FlipstudyError, RuntimeError):
    """Another build (or ``flipstudy archive``) holds the lock of this study folder."""


class StudyFolderError(FlipstudyError, FileExistsError):
    """A folder that a build will not replace (it holds files the build did not write)."""


# ---- render: rendering


class StudyRenderError(FlipstudyError, ValueError):
    """A study that cannot be rendered as asked (its manifest, files or settings)."""


class StaleRenderError(StudyRenderError):
    """Rendered outputs that do not match the study (stale, missing, mixed settings)."""


# ---- analysis: analysis


class ResponsesError(FlipstudyError, ValueError):
    """A response table that cannot be analysed; the message says where and what was expected.

    Examples
    --------
    >>> import pandas as pd
    >>> from flipstudy.analysis import ResponsesError, load_responses
    >>> try:
    ...     load_responses(pd.DataFrame({"participant": ["P01"], "group": ["g"]}))
    ... except ResponsesError as e:
    ...     print(type(e).__name__)
    ResponsesError
    """


class NeedsExportError(ResponsesError):
    """A study folder without ``responses.csv``: a step to take first (``flipstudy export``),
    reported as every user error is ("error:", exit status 1), the message naming the step
    (issue 33: a log or CI reader needs the word and the status to see that it failed).

    Examples
    --------
    >>> from flipstudy.analysis import NeedsExportError, load_responses
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     try:
    ...         load_responses(tmp)
    ...     except NeedsExportError as e:
    ...         print("flipstudy export" in str(e))
    True
    """


# ---- study: sessions, storage, export, the web site, reproduce


class RequestError(FlipstudyError):
    """A request that is refused: ``status`` (4xx) and a message for the JSON body
    (the server answers it; the CLI prints it as any other user error)."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status
        self.message = message


class ConflictError(FlipstudyError):
    """A write that contradicts what is stored (HTTP 409)."""


class SessionError(FlipstudyError, ValueError):
    """A session that cannot be opened; the message tells the experimenter what to do."""


class StudyChangedError(SessionError):
    """The study folder a server serves was replaced or changed under it (its folder,
    ``sessions.sqlite``, ``manifest.csv`` or ``design.toml``): the server stops taking
    answers, since it could no longer store them in the study's own database."""


class ParticipantBusyError(FlipstudyError, ValueError):
    """Another process serves this participant of this study."""


class ModelError(FlipstudyError, ValueError):
    """An invalid observer model; the message names the file and field."""


class StudyHasAnswersError(FlipstudyError, FileExistsError):
    """A command would replace or delete a study that holds real participants' answers."""


class ArchiveError(FlipstudyError, OSError):
    """``flipstudy archive`` cannot move the study (the message says why)."""


class ClusterError(FlipstudyError, RuntimeError):
    """A cluster that cannot run this build (address, workers, files)."""


class VersionMismatchError(ClusterError):
    """A worker whose Python or key packages differ from the client's."""


class NoSharedFolderError(ClusterError):
    """A worker that cannot read or write the study folder at the client's path."""


class ReproduceError(FlipstudyError, RuntimeError):
    """The reproduce run cannot start or a stage failed (message names which)."""


class OwnedPathError(FlipstudyError, FileExistsError):
    """An output path is a file or folder that a study folder owns."""

class StudyInUseError(FlipstudyError, RuntimeError):
    """A command would replace a study that a ``flipstudy run`` server has open, a
    server would open a study that a command is replacing right now, or another
    command held the study's writer lock (:class:`flipstudy.study.lock.StudyLock`)
    for longer than ``FLIPSTUDY_LOCK_WAIT`` seconds."""

class DesignFrozenError(FlipstudyError, RuntimeError):
    """The design of a study with answers would change, or has changed."""

class CorruptDatabaseError(FlipstudyStateError):
    """``sessions.sqlite`` is not a readable SQLite database (truncated, overwritten)."""


class SiteError(FlipstudyError, ValueError):
    """A site that cannot be written; the message says what to do."""


class WebImportError(FlipstudyError, ValueError):
    """A results file that cannot be imported; the message names file and line or row."""


class JsPsychFetchError(FlipstudyError, RuntimeError):
    """jsPsych could not be fetched or the cached copy does not match the pins."""


__all__ = [
    "FlipstudyError",
    "FlipstudyValueError",
    "FlipstudyFileNotFoundError",
    "FlipstudyFileExistsError",
    "FlipstudyOSError",
    "FlipstudyStateError",
    "FlipstudyUsageError",
    "StyleError",
    "ManifestError",
    "CalibrationError",
    "BVHError",
    "BodyMappingError",
    "DesignError",
    "SynthError",
    "StimulusError",
    "AnimatorEditError",
    "FlipEditError",
    "ConcatError",
    "StudyLockedError",
    "StudyFolderError",
    "StudyRenderError",
    "StaleRenderError",
    "ResponsesError",
    "NeedsExportError",
    "RequestError",
    "ConflictError",
    "SessionError",
    "StudyChangedError",
    "ParticipantBusyError",
    "ModelError",
    "StudyHasAnswersError",
    "ArchiveError",
    "ClusterError",
    "VersionMismatchError",
    "NoSharedFolderError",
    "ReproduceError",
    "OwnedPathError",
    "StudyInUseError",
    "DesignFrozenError",
    "CorruptDatabaseError",
    "SiteError",
    "WebImportError",
    "JsPsychFetchError",
]


class SourceMismatchError(FlipstudyValueError):
    """The ``[[sources]]`` of a comparison design do not hold the same items (a clip
    missing in one folder, a folder without clips, an item twice); the message names
    the folder and the item."""


class ComparisonError(FlipstudyValueError):
    """A comparison study's answers or strengths that cannot be analysed or simulated
    as asked (a source never compared, an unknown source); the message says which."""


__all__ += ["SourceMismatchError", "ComparisonError"]


class MotionFileError(FlipstudyValueError):
    """A joint-position array, an AMASS/SMPL ``.npz``, a layout file or a body-model
    file that is not what its reader expects (shape, NaN frames, unknown layout, a
    missing ``--body-model``): the message names the file and what was expected."""


__all__ += ["MotionFileError"]


class UnphysicalClipError(FlipstudyError, ValueError):
    """A CLIP that physics contradicts (apparent gravity, body height), refused by the
    one loading gate (:func:`flipstudy.stimuli.loading.checked_clip`) with the fix."""


__all__ += ["UnphysicalClipError"]


# ---- the names before issue 40 (every class is named …Error now)

StudyLocked = StudyLockedError
NeedsExport = NeedsExportError
Conflict = ConflictError
StudyChanged = StudyChangedError
ParticipantBusy = ParticipantBusyError
StudyHasAnswers = StudyHasAnswersError
VersionMismatch = VersionMismatchError
NoSharedFolder = NoSharedFolderError
StudyInUse = StudyInUseError
DesignFrozen = DesignFrozenError
CorruptDatabase = CorruptDatabaseError

#: old name → the class: code that catches an error by its old name, and pickles that
#: name it, keep working (a pickle names the class by its module and name); not in
#: ``__all__``, which lists each class once, by its name
OLD_NAMES = {n: globals()[n] for n in (
    "StudyLocked", "NeedsExport", "Conflict", "StudyChanged", "ParticipantBusy", "StudyHasAnswers",
    "VersionMismatch", "NoSharedFolder", "StudyInUse", "DesignFrozen", "CorruptDatabase")}

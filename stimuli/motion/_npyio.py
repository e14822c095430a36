"""Bounded readers of ``.npy`` and ``.npz`` files (joint positions, AMASS motions,
body models): every header is read and checked before an array is allocated.

An ``.npy`` header names the shape and dtype; it is read with
:mod:`numpy.lib.format` and refused when it holds Python objects (never
unpickled), a structured type, more than :data:`MAX_POSITION_FRAMES` frames (for
the arrays whose first axis is frames), more than :data:`MAX_JOINT_FRAMES` frames ×
joints (a position array) or more than :data:`MAX_ARRAY_BYTES` bytes; an ``.npz`` is opened with :mod:`zipfile`, and each member read is
checked the same way (its header, its uncompressed size, the total of all
members read), so neither a header claiming 10¹² frames nor a small zip of a
gigabyte of compressed zeros allocates more than the limit.  A truncated file, a
bad CRC, a text or BVH file named ``.npy`` each give a
:class:`~flipstudy.errors.MotionFileError` naming the file and the array.
"""
from __future__ import annotations

import math
import os
import stat
import zipfile
import zlib
from pathlib import Path

import numpy as np
from numpy.lib import format as npformat

from flipstudy.errors import MotionFileError

#: Frames a position or AMASS file may hold: 100,000 (13.9 min at 120 fps, 55 min at
#: 30 fps; a 10-minute capture at 120 fps is 72,000).
MAX_POSITION_FRAMES = 100_000
#: Bytes of the arrays read from one ``.npy``/``.npz`` file, as stored (256 MiB).
MAX_ARRAY_BYTES = 256 * 2**20
#: Frames × joints of a position array (2.5 million: 100,000 frames of 25 joints; the clip
#: built from 2.1 million, 100,000 frames of 21 joints, peaks at 1.2 GB in 13 s).
MAX_JOINT_FRAMES = 2_500_000

_ZIP_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, OSError,
               NotImplementedError, RuntimeError, ValueError)


def _regular_file(path: Path, what: str) -> int:
    """The size of ``path``, a regular file (not a directory, device or FIFO)."""
    try:
        st = os.stat(path)
    except OSError as e:
        raise MotionFileError(f"{path}: cannot read the {what}: {e.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file (a device or pipe)"
        raise MotionFileError(f"{path}: the {what} is {kind}; expected a regular file")
    return st.st_size


def _what_it_is(head: bytes) -> str:
    """A guess at what a file that is not an ``.npy`` is, from its first bytes."""
    if not head:
        return "it is empty"
    if head.lstrip().upper().startswith(b"HIERARCHY"):
        return "it reads as a BVH file (name it .bvh)"
    if head.startswith(b"PK"):
        return "it is a zip archive (an .npz named .npy?)"
    return "it does not start with numpy's \\x93NUMPY signature"


def _header(f, where: str) -> tuple[tuple, bool, np.dtype]:
    """Shape, Fortran order and dtype of the ``.npy`` stream ``f`` (at its start)."""
    head = f.read(6)
    if head != npformat.MAGIC_PREFIX:
        raise MotionFileError(f"{where}: not a readable .npy/.npz file: {_what_it_is(head + f.read(64))}")
    try:
        version = tuple(f.read(2))
        if version == (1, 0):
            return npformat.read_array_header_1_0(f)
        if version == (2, 0):
            return npformat.read_array_header_2_0(f)
    except Exception as e:          # numpy's parser of the (<= 10,000-byte) header: tokenize, ast, …
        raise MotionFileError(f"{where}: the .npy header is not readable "
                              f"({str(e).splitlines()[0][:200] if str(e) else type(e).__name__})") from None
    raise MotionFileError(f"{where}: .npy format version {version} is not read; expected a plain "
                          f"numeric array saved by numpy.save (version 1.0 or 2.0)")


def _check(path, label: str, shape: tuple, dtype: np.dtype, frames: bool, budget: int) -> int:
    """The bytes of an array (``label``, e.g. "the motion's array 'poses'") of ``shape``
    and ``dtype`` in file ``path``, refused beyond the limits."""
    where = f"{path}: {label}"
    if dtype.hasobject:
        raise MotionFileError(f"{path}: cannot read {label} without unpickling Python objects (it holds "
                              f"dtype object); expected plain numeric arrays")
    if dtype.names is not None or dtype.subdtype is not None or dtype.kind == "V":
        raise MotionFileError(f"{where}: a structured array ({dtype}); expected plain numbers")
    count = math.prod(shape)
    nbytes = count * dtype.itemsize
    if frames and shape and shape[0] > MAX_POSITION_FRAMES:
        raise MotionFileError(f"{where}: {shape[0]:,} frames, more than the {MAX_POSITION_FRAMES:,} a "
                              f"motion may have (stimuli.motion._npyio.MAX_POSITION_FRAMES); cut it first")
    if frames and len(shape) == 3 and shape[0] * shape[1] > MAX_JOINT_FRAMES:
        raise MotionFileError(f"{where}: {shape[0]:,} frames × {shape[1]:,} joints = {shape[0] * shape[1]:,} "
                              f"joint-frames, more than the {MAX_JOINT_FRAMES:,} a position file may hold "
                              f"(stimuli.motion._npyio.MAX_JOINT_FRAMES); cut it first")
    span = math.prod(max(int(n), 1) for n in shape)        # an empty axis hides no others' size
    if nbytes > budget or span * max(dtype.itemsize, 1) > MAX_ARRAY_BYTES:
        raise MotionFileError(f"{where}: an array of shape {shape} ({span * dtype.itemsize / 2**20:,.0f} MiB), more than "
                              f"the {MAX_ARRAY_BYTES / 2**20:g} MiB read from one file "
                              f"(stimuli.motion._npyio.MAX_ARRAY_BYTES)")
    return nbytes


def _data(f, where: str, shape: tuple, fortran: bool, dtype: np.dtype, nbytes: int) -> np.ndarray:
    """The array after a checked header, read into a buffer of exactly ``nbytes``."""
    out = np.empty(shape[::-1] if fortran else shape, dtype=dtype)
    buf = memoryview(out.reshape(-1).view(np.uint8)) if nbytes else memoryview(b"")
    got = 0
    while got < nbytes:
        chunk = f.read(min(nbytes - got, 2**24))
        if not chunk:
            raise MotionFileError(f"{where}: the file ends after {got:,} of the {nbytes:,} bytes its "
                                  f"header promises (a truncated file)")
        buf[got:got + len(chunk)] = chunk
        got += len(chunk)
    return out.T if fortran else out


def load_npy(path, frames: bool = True) -> np.ndarray:
    """The array of an ``.npy`` file, its header checked first (see the module);
    ``frames``: its first axis is frames (limited to :data:`MAX_POSITION_FRAMES`)."""
    path = Path(path)
    _regular_file(path, ".npy file")
    try:
        with open(path, "rb") as f:
            shape, fortran, dtype = _header(f, str(path))
            nbytes = _check(path, "the array", shape, dtype, frames, MAX_ARRAY_BYTES)
            return _data(f, str(path), shape, fortran, dtype, nbytes)
    except OSError as e:
        raise MotionFileError(f"{path}: cannot read the .npy file: {e.strerror or e}") from None


def _open_zip(path: Path, what: str) -> zipfile.ZipFile:
    _regular_file(path, what)
    try:
        return zipfile.ZipFile(path)
    except _ZIP_ERRORS as e:
        raise MotionFileError(f"{path}: not a readable .npz {what} (not a zip archive of .npy arrays: "
                              f"{str(e)[:200] or type(e).__name__})") from None


def npz_names(path, what: str = "file") -> list[str]:
    """The names of the arrays of an ``.npz`` (its ``.npy`` members, without ``.npy``)."""
    path = Path(path)
    with _open_zip(path, what) as z:
        names = [n[:-4] for n in z.namelist() if n.endswith(".npy")]
    if not names:
        raise MotionFileError(f"{path}: an .npz {what} without any .npy array inside")
    return names


def load_npz(path, keys, what: str = "file", frames=()) -> dict:
    """The arrays ``keys`` of an ``.npz`` (those present; others are not read), each
    header and the total checked before reading (see the module); ``frames``: the
    keys whose first axis is frames."""
    path = Path(path)
    out: dict = {}
    budget = MAX_ARRAY_BYTES
    k = None
    with _open_zip(path, what) as z:
        try:
            members = {n[:-4]: z.getinfo(n) for n in z.namelist() if n.endswith(".npy")}
            for k in keys:
                if k not in members:
                    continue
                label = f"the {what}'s array {k!r}"
                where = f"{path}: {label}"
                info = members[k]
                if info.file_size > budget + 2**16:
                    raise MotionFileError(f"{where} is {info.file_size / 2**20:,.0f} MiB uncompressed, more "
                                          f"than the {MAX_ARRAY_BYTES / 2**20:g} MiB read from one file "
                                          f"(stimuli.motion._npyio.MAX_ARRAY_BYTES)")
                with z.open(info) as f:
                    shape, fortran, dtype = _header(f, where)
                    nbytes = _check(path, label, shape, dtype, k in frames, budget)
                    out[k] = _data(f, where, shape, fortran, dtype, nbytes)
                    f.read(1)                       # to the member's end: its CRC is checked there
                budget -= nbytes
        except MotionFileError:
            raise
        except _ZIP_ERRORS as e:
            raise MotionFileError(f"{path}: the {what}'s array {k!r} is damaged ({str(e)[:200] or type(e).__name__}); "
                                  f"expected an .npz written by numpy.savez") from None
    return out


def real_array(a: np.ndarray, where: str) -> np.ndarray:
    """``a`` as float64 when it holds finite real numbers, else :class:`MotionFileError`."""
    if a.dtype.kind == "c":
        raise MotionFileError(f"{where}: holds complex numbers; expected real numbers")
    if a.dtype.kind not in "biuf":
        raise MotionFileError(f"{where}: holds {a.dtype}; expected numbers")
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        raise MotionFileError(f"{where}: holds NaN or infinite values; expected finite numbers")
    return a


def scalar(a: np.ndarray, where: str) -> float:
    """The one finite real number an array holds (a frame rate), else :class:`MotionFileError`."""
    if a.size != 1:
        raise MotionFileError(f"{where}: an array of shape {a.shape}; expected one number")
    return float(real_array(a.reshape(-1), where)[0])


__all__ = ["MAX_POSITION_FRAMES", "MAX_ARRAY_BYTES", "MAX_JOINT_FRAMES", "load_npy", "load_npz", "npz_names", "real_array", "scalar"]

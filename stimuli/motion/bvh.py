"""BVH reading and writing.

Reading resolves, at the edge, everything the real files disagree on
(``../shared/mocap/SOURCES.md`` lists them):

* **Euler orders** per joint, as the CHANNELS line lists them (intrinsic);
* **root translation convention**: if the root OFFSET equals the first frame's
  position channels (MASS exports) the channels are absolute; otherwise
  (raw CMU with a zero OFFSET, iClone with OFFSET = standing hip height and
  small channel deltas) the position is OFFSET + channels.  The same rule is
  used for any other joint that carries position channels;
* **units**: ``scale=`` (file units → metres) or ``scale=None`` to guess from the
  size of the rest skeleton (an adult standing); the guess is recorded;
* **frame time**: ``fps=`` overrides the header (the header of some CMU
  conversions is wrong: physics, not the reader, notices that);
* **T-pose first frame** of raw CMU files: detected and dropped (``drop_tpose``).

The numbers of the MOTION block are parsed in one vectorised step.  Malformed
or absurd input raises :class:`BVHError` naming the file, the line and what was
expected: only regular files of at most :data:`MAX_BVH_BYTES` are read; every number
must be finite; the frame rate must lie in :data:`FPS_RANGE`; every OFFSET, rest
joint position and position channel within :data:`MAX_POSITION_M` metres of the
origin (after unit scaling); every angle within :data:`MAX_ANGLE_DEG` degrees.

This module is the reader and the one place the BVH names are imported from; its
private helpers: :mod:`._bvh_parse` (the HIERARCHY and MOTION text),
:mod:`._bvh_units` (the unit and frame-rate guesses), :mod:`._bvh_write` (the
writer, :func:`save_bvh` and :func:`bvh_text`).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.errors import BVHError, FlipstudyValueError
from ._bvh_parse import parse_hierarchy, parse_motion
from ._bvh_units import FPS_RANGE, STANDING_HEIGHT_M, UNIT_CANDIDATES, check_fps, guess_scale, header_fps
from ._bvh_write import bvh_text, save_bvh
from .clip import Clip
from .skeleton import POSITION_CHANNELS, ROTATION_CHANNELS, Skeleton

#: Largest file :func:`load_bvh` reads (bytes); larger ones are refused by name.
#: The largest real clip we know is 4 MB; raise this module constant to read more.
MAX_BVH_BYTES = 512 * 2**20
#: Farthest a joint may be from the origin, metres (after unit scaling).
MAX_POSITION_M = 1000.0
#: Largest rotation channel value, degrees (a thousand-odd turns; beyond is not motion).
MAX_ANGLE_DEG = 1e6


def _euler_to_quat(values: np.ndarray, orders: list[str], col_of: list[list[int]]) -> np.ndarray:
    """(F,J,4) quaternions (scipy's x, y, z, w) from Euler channels in degrees.

    BVH angles are intrinsic, in the order the CHANNELS line lists them:
    ``Rotation.from_euler(order.upper(), angles, degrees=True)``, one scipy call per
    distinct order for all frames and joints with that order at once.  The angles go
    in as an (F, Jg, 3) array, not flattened to (F*Jg, 3): scipy (1.17+, N-d
    rotations) hands N-dimensional input to its vectorised numpy backend, several times
    faster than its Cython loop over 2-D input, with the same quaternions
    (``tests/stimuli/test_fast_paths.py`` checks both against each other on the shared files)."""
    F = values.shape[0]
    J = len(orders)
    groups: dict[str, list[int]] = {}
    for j, o in enumerate(orders):
        if o:
            groups.setdefault(o, []).append(j)
    if len(groups) == 1 and len(next(iter(groups.values()))) == J:   # one order for all
        order, joints = next(iter(groups.items()))
        return _from_euler(order.upper(), values[:, np.array([col_of[j] for j in joints])])
    q = np.zeros((F, J, 4))
    q[..., 3] = 1.0
    for order, joints in groups.items():
        cols = np.array([col_of[j] for j in joints])         # (Jg, 3)
        q[:, joints] = _from_euler(order.upper(), values[:, cols])   # angles (F, Jg, 3)
    return q


def _from_euler(order: str, ang: np.ndarray) -> np.ndarray:
    """(..., 4) quaternions of (..., 3) intrinsic Euler angles in degrees, one scipy
    call (N-d rotations, scipy 1.17+)."""
    return Rotation.from_euler(order, ang, degrees=True).as_quat()


def _detect_tpose(values: np.ndarray, rot_cols: np.ndarray, q: np.ndarray) -> bool:
    """True when frame 0 is a calibration T-pose: nearly all rotation channels exactly
    zero, unlike frame 1, and a pose jump to frame 1 far above the clip's usual
    frame-to-frame change."""
    if values.shape[0] < 4 or rot_cols.size == 0:
        return False
    zero0 = np.mean(values[0, rot_cols] == 0.0)
    zero1 = np.mean(values[1, rot_cols] == 0.0)
    if zero0 < 0.75 or zero1 > 0.5:
        return False
    dots = np.abs(np.sum(q[1:] * q[:-1], axis=-1)).clip(0, 1)     # (F-1, J)
    step = (2 * np.arccos(dots)).sum(axis=1)
    return bool(step[0] > 10 * max(np.median(step[1:]), 1e-6))


def _read_regular_file(path: Path) -> bytes:
    """The bytes of a regular file of at most :data:`MAX_BVH_BYTES`; a FIFO, a device
    (``/dev/zero``), a directory or a larger file is refused before it is opened."""
    try:
        st = os.stat(path)
    except OSError as e:
        raise BVHError(path, None, f"cannot read file: {e.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        kind = ("a directory" if stat.S_ISDIR(st.st_mode) else "a FIFO (named pipe)"
                if stat.S_ISFIFO(st.st_mode) else "a device" if stat.S_ISCHR(st.st_mode)
                or stat.S_ISBLK(st.st_mode) else "a socket" if stat.S_ISSOCK(st.st_mode)
                else "not a regular file")
        raise BVHError(path, None, f"is {kind}; expected a regular BVH file")
    if st.st_size > MAX_BVH_BYTES:
        raise BVHError(path, None, f"file is {st.st_size / 2**20:.0f} MiB, larger than the "
                                   f"{MAX_BVH_BYTES / 2**20:g} MiB the reader accepts "
                                   f"(stimuli.motion.bvh.MAX_BVH_BYTES)")
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_BVH_BYTES + 1)   # the file may grow between stat and read
    except OSError as e:
        raise BVHError(path, None, f"cannot read file: {e.strerror}") from None
    if len(raw) > MAX_BVH_BYTES:
        raise BVHError(path, None, f"file is larger than the {MAX_BVH_BYTES / 2**20:g} MiB the "
                                   f"reader accepts (stimuli.motion.bvh.MAX_BVH_BYTES)")
    return raw


def _check_bounds(path, h: dict, values: np.ndarray, first: int, s: float,
                  pos_cols: np.ndarray, rot_cols: np.ndarray) -> None:
    """Refuse absurd numbers (all finite by now), each with its line: OFFSETs and rest
    joint positions farther than :data:`MAX_POSITION_M` metres once scaled by ``s``,
    position channels as far, rotation channels beyond :data:`MAX_ANGLE_DEG`.  Array
    operations over all frames at once; the loops below run only to name a culprit."""
    lim = MAX_POSITION_M / s                                   # in file units
    offsets = np.array(h["offsets"], dtype=np.float64)          # (J, 3), finite
    ends = np.array([o for _, o in h["end_sites"]], dtype=np.float64).reshape(-1, 3)
    for arr, lns, what in ((offsets, h["offset_lines"], "OFFSET"),
                           (ends, h["end_lines"], "End Site OFFSET")):
        bad = np.flatnonzero(np.abs(arr).max(axis=1, initial=0) > lim)
        if bad.size:
            k = int(bad[0])
            raise BVHError(path, lns[k], f"{what} {np.abs(arr[k]).max():g} file units "
                                         f"({np.abs(arr[k]).max() * s:.3g} m at {s:g} m per unit) "
                                         f"from its joint, beyond the {MAX_POSITION_M:g} m a body "
                                         f"part can be")
    # rest pose: each joint's distance from the root (sums of bounded offsets)
    parents = h["parents"]
    rest = np.zeros_like(offsets)
    with np.errstate(over="ignore", invalid="ignore"):
        for j in range(1, len(parents)):
            rest[j] = rest[parents[j]] + offsets[j]
    far = np.flatnonzero(~(np.abs(rest).max(axis=1) <= lim))
    if far.size:
        k = int(far[0])
        raise BVHError(path, h["offset_lines"][k], f"joint {h['names'][k]!r} lies "
                                                   f"{np.abs(rest[k]).max() * s:.3g} m from the root in "
                                                   f"the rest pose, beyond {MAX_POSITION_M:g} m")
    for cols, limit, what, unit in ((pos_cols, lim, "position", f"file units (> {MAX_POSITION_M:g} m)"),
                                    (rot_cols, MAX_ANGLE_DEG, "angle", "degrees")):
        if cols.size == 0:
            continue
        over = np.abs(values[:, cols]) > limit
        if over.any():
            f, c = np.argwhere(over)[0]
            raise BVHError(path, first + int(f) + 1,
                           f"{what} {values[f, cols[c]]:g} in frame {int(f) + 1}, channel "
                           f"{int(cols[c]) + 1}: beyond ±{limit:g} {unit}")



def _lines(path: Path) -> list[str]:
    """The file's lines (UTF-8, else Latin-1; any line ending)."""
    raw = _read_regular_file(path)
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark is not part of 'HIERARCHY'
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if not text.strip():
        raise BVHError(path, 1, "empty file: expected 'HIERARCHY'")
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _channel_columns(channels):
    """Per joint its rotation columns and position columns (None without), its Euler
    order, and all rotation and position columns."""
    col_of_rot: list[list[int]] = []
    col_of_pos: list[list[int] | None] = []
    c0 = 0
    for ch in channels:
        idx = {c: c0 + k for k, c in enumerate(ch)}
        rot = [c for c in ch if c in ROTATION_CHANNELS]
        col_of_rot.append([idx[c] for c in rot])
        col_of_pos.append([idx[c] for c in POSITION_CHANNELS] if POSITION_CHANNELS[0] in idx else None)
        c0 += len(ch)
    orders = ["".join(c[0] for c in ch if c in ROTATION_CHANNELS) for ch in channels]
    rot_cols = np.array([c for cols in col_of_rot for c in cols], dtype=np.int64)
    pos_cols = np.array([c for cols in col_of_pos if cols is not None for c in cols], dtype=np.int64)
    return col_of_rot, col_of_pos, orders, rot_cols, pos_cols


def _scale(scale, h: dict, offsets: np.ndarray, meta: dict):
    """Metres per file unit, given or guessed (``meta["scale_source"]`` says which), and
    the rest skeleton the guess was made on (None when given)."""
    skel = None
    if scale is None:
        rest_offsets = offsets.copy()
        rest_offsets[0] = 0.0       # root_pos carries the root's position (see below)
        skel = Skeleton(h["names"], h["parents"], rest_offsets, h["channels"], h["end_sites"])
        with np.errstate(over="ignore", invalid="ignore"):   # absurd offsets: refused below
            s, unit = guess_scale(skel)
        meta["scale_source"] = f"guess: {unit}"
    else:
        try:
            s = float(scale)
        except (TypeError, ValueError):
            s = float("nan")
        if not (np.isfinite(s) and 1e-6 <= s <= 1e3):
            raise FlipstudyValueError(f"scale: expected metres per file unit between 1e-06 and 1000 "
                                      f"(0.01 for centimetres), got {scale!r}")
        meta["scale_source"] = "given"
    return s, skel


def _translations(values, offsets, col_of_pos, names, first_frame):
    """Translations of the root and any other joint with position channels: (root (F,3),
    joints (F,J,3) or None, the convention read per joint)."""
    J = len(names)
    root_pos = np.broadcast_to(offsets[0], (values.shape[0], 3)).copy()
    joint_pos = None
    conventions = {}
    for j in range(J):
        cols = col_of_pos[j]
        if cols is None:
            continue
        ch = values[:, cols]
        off = offsets[j]
        tol = 1e-4 * max(1.0, float(np.abs(off).max()))
        if np.any(off != 0) and np.allclose(off, first_frame[cols], atol=tol):
            pos = ch
            conventions[names[j]] = "channels are absolute (OFFSET repeats frame 1)"
        else:
            pos = off + ch
            conventions[names[j]] = "OFFSET + channels"
        if j == 0:
            root_pos = pos
        else:
            if joint_pos is None:
                joint_pos = np.broadcast_to(offsets[None], (values.shape[0], J, 3)).copy()
            joint_pos[:, j] = pos
    return root_pos, joint_pos, conventions


def load_bvh(path, scale: float | None = None, fps: float | None = None,
             drop_tpose: bool | str = "auto") -> Clip:
    """Read a BVH file into a :class:`Clip` in metres.

    Parameters
    ----------
    path : str or pathlib.Path
        The BVH file.
    scale : float or None
        Metres per file unit; ``None`` guesses it from the skeleton's size.
    fps : float, optional
        Frames per second, overriding the header's Frame Time.
    drop_tpose : {"auto", True, False}
        ``"auto"`` drops a calibration T-pose first frame (raw CMU); ``True``
        always drops frame 0, ``False`` never.

    Returns
    -------
    Clip
        In metres; ``clip.meta`` records the scale used and any warnings.

    Raises
    ------
    BVHError
        For a malformed file, naming its line and what was expected.

    Examples
    --------
    A built-in flip written in centimetres and read back, the unit guessed:

    >>> import tempfile, pathlib
    >>> from flipstudy import builtin, load_bvh, save_bvh
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = save_bvh(builtin("backflip"), pathlib.Path(tmp) / "backflip.bvh", scale=0.01)
    ...     clip = load_bvh(path, fps=60)
    >>> clip.meta["scale_source"], clip.fps
    ('guess: cm', 60.0)

    A capture of the CMU database (in its ASF length units) reads the same way,
    ``load_bvh("88_01.bvh", fps=60)``, with ``scale_source`` ``'guess: CMU/ASF
    length units (1/0.45 in)'``.
    """
    path = Path(path)
    lines = _lines(path)
    h, motion_at = parse_hierarchy(lines, path)
    n_frames, frame_time, frame_time_text, values, first = parse_motion(
        lines, motion_at, sum(len(c) for c in h["channels"]), path)

    names, parents, channels = h["names"], h["parents"], h["channels"]
    offsets = np.array(h["offsets"], dtype=np.float64)
    col_of_rot, col_of_pos, orders, rot_cols, pos_cols = _channel_columns(channels)
    meta: dict = {"name": path.stem, "path": str(path), "warnings": [], "dropped_frames": []}
    s, skel = _scale(scale, h, offsets, meta)
    _check_bounds(path, h, values, first, s, pos_cols, rot_cols)
    q = _euler_to_quat(values, orders, col_of_rot)

    first_frame = values[0]  # the translation convention is decided on the file's frame 1
    do_drop = drop_tpose is True or (drop_tpose == "auto" and _detect_tpose(values, rot_cols, q))
    if do_drop and n_frames > 1:
        values = values[1:]
        q = q[1:]
        meta["dropped_frames"] = [0]
        meta["warnings"].append(
            "frame 1 of the file is a calibration T-pose (rotation channels zero, a pose jump to "
            "frame 2); it was dropped, so frame indices count from the file's frame 2")

    root_pos, joint_pos, conventions = _translations(values, offsets, col_of_pos, names, first_frame)
    meta["root_convention"] = conventions.get(names[0], "no position channels (OFFSET only)")
    meta["file_root_offset"] = offsets[0].tolist()
    offsets[0] = 0.0  # root_pos is absolute from here on

    if skel is None:
        skel = Skeleton(names, parents, offsets, channels, h["end_sites"])
    meta["scale"] = s
    fps_header = header_fps(frame_time, frame_time_text)
    meta["header_fps"] = fps_header
    meta["header_frame_time"] = frame_time
    if fps is not None:
        fps = check_fps(fps)
        meta["fps_source"] = "given"
    else:
        fps = fps_header
        meta["fps_source"] = "header"
    if s != 1.0:  # the same as Clip.scaled(s), without building the clip twice
        skel = skel.scaled(s)
        root_pos = root_pos * s
        joint_pos = None if joint_pos is None else joint_pos * s
    return Clip(skel, fps, root_pos, q, joint_pos, meta)


__all__ = ["BVHError", "load_bvh", "save_bvh", "bvh_text", "guess_scale", "MAX_BVH_BYTES", "FPS_RANGE",
           "MAX_POSITION_M", "MAX_ANGLE_DEG", "UNIT_CANDIDATES", "STANDING_HEIGHT_M"]

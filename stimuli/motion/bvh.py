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
"""

from __future__ import annotations

from ..exceptions import FlipstudyError, FlipstudyValueError
import math
import os
import re
import stat
from decimal import Decimal, InvalidOperation
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from .._io import atomic_write_text
from .clip import Clip
from .skeleton import POSITION_CHANNELS, ROTATION_CHANNELS, Skeleton

KNOWN_CHANNELS = set(POSITION_CHANNELS) | set(ROTATION_CHANNELS)

#: Length units a BVH file is commonly written in: (metres per unit, name).
UNIT_CANDIDATES = (
    (1.0, "m"),
    (0.01, "cm"),
    (0.001, "mm"),
    (0.0254, "in"),
    (0.0254 / 0.45, "CMU/ASF length units (1/0.45 in)"),
    (0.3048, "ft"),
)
STANDING_HEIGHT_M = 1.70

#: Largest file :func:`load_bvh` reads (bytes); larger ones are refused by name.
#: The largest real clip we know is 4 MB; raise this module constant to read more.
MAX_BVH_BYTES = 512 * 2**20
#: Frame rates a BVH file may declare (or ``fps=`` give), frames per second.
FPS_RANGE = (1.0, 10_000.0)
#: Farthest a joint may be from the origin, metres (after unit scaling).
MAX_POSITION_M = 1000.0
#: Largest rotation channel value, degrees (a thousand-odd turns; beyond is not motion).
MAX_ANGLE_DEG = 1e6

_FRAMES_RE = re.compile(r"Frames\s*:\s*(.*)\Z", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"Frame\s+Time\s*:\s*(.*)\Z", re.IGNORECASE)


class BVHError(FlipstudyError, ValueError):
    """A malformed BVH file: the message names the file, the line and what was expected."""

    def __init__(self, path, line: int | None, message: str):
        self.path = str(path)
        self.line = line
        where = f"{self.path}" + (f", line {line}" if line is not None else "")
        super().__init__(f"{where}: {message}")


# --------------------------------------------------------------------- reading
def _parse_hierarchy(lines: list[str], path) -> tuple[dict, int]:
    """Parse HIERARCHY up to MOTION. Returns skeleton parts and the MOTION line index."""
    names: list[str] = []
    index_of: dict[str, int] = {}  # name -> joint: uniqueness checked in O(1)
    offset_lines: list[int] = []   # 1-based line of each joint's OFFSET
    end_lines: list[int] = []      # 1-based line of each End Site's OFFSET
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[tuple[str, ...]] = []
    end_sites: list[tuple[int, np.ndarray]] = []
    stack: list[int] = []          # joint index per open brace; -2 for an End Site block
    pending: int | None = None     # a joint (or -2) waiting for its '{'
    cur_end: list | None = None
    i = 0
    n = len(lines)
    # skip leading blank lines
    while i < n and not lines[i].strip():
        i += 1
    if i >= n:
        raise BVHError(path, 1, "empty file: expected 'HIERARCHY'")
    if lines[i].strip().upper() != "HIERARCHY":
        raise BVHError(path, i + 1, f"expected 'HIERARCHY', found {lines[i].strip()[:40]!r}")
    i += 1
    root_seen = False
    while i < n:
        raw = lines[i].strip()
        ln = i + 1
        i += 1
        if not raw:
            continue
        parts = raw.split()
        key = parts[0]
        if key == "MOTION":
            if stack:
                raise BVHError(path, ln, f"unbalanced braces: {len(stack)} block(s) still open "
                                         f"before MOTION (expected '}}')")
            if pending is not None:
                raise BVHError(path, ln, "expected '{' after the joint line before MOTION")
            if not names:
                raise BVHError(path, ln, "no ROOT joint in HIERARCHY")
            return dict(names=names, parents=parents, offsets=offsets, channels=channels,
                        end_sites=end_sites, offset_lines=offset_lines, end_lines=end_lines), i
        if pending is not None and key != "{":
            raise BVHError(path, ln, f"expected '{{' after joint line, found {raw[:40]!r}")
        if key in ("ROOT", "JOINT"):
            name = raw[len(key):].strip()
            if not name:
                raise BVHError(path, ln, f"{key} without a name")
            if key == "ROOT":
                if root_seen or stack:
                    raise BVHError(path, ln, "a second ROOT (only one skeleton per file is read)")
                root_seen = True
                parent = -1
            else:
                if not stack or stack[-1] < 0:
                    raise BVHError(path, ln, "JOINT outside a ROOT/JOINT block")
                parent = stack[-1]
            if name in index_of:
                raise BVHError(path, ln, f"duplicate joint name {name!r} "
                                         f"(first at joint {index_of[name]})")
            index_of[name] = len(names)
            names.append(name)
            offset_lines.append(0)
            parents.append(parent)
            offsets.append(None)  # type: ignore[arg-type]
            channels.append(None)  # type: ignore[arg-type]
            pending = len(names) - 1
        elif key == "End" and len(parts) >= 2 and parts[1] == "Site":
            if not stack or stack[-1] < 0:
                raise BVHError(path, ln, "End Site outside a joint block")
            pending = -2
            cur_end = [stack[-1], None, 0]
        elif key == "{":
            if pending is None:
                raise BVHError(path, ln, "unexpected '{' (no ROOT, JOINT or End Site before it)")
            stack.append(pending)
            pending = None
        elif key == "}":
            if not stack:
                raise BVHError(path, ln, "unbalanced braces: '}' with no open block")
            top = stack.pop()
            if top == -2:
                if cur_end is None or cur_end[1] is None:
                    raise BVHError(path, ln, "End Site without OFFSET")
                end_sites.append((cur_end[0], cur_end[1]))
                end_lines.append(cur_end[2])
                cur_end = None
            else:
                if offsets[top] is None:
                    raise BVHError(path, ln, f"joint {names[top]!r} has no OFFSET")
                if channels[top] is None:
                    channels[top] = ()
        elif key == "OFFSET":
            if not stack:
                raise BVHError(path, ln, "OFFSET outside a block")
            try:
                vals = [float(v) for v in parts[1:]]
            except (ValueError, OverflowError):
                raise BVHError(path, ln, f"OFFSET needs 3 numbers, found {' '.join(parts[1:])!r}") from None
            if len(vals) != 3 or not all(map(math.isfinite, vals)):
                raise BVHError(path, ln, f"OFFSET needs 3 finite numbers, found {len(vals)}: "
                                         f"{' '.join(parts[1:])!r}")
            if stack[-1] == -2:
                cur_end[1] = np.array(vals)  # type: ignore[index]
                cur_end[2] = ln  # type: ignore[index]
            else:
                offsets[stack[-1]] = vals
                offset_lines[stack[-1]] = ln
        elif key == "CHANNELS":
            if not stack or stack[-1] < 0:
                raise BVHError(path, ln, "CHANNELS outside a joint block")
            try:
                count = int(parts[1])
            except (IndexError, ValueError, OverflowError):
                raise BVHError(path, ln, "CHANNELS needs a count, e.g. 'CHANNELS 3 Zrotation "
                                         "Yrotation Xrotation'") from None
            chans = tuple(parts[2:])
            if len(chans) != count:
                raise BVHError(path, ln, f"CHANNELS says {count} but lists {len(chans)} names")
            for c in chans:
                if c not in KNOWN_CHANNELS:
                    raise BVHError(path, ln, f"unknown channel name {c!r}; expected one of "
                                             f"{sorted(KNOWN_CHANNELS)}")
            rot = [c for c in chans if c in ROTATION_CHANNELS]
            pos = [c for c in chans if c in POSITION_CHANNELS]
            if len(set(chans)) != len(chans) or len(rot) not in (0, 3) or len(pos) not in (0, 3):
                raise BVHError(path, ln, f"CHANNELS must list 0 or 3 distinct rotations and 0 or "
                                         f"3 distinct positions, found {list(chans)}")
            channels[stack[-1]] = chans
        else:
            raise BVHError(path, ln, f"unexpected {raw[:40]!r} in HIERARCHY; expected ROOT, JOINT, "
                                     f"End Site, OFFSET, CHANNELS, braces or MOTION")
    if stack or pending is not None:
        raise BVHError(path, n, f"unbalanced braces: file ends with {len(stack)} block(s) open")
    raise BVHError(path, n, "no MOTION section (file ends inside HIERARCHY)")


def _tokens_per_line(data: bytes, n_lines: int) -> np.ndarray:
    """Number of whitespace-separated tokens on each line, vectorised over bytes."""
    b = np.frombuffer(data, dtype=np.uint8)
    if b.size == 0:
        return np.zeros(n_lines, dtype=np.int64)
    # the separators are exactly those of bytes.split(), which makes the tokens
    nl = b == 10
    sep = nl | (b == 32) | (b == 9) | (b == 13) | (b == 11) | (b == 12)
    start = ~sep
    start[1:] &= sep[:-1]
    line_of = np.searchsorted(np.flatnonzero(nl), np.flatnonzero(start))  # line of each token
    return np.bincount(line_of, minlength=n_lines)[:n_lines]


def _parse_motion(lines: list[str], start: int, n_channels: int, path):
    """Frames, frame time (number and text as written), the (F, C) value array and the
    0-based index of the first frame line, from the MOTION block."""
    i = start
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise BVHError(path, i, "MOTION block is empty: expected 'Frames: N'")
    m = _FRAMES_RE.match(lines[i].strip())
    if m is None:
        raise BVHError(path, i + 1, f"expected 'Frames: N', found {lines[i].strip()[:40]!r}")
    val = m.group(1).strip()
    try:
        n_frames = int(val)
    except (ValueError, OverflowError):
        raise BVHError(path, i + 1, f"'Frames:' needs a whole number, found {val!r}") from None
    if n_frames < 0:
        raise BVHError(path, i + 1, f"'Frames:' must not be negative, found {n_frames}")
    if n_frames == 0:
        raise BVHError(path, i + 1, "'Frames: 0': a clip needs at least one frame")
    i += 1
    while i < len(lines) and not lines[i].strip():
        i += 1
    m = _FRAME_TIME_RE.match(lines[i].strip()) if i < len(lines) else None
    if m is None:
        raise BVHError(path, min(i + 1, len(lines)), "missing 'Frame Time: seconds' after 'Frames:'")
    val = m.group(1).strip()
    try:
        frame_time = float(val)
    except (ValueError, OverflowError):
        raise BVHError(path, i + 1, f"'Frame Time:' needs a number of seconds, found {val!r}") from None
    lo, hi = FPS_RANGE
    if not (np.isfinite(frame_time) and 1.0 / hi <= frame_time <= 1.0 / lo):
        raise BVHError(path, i + 1, f"'Frame Time:' must be a positive number of seconds between "
                                    f"{1.0 / hi:g} and {1.0 / lo:g} ({lo:g} to {hi:g} frames per "
                                    f"second), found {val[:40]!r}")
    first = i + 1  # 0-based index of the first data line
    data_lines = lines[first:]
    # drop trailing blank lines
    k = len(data_lines)
    while k > 0 and not data_lines[k - 1].strip():
        k -= 1
    data_lines = data_lines[:k]
    if len(data_lines) < n_frames:
        raise BVHError(path, first + len(data_lines) + 1,
                       f"truncated MOTION block: 'Frames: {n_frames}' but the file ends after "
                       f"{len(data_lines)} frame line(s)")
    if len(data_lines) > n_frames:
        raise BVHError(path, first + n_frames + 1,
                       f"{len(data_lines)} frame lines but 'Frames: {n_frames}' "
                       f"(more data than the header declares)")
    values = _fast_values(data_lines, n_frames, n_channels)
    if values is None:
        values = _checked_values(data_lines, n_frames, n_channels, first, path)
    finite = np.isfinite(values)
    if not finite.all():
        f, c = np.argwhere(~finite)[0]
        raise BVHError(path, first + int(f) + 1, f"non-finite value {values[f, c]!r} in frame "
                                                 f"{int(f) + 1}, channel {int(c) + 1} (NaN/inf "
                                                 f"are not valid motion data)")
    return n_frames, frame_time, val, values, first


def _fast_values(data_lines: list[str], n_frames: int, n_channels: int) -> np.ndarray | None:
    """The (F, C) frame values through numpy's C text reader, or ``None`` whenever the
    block is anything but plain ASCII numbers, ``n_channels`` on every one of the
    ``n_frames`` lines: :func:`_checked_values` then reads it again and names the
    problem.  ``np.loadtxt`` skips blank lines, so a blank line inside the block shows
    up as a missing row (and takes the checked path)."""
    if n_channels == 0:
        return None
    block = "\n".join(data_lines)
    # loadtxt also splits at \x1c-\x1f (and non-ASCII spaces), bytes.split() does not
    if not block.isascii() or any(c in block for c in "\x1c\x1d\x1e\x1f"):
        return None
    try:
        values = np.loadtxt(data_lines, dtype=np.float64, comments=None, ndmin=2)
    except ValueError:
        return None
    if values.shape != (n_frames, n_channels):
        return None
    return values


def _checked_values(data_lines: list[str], n_frames: int, n_channels: int, first: int,
                    path) -> np.ndarray:
    """The (F, C) frame values, token by token, raising :class:`BVHError` at the first
    line with the wrong number of values or a non-numeric one."""
    data = "\n".join(data_lines).encode("ascii", "replace")  # one byte per character
    counts = _tokens_per_line(data, len(data_lines))
    bad = np.nonzero(counts != n_channels)[0]
    if bad.size:
        b = int(bad[0])
        raise BVHError(path, first + b + 1, f"wrong number of values on a frame line: expected "
                                            f"{n_channels} (the CHANNELS of the hierarchy), "
                                            f"found {int(counts[b])}")
    tokens = data.split()  # same separators as the count above, so F * C tokens
    try:
        values = np.array(tokens, dtype=np.float64)
    except ValueError:
        for j, tok in enumerate(tokens):  # error path only: find the culprit
            try:
                float(tok)
            except ValueError:
                line = first + j // n_channels + 1
                raise BVHError(path, line, f"non-numeric value {tok.decode('ascii')!r} in frame "
                                           f"{j // n_channels + 1}, channel {j % n_channels + 1}") from None
        raise
    return values.reshape(n_frames, n_channels)


def guess_scale(skeleton: Skeleton) -> tuple[float, str]:
    """Guess file units → metres from the size of the rest skeleton.

    The rest pose of every file we know is standing (T- or A-pose), so its largest
    extent (height, or arm span in a T-pose) is about an adult's height.  The unit
    whose conversion puts it closest to 1.70 m (in log scale) wins."""
    P = skeleton.rest_positions()
    pts = [P]
    if skeleton.end_sites:
        pts.append(np.array([P[p] + o for p, o in skeleton.end_sites]))
    pts = np.concatenate(pts)
    extent = float(np.max(pts.max(0) - pts.min(0)))
    if extent <= 0:
        return 1.0, "m (skeleton has no extent; assumed)"
    best = min(UNIT_CANDIDATES, key=lambda u: abs(np.log(extent * u[0] / STANDING_HEIGHT_M)))
    return best[0], best[1]


def _header_fps(frame_time: float, text: str) -> float:
    """Frames per second from the header's Frame Time.

    Headers store a rounded frame time (".0083333", ".016667"): snap to the whole rate
    it stands for, but only when that rate's frame time rounds to the digits written
    (so a frame time written with 10 decimals for 119.99 fps stays 119.99)."""
    fps = 1.0 / frame_time
    whole = round(fps)
    if whole < 1 or abs(fps - whole) >= 2e-4 * fps:
        return fps
    try:
        half_unit = 0.5 * 10.0 ** Decimal(text).as_tuple().exponent
    except (InvalidOperation, TypeError, ValueError):
        return fps
    if abs(frame_time - 1.0 / whole) <= half_unit * (1 + 1e-9):
        return float(whole)
    return fps


def _euler_to_quat(values: np.ndarray, orders: list[str], col_of: list[list[int]]) -> np.ndarray:
    """(F,J,4) quaternions (scipy's x, y, z, w) from Euler channels in degrees.

    BVH angles are intrinsic, in the order the CHANNELS line lists them:
    ``Rotation.from_euler(order.upper(), angles, degrees=True)``, one scipy call per
    distinct order for all frames and joints with that order at once.  The angles go
    in as an (F, Jg, 3) array, not flattened to (F*Jg, 3): scipy (1.17+, N-d
    rotations) hands N-dimensional input to its vectorised numpy backend, several times
    faster than its Cython loop over 2-D input, with the same quaternions
    (``tests/test_fast_paths.py`` checks both against each other on the shared files)."""
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


def _check_fps(fps, field: str = "fps") -> float:
    """A frame rate given by the caller, in :data:`FPS_RANGE`."""
    try:
        v = float(fps)
    except (TypeError, ValueError):
        v = float("nan")
    lo, hi = FPS_RANGE
    if not (np.isfinite(v) and lo <= v <= hi):
        raise FlipstudyValueError(f"{field}: expected a frame rate between {lo:g} and {hi:g} frames "
                                  f"per second, got {fps!r}")
    return v


def load_bvh(path, scale: float | None = None, fps: float | None = None,
             drop_tpose: bool | str = "auto") -> Clip:
    """Read a BVH file into a :class:`Clip` in metres.

    Parameters
    ----------
    path : file path.
    scale : metres per file unit; ``None`` guesses it from the skeleton's size.
    fps : frames per second, overriding the header's Frame Time.
    drop_tpose : ``"auto"`` drops a calibration T-pose first frame (raw CMU);
        ``True`` always drops frame 0, ``False`` never.

    Example
    -------
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
    raw = _read_regular_file(path)
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark is not part of 'HIERARCHY'
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if not text.strip():
        raise BVHError(path, 1, "empty file: expected 'HIERARCHY'")
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    h, motion_at = _parse_hierarchy(lines, path)
    n_frames, frame_time, frame_time_text, values, first = _parse_motion(
        lines, motion_at, sum(len(c) for c in h["channels"]), path)

    names, parents, channels = h["names"], h["parents"], h["channels"]
    J = len(names)
    offsets = np.array(h["offsets"], dtype=np.float64)
    # channel columns
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
    meta: dict = {"name": path.stem, "path": str(path), "warnings": [], "dropped_frames": []}
    skel = None
    if scale is None:
        rest_offsets = offsets.copy()
        rest_offsets[0] = 0.0       # root_pos carries the root's position (see below)
        skel = Skeleton(names, parents, rest_offsets, channels, h["end_sites"])
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

    # translations: root and any other joint with position channels
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
    meta["root_convention"] = conventions.get(names[0], "no position channels (OFFSET only)")
    meta["file_root_offset"] = offsets[0].tolist()
    offsets[0] = 0.0  # root_pos is absolute from here on

    if skel is None:
        skel = Skeleton(names, parents, offsets, channels, h["end_sites"])
    meta["scale"] = s
    header_fps = _header_fps(frame_time, frame_time_text)
    meta["header_fps"] = header_fps
    meta["header_frame_time"] = frame_time
    if fps is not None:
        fps = _check_fps(fps)
        meta["fps_source"] = "given"
    else:
        fps = header_fps
        meta["fps_source"] = "header"
    if s != 1.0:  # the same as Clip.scaled(s), without building the clip twice
        skel = skel.scaled(s)
        root_pos = root_pos * s
        joint_pos = None if joint_pos is None else joint_pos * s
    return Clip(skel, fps, root_pos, q, joint_pos, meta)


# --------------------------------------------------------------------- writing
def _fmt(x: float) -> str:
    s = f"{x:.9f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def bvh_text(clip: Clip, scale: float = 1.0) -> str:
    """The BVH text of a clip; lengths are written as metres / ``scale``."""
    sk = clip.skeleton
    J = sk.num_joints
    inv = 1.0 / scale
    jp = clip.joint_pos
    if jp is None:
        # joints other than the root may declare position channels yet hold their OFFSET
        jp = np.broadcast_to(sk.offsets[None], (clip.num_frames, J, 3))
    offsets = sk.offsets * inv
    # joints with position channels: write OFFSET = frame 1 and absolute channels,
    # which the reader's rule reads back unambiguously
    has = sk.has_position.copy()
    has[0] = False
    offsets[has] = jp[0, has] * inv
    # the root: a clip's root_pos is its world position (the skeleton's root offset plays
    # no part in forward kinematics), so write OFFSET 0 + absolute channels; a root without
    # position channels can only carry a fixed position, in its OFFSET
    if sk.has_position[0]:
        offsets[0] = 0.0
    else:
        if not np.allclose(clip.root_pos, clip.root_pos[:1], rtol=0, atol=1e-9):
            raise ValueError("bvh_text: the root moves but has no position channels; give it "
                             "Xposition Yposition Zposition channels before writing")
        offsets[0] = clip.root_pos[0] * inv
    children: list[list[int]] = [[] for _ in range(J)]
    for j in range(1, J):
        children[sk.parents[j]].append(j)
    # the writer walks depth-first, which must reproduce the stored topological order
    dfs: list[int] = []
    todo = [0]
    while todo:
        j = todo.pop()
        dfs.append(j)
        todo.extend(reversed(children[j]))
    if dfs != list(range(J)):
        raise ValueError("bvh_text: skeleton joints are not in depth-first order; "
                         "reorder the skeleton before writing")
    ends: list[list[np.ndarray]] = [[] for _ in range(J)]
    for p, o in sk.end_sites:
        ends[p].append(o * inv)
    out = ["HIERARCHY"]

    def emit(j: int, depth: int):
        ind = "\t" * depth
        out.append(f"{ind}{'ROOT' if j == 0 else 'JOINT'} {sk.joint_names[j]}")
        out.append(f"{ind}{{")
        out.append(f"{ind}\tOFFSET {' '.join(_fmt(v) for v in offsets[j])}")
        if sk.channels[j]:
            out.append(f"{ind}\tCHANNELS {len(sk.channels[j])} {' '.join(sk.channels[j])}")
        for c in children[j]:
            emit(c, depth + 1)
        for o in ends[j]:
            out.append(f"{ind}\tEnd Site")
            out.append(f"{ind}\t{{")
            out.append(f"{ind}\t\tOFFSET {' '.join(_fmt(v) for v in o)}")
            out.append(f"{ind}\t}}")
        out.append(f"{ind}}}")

    emit(0, 0)
    F = clip.num_frames
    cols = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gimbal-lock warnings: the angles stay valid
        rots = {}
        for order in set(sk.euler_orders):
            if order:
                js = [j for j in range(J) if sk.euler_orders[j] == order]
                e = Rotation.from_quat(clip.rotations[:, js].reshape(-1, 4)).as_euler(order.upper(), degrees=True)
                e = np.unwrap(e.reshape(F, len(js), 3), period=360.0, axis=0)
                for k, j in enumerate(js):
                    rots[j] = e[:, k]
    for j in range(J):
        order = sk.euler_orders[j]
        for ch in sk.channels[j]:
            axis = "XYZ".index(ch[0])
            if ch in POSITION_CHANNELS:
                src = clip.root_pos if j == 0 else jp[:, j]
                cols.append(src[:, axis] * inv)
            else:
                cols.append(rots[j][:, order.index(ch[0])])
    data = np.stack(cols, axis=1) if cols else np.zeros((F, 0))
    data[np.abs(data) < 5e-10] = 0.0
    fmt = " ".join("%.9f" if ch in POSITION_CHANNELS else "%.7f"
                   for ch in (c for chs in sk.channels for c in chs))
    body = "\n".join(fmt % tuple(row) for row in data)
    out.append("MOTION")
    out.append(f"Frames: {F}")
    out.append(f"Frame Time: {1.0 / clip.fps:.10f}")
    return "\n".join(out) + "\n" + body + "\n"


def save_bvh(clip: Clip, path, scale: float = 1.0) -> Path:
    """Write a clip as BVH (atomically).  Lengths are written in units of ``scale``
    metres (1.0: metres, 0.01: centimetres).  Euler orders and channel layout are
    the skeleton's; the root OFFSET is zero and its channels absolute (a root without
    position channels must stand still: its position is written as its OFFSET).

    Example
    -------
    >>> import tempfile, pathlib
    >>> from flipstudy import builtin, save_bvh
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = save_bvh(builtin("backflip"), pathlib.Path(tmp) / "backflip.bvh", scale=0.01)
    ...     text = path.read_text()
    >>> text.splitlines()[:2]
    ['HIERARCHY', 'ROOT Hips']
    >>> "Frames: 397" in text
    True
    """
    atomic_write_text(path, bvh_text(clip, scale))
    return Path(path)

"""The text of a BVH file: its HIERARCHY read into skeleton tables and its MOTION
block into one (F, C) array of numbers, every malformed line refused with a
:class:`BVHError` naming the file, the line and what was expected.

:func:`flipstudy.stimuli.motion.bvh.load_bvh` turns these tables into a clip.

>>> lines = ["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0 0 0",
...          "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
...          "  End Site", "  {", "    OFFSET 0 10 0", "  }", "}",
...          "MOTION", "Frames: 2", "Frame Time: 0.0333333", "0 90 0 0 0 0", "0 91 0 0 0 5"]
>>> h, at = parse_hierarchy(lines, "tiny.bvh")
>>> h["names"], h["channels"][0][3:]
(['Hips'], ('Zrotation', 'Xrotation', 'Yrotation'))
>>> n_frames, frame_time, text, values, first = parse_motion(lines, at, 6, "tiny.bvh")
>>> n_frames, text, values[1].tolist(), first
(2, '0.0333333', [0.0, 91.0, 0.0, 0.0, 0.0, 5.0], 13)
>>> parse_motion(lines[:-1], at, 6, "tiny.bvh")
Traceback (most recent call last):
...
flipstudy.errors.BVHError: tiny.bvh, line 15: truncated MOTION block: 'Frames: 2' but the file ends after 1 frame line(s)
"""
from __future__ import annotations

import math
import re

import numpy as np

from flipstudy.errors import BVHError
from ._bvh_units import FPS_RANGE
from .skeleton import POSITION_CHANNELS, ROTATION_CHANNELS

KNOWN_CHANNELS = set(POSITION_CHANNELS) | set(ROTATION_CHANNELS)

_FRAMES_RE = re.compile(r"Frames\s*:\s*(.*)\Z", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"Frame\s+Time\s*:\s*(.*)\Z", re.IGNORECASE)


def parse_hierarchy(lines: list[str], path) -> tuple[dict, int]:
    """Parse HIERARCHY up to MOTION. Returns skeleton parts and the MOTION line index."""
    names: list[str] = []
    index_of: dict[str, int] = {}  # name -> joint: uniqueness checked in O(1)
    offset_lines: list[int] = []   # 1-based line of each joint's OFFSET
    end_lines: list[int] = []      # 1-based line of each End Site's OFFSET
    channel_lines: dict[int, int] = {}   # joint → 1-based line of its CHANNELS
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
                if cur_end[1] is not None:  # type: ignore[index]
                    raise BVHError(path, ln, f"a second OFFSET in one End Site (the first at line "
                                             f"{cur_end[2]}); a block has exactly one")  # type: ignore[index]
                cur_end[1] = np.array(vals)  # type: ignore[index]
                cur_end[2] = ln  # type: ignore[index]
            else:
                if offsets[stack[-1]] is not None:
                    raise BVHError(path, ln, f"a second OFFSET for joint {names[stack[-1]]!r} (the first "
                                             f"at line {offset_lines[stack[-1]]}); a joint has exactly one")
                offsets[stack[-1]] = vals
                offset_lines[stack[-1]] = ln
        elif key == "CHANNELS":
            if not stack or stack[-1] < 0:
                raise BVHError(path, ln, "CHANNELS outside a joint block")
            if stack[-1] in channel_lines:
                raise BVHError(path, ln, f"a second CHANNELS for joint {names[stack[-1]]!r} (the first "
                                         f"at line {channel_lines[stack[-1]]}); a joint has at most one")
            channel_lines[stack[-1]] = ln
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


def tokens_per_line(data: bytes, n_lines: int) -> np.ndarray:
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


def parse_motion(lines: list[str], start: int, n_channels: int, path):
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
    values = fast_values(data_lines, n_frames, n_channels)
    if values is None:
        values = checked_values(data_lines, n_frames, n_channels, first, path)
    finite = np.isfinite(values)
    if not finite.all():
        f, c = np.argwhere(~finite)[0]
        toks = data_lines[f].split()                  # the value as the file writes it
        shown = toks[c] if c < len(toks) else str(float(values[f, c]))
        raise BVHError(path, first + int(f) + 1, f"non-finite value '{shown}' in frame "
                                                 f"{int(f) + 1}, channel {int(c) + 1} (NaN/inf "
                                                 f"are not valid motion data)")
    return n_frames, frame_time, val, values, first


def fast_values(data_lines: list[str], n_frames: int, n_channels: int) -> np.ndarray | None:
    """The (F, C) frame values through numpy's C text reader, or ``None`` whenever the
    block is anything but plain ASCII numbers, ``n_channels`` on every one of the
    ``n_frames`` lines: :func:`checked_values` then reads it again and names the
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


def checked_values(data_lines: list[str], n_frames: int, n_channels: int, first: int,
                    path) -> np.ndarray:
    """The (F, C) frame values, token by token, raising :class:`BVHError` at the first
    line with the wrong number of values or a non-numeric one."""
    data = "\n".join(data_lines).encode("ascii", "replace")  # one byte per character
    counts = tokens_per_line(data, len(data_lines))
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


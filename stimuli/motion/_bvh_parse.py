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
    h = _Hierarchy(path)
    while i < n:
        raw = lines[i].strip()
        ln = i + 1
        i += 1
        if not raw:
            continue
        parts = raw.split()
        key = parts[0]
        if key == "MOTION":
            return h.finished(ln), i
        if h.pending is not None and key != "{":
            raise BVHError(path, ln, f"expected '{{' after joint line, found {raw[:40]!r}")
        if key in ("ROOT", "JOINT"):
            h.joint(key, raw, ln)
        elif key == "End" and len(parts) >= 2 and parts[1] == "Site":
            h.end_site(ln)
        elif key == "{":
            h.open(ln)
        elif key == "}":
            h.close(ln)
        elif key == "OFFSET":
            h.offset(parts, ln)
        elif key == "CHANNELS":
            h.channel_line(parts, ln)
        else:
            raise BVHError(path, ln, f"unexpected {raw[:40]!r} in HIERARCHY; expected ROOT, JOINT, "
                                     f"End Site, OFFSET, CHANNELS, braces or MOTION")
    if h.stack or h.pending is not None:
        raise BVHError(path, n, f"unbalanced braces: file ends with {len(h.stack)} block(s) open")
    raise BVHError(path, n, "no MOTION section (file ends inside HIERARCHY)")


class _Hierarchy:
    """The state of :func:`parse_hierarchy` between lines: the joints read so far and
    the open blocks; one method per kind of line, each raising :class:`BVHError` with
    the line."""

    def __init__(self, path):
        self.path = path
        self.names: list[str] = []
        self.index_of: dict[str, int] = {}  # name -> joint: uniqueness checked in O(1)
        self.offset_lines: list[int] = []   # 1-based line of each joint's OFFSET
        self.end_lines: list[int] = []      # 1-based line of each End Site's OFFSET
        self.channel_lines: dict[int, int] = {}   # joint → 1-based line of its CHANNELS
        self.parents: list[int] = []
        self.offsets: list[list[float]] = []
        self.channels: list[tuple[str, ...]] = []
        self.end_sites: list[tuple[int, np.ndarray]] = []
        self.stack: list[int] = []          # joint index per open brace; -2 for an End Site block
        self.pending: int | None = None     # a joint (or -2) waiting for its '{'
        self.cur_end: list | None = None
        self.root_seen = False

    def finished(self, ln: int) -> dict:
        """At MOTION: the skeleton parts, checked complete."""
        path, stack = self.path, self.stack
        if stack:
            raise BVHError(path, ln, f"unbalanced braces: {len(stack)} block(s) still open "
                                     f"before MOTION (expected '}}')")
        if self.pending is not None:
            raise BVHError(path, ln, "expected '{' after the joint line before MOTION")
        if not self.names:
            raise BVHError(path, ln, "no ROOT joint in HIERARCHY")
        return dict(names=self.names, parents=self.parents, offsets=self.offsets,
                    channels=self.channels, end_sites=self.end_sites,
                    offset_lines=self.offset_lines, end_lines=self.end_lines)

    def joint(self, key: str, raw: str, ln: int) -> None:
        """A ROOT or JOINT line."""
        path, stack = self.path, self.stack
        name = raw[len(key):].strip()
        if not name:
            raise BVHError(path, ln, f"{key} without a name")
        if key == "ROOT":
            if self.root_seen or stack:
                raise BVHError(path, ln, "a second ROOT (only one skeleton per file is read)")
            self.root_seen = True
            parent = -1
        else:
            if not stack or stack[-1] < 0:
                raise BVHError(path, ln, "JOINT outside a ROOT/JOINT block")
            parent = stack[-1]
        if name in self.index_of:
            raise BVHError(path, ln, f"duplicate joint name {name!r} "
                                     f"(first at joint {self.index_of[name]})")
        self.index_of[name] = len(self.names)
        self.names.append(name)
        self.offset_lines.append(0)
        self.parents.append(parent)
        self.offsets.append(None)  # type: ignore[arg-type]
        self.channels.append(None)  # type: ignore[arg-type]
        self.pending = len(self.names) - 1

    def end_site(self, ln: int) -> None:
        """An End Site line."""
        if not self.stack or self.stack[-1] < 0:
            raise BVHError(self.path, ln, "End Site outside a joint block")
        self.pending = -2
        self.cur_end = [self.stack[-1], None, 0]

    def open(self, ln: int) -> None:
        """A '{'."""
        if self.pending is None:
            raise BVHError(self.path, ln, "unexpected '{' (no ROOT, JOINT or End Site before it)")
        self.stack.append(self.pending)
        self.pending = None

    def close(self, ln: int) -> None:
        """A '}': the block's joint (or End Site) checked complete."""
        path = self.path
        if not self.stack:
            raise BVHError(path, ln, "unbalanced braces: '}' with no open block")
        top = self.stack.pop()
        if top == -2:
            cur_end = self.cur_end
            if cur_end is None or cur_end[1] is None:
                raise BVHError(path, ln, "End Site without OFFSET")
            self.end_sites.append((cur_end[0], cur_end[1]))
            self.end_lines.append(cur_end[2])
            self.cur_end = None
        else:
            if self.offsets[top] is None:
                raise BVHError(path, ln, f"joint {self.names[top]!r} has no OFFSET")
            if self.channels[top] is None:
                self.channels[top] = ()

    def offset(self, parts: list[str], ln: int) -> None:
        """An OFFSET line (of a joint or an End Site)."""
        path, stack, cur_end = self.path, self.stack, self.cur_end
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
            if self.offsets[stack[-1]] is not None:
                raise BVHError(path, ln, f"a second OFFSET for joint {self.names[stack[-1]]!r} (the first "
                                         f"at line {self.offset_lines[stack[-1]]}); a joint has exactly one")
            self.offsets[stack[-1]] = vals
            self.offset_lines[stack[-1]] = ln

    def channel_line(self, parts: list[str], ln: int) -> None:
        """A CHANNELS line."""
        path, stack = self.path, self.stack
        if not stack or stack[-1] < 0:
            raise BVHError(path, ln, "CHANNELS outside a joint block")
        if stack[-1] in self.channel_lines:
            raise BVHError(path, ln, f"a second CHANNELS for joint {self.names[stack[-1]]!r} (the first "
                                     f"at line {self.channel_lines[stack[-1]]}); a joint has at most one")
        self.channel_lines[stack[-1]] = ln
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
        self.channels[stack[-1]] = chans


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


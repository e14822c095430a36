"""Study designs as data (TOML).

A design names the base clips, the error groups (kind, profile, sign, levels),
how often each motion is shown, the reference (practice) clips, the frame rate
and the seed.  ``PAPER_DESIGN`` is the study of Majkowska & Faloutsos 2007,
Section 7: forward and backward somersaults; smooth and abrupt angular-momentum
increases and decreases at 0/17/25/37/50 %; take-off angle increases at
0/10/20/30/40 %; each motion shown twice.

Every invalid field raises :class:`DesignError` naming the field.
"""

from __future__ import annotations

from .exceptions import FlipstudyError
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from .errors import COM_POLICIES, KINDS, PROFILES


class DesignError(FlipstudyError, ValueError):
    """An invalid study design; the message names the file and field."""


@dataclass
class ClipSpec:
    name: str
    source: str                 # built-in name or BVH path (relative to the design file)
    scale: float | None = None  # metres per file unit (BVH); None: guess
    fps: float | None = None    # override the file's frame rate (BVH)
    flips: int | None = None    # turn the clip into an N-flip one first (flipstudy edit)
    k_ratio: float = 0.7        # its retiming factor as a fraction of k*


@dataclass
class Group:
    name: str
    kind: str                   # "angular-momentum" | "takeoff-angle"
    profile: str | None         # "smooth" | "abrupt" (angular momentum only)
    sign: int                   # +1 increase, -1 decrease
    levels: list[float]         # nominal error in percent (magnitude; 0 = original)


@dataclass
class Design:
    name: str
    seed: int
    fps: float
    repetitions: int
    total_mass: float
    clips: list[ClipSpec]
    groups: list[Group]
    reference: list[str] = field(default_factory=list)
    com_policy: str = "angle"
    tolerance_pct: float = 1.0        # refuse stimuli whose measured error misses by more
    replay: bool = False              # may a participant replay a motion (sessions)
    break_every: int = 40             # trials between breaks (sessions)
    path: Path | None = None

    def clip(self, name: str) -> ClipSpec:
        for c in self.clips:
            if c.name == name:
                return c
        raise KeyError(name)


PAPER_DESIGN = """\
# The perception study of Majkowska & Faloutsos 2007 ("Flipping with Physics"), Section 7.
# Forward and backward single somersaults; angular-momentum errors (smooth/abrupt,
# increase/decrease) and take-off angle errors. Level = nominal error in percent,
# 0 = the original motion. Each motion is shown `repetitions` times.

[study]
name = "flipping-with-physics-2007"
seed = 20070803
fps = 120                 # frame rate of the generated stimuli
repetitions = 2           # each motion shown twice
total_mass = 70.0         # kg, for the body model
com_policy = "angle"      # AM errors keep the take-off angle ("landing": keep the landing point)
tolerance_pct = 1.0       # refuse a stimulus whose measured error misses the nominal by more
replay = false            # participants may not replay a motion
break_every = 40          # a break every 40 trials

# Base clips: a built-in name (backflip, frontflip, jump) or a BVH path relative to
# this file, with optional scale (metres per file unit) and fps (override the header),
# and optional flips = N (and k_ratio, default 0.7) to study the multi-flip method's
# own output: the clip is first made an N-flip one, as `flipstudy edit --flips N` does.
[[clips]]
name = "backflip"
source = "backflip"

[[clips]]
name = "frontflip"
source = "frontflip"

# Reference examples (original, correct motions) shown before the test trials.
[reference]
clips = ["backflip", "frontflip"]

[[groups]]
name = "smooth-increase"
kind = "angular-momentum"
profile = "smooth"
sign = 1
levels = [0, 17, 25, 37, 50]

[[groups]]
name = "smooth-decrease"
kind = "angular-momentum"
profile = "smooth"
sign = -1
levels = [0, 17, 25, 37, 50]

[[groups]]
name = "abrupt-increase"
kind = "angular-momentum"
profile = "abrupt"
sign = 1
levels = [0, 17, 25, 37, 50]

[[groups]]
name = "abrupt-decrease"
kind = "angular-momentum"
profile = "abrupt"
sign = -1
levels = [0, 17, 25, 37, 50]

[[groups]]
name = "takeoff-increase"
kind = "takeoff-angle"
sign = 1
levels = [0, 10, 20, 30, 40]
"""


def _get(d: dict, key: str, typ, where: str, default=..., check=None):
    if key not in d:
        if default is ...:
            raise DesignError(f"{where}: missing field '{key}'")
        return default
    v = d[key]
    if typ is float and isinstance(v, int) and not isinstance(v, bool):
        v = float(v)
    if not isinstance(v, typ) or isinstance(v, bool) and typ is not bool:
        tname = typ.__name__ if isinstance(typ, type) else "/".join(t.__name__ for t in typ)
        raise DesignError(f"{where}.{key}: expected {tname}, got {v!r}")
    if check is not None:
        msg = check(v)
        if msg:
            raise DesignError(f"{where}.{key}: {msg}, got {v!r}")
    return v


def parse_design(text: str, path: Path | str = "<design>") -> Design:
    """Parse and validate a design (TOML text)."""
    src = str(path)
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DesignError(f"{src}: not valid TOML: {e}") from None
    unknown = set(d) - {"study", "clips", "groups", "reference"}
    if unknown:
        raise DesignError(f"{src}: unknown section(s) {sorted(unknown)}; expected study, clips, "
                          f"groups, reference")
    st = d.get("study")
    if not isinstance(st, dict):
        raise DesignError(f"{src}: missing [study] section")
    w = f"{src}: [study]"
    positive = lambda v: None if v > 0 else "must be positive"  # noqa: E731
    design = Design(
        name=_get(st, "name", str, w),
        seed=_get(st, "seed", int, w, check=lambda v: None if v >= 0 else "must be >= 0"),
        fps=_get(st, "fps", float, w, 120.0, positive),
        repetitions=_get(st, "repetitions", int, w, 2, positive),
        total_mass=_get(st, "total_mass", float, w, 70.0, positive),
        clips=[], groups=[],
        com_policy=_get(st, "com_policy", str, w, "angle",
                        lambda v: None if v in COM_POLICIES else f"must be one of {list(COM_POLICIES)}"),
        tolerance_pct=_get(st, "tolerance_pct", float, w, 1.0, positive),
        replay=_get(st, "replay", bool, w, False),
        break_every=_get(st, "break_every", int, w, 40, positive),
        path=Path(path) if str(path) != "<design>" else None,
    )
    clips = d.get("clips")
    if not isinstance(clips, list) or not clips:
        raise DesignError(f"{src}: [[clips]]: at least one base clip is needed")
    for i, c in enumerate(clips):
        wc = f"{src}: clips[{i}]"
        if not isinstance(c, dict):
            raise DesignError(f"{wc}: expected a table")
        design.clips.append(ClipSpec(
            name=_get(c, "name", str, wc, check=_name_ok),
            source=_get(c, "source", str, wc),
            scale=_get(c, "scale", float, wc, None, positive),
            fps=_get(c, "fps", float, wc, None, positive),
            flips=_get(c, "flips", int, wc, None,
                       lambda v: None if 1 <= v <= 6 else "expected a whole number of flips from 1 to 6"),
            k_ratio=_get(c, "k_ratio", float, wc, 0.7,
                         lambda v: None if 0.2 <= v <= 2 else "expected a fraction of k* from 0.2 to 2")))
    names = [c.name for c in design.clips]
    if len(set(names)) != len(names):
        raise DesignError(f"{src}: clips: duplicate clip names {sorted({n for n in names if names.count(n) > 1})}")
    groups = d.get("groups")
    if not isinstance(groups, list) or not groups:
        raise DesignError(f"{src}: [[groups]]: at least one error group is needed")
    for i, g in enumerate(groups):
        wg = f"{src}: groups[{i}]"
        if not isinstance(g, dict):
            raise DesignError(f"{wg}: expected a table")
        kind = _get(g, "kind", str, wg, check=lambda v: None if v in KINDS else f"must be one of {list(KINDS)}")
        profile = None
        if kind == "angular-momentum":
            profile = _get(g, "profile", str, wg,
                           check=lambda v: None if v in PROFILES else f"must be one of {list(PROFILES)}")
        elif "profile" in g:
            raise DesignError(f"{wg}.profile: only angular-momentum groups have a profile")
        sign = _get(g, "sign", int, wg, 1, lambda v: None if v in (1, -1) else "must be 1 or -1")
        levels = _get(g, "levels", list, wg)
        if not levels:
            raise DesignError(f"{wg}.levels: at least one level is needed")
        lv = []
        for v in levels:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0:
                raise DesignError(f"{wg}.levels: each level is a percentage >= 0, got {v!r}")
            lv.append(float(v))
        if len(set(lv)) != len(lv):
            raise DesignError(f"{wg}.levels: duplicate levels in {levels}")
        if kind == "angular-momentum" and sign < 0 and max(lv) >= 90:
            raise DesignError(f"{wg}.levels: a decrease of 90 % or more stops the rotation")
        design.groups.append(Group(_get(g, "name", str, wg, check=_name_ok), kind, profile, sign, sorted(lv)))
    gnames = [g.name for g in design.groups]
    if len(set(gnames)) != len(gnames):
        raise DesignError(f"{src}: groups: duplicate group names")
    ref = d.get("reference", {})
    if not isinstance(ref, dict):
        raise DesignError(f"{src}: [reference]: expected a table with 'clips'")
    design.reference = _get(ref, "clips", list, f"{src}: [reference]", [])
    for r in design.reference:
        if r not in names:
            raise DesignError(f"{src}: [reference].clips: {r!r} is not one of the clips {names}")
    return design


def _name_ok(v: str):
    import re
    return None if re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}", v) else \
        "must be 1-64 letters, digits, '_', '.', '-' (it names files)"


def load_design(path) -> Design:
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as e:
        raise DesignError(f"{p}: cannot read design: {e.strerror}") from None
    return parse_design(text, p)

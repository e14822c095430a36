"""Study designs as data (TOML).

A design names the base clips, the error groups (kind, profile, sign, levels),
how often each motion is shown, the reference (practice) clips, the frame rate
and the seed (the ``[study]`` table and the ones after it: what the stimuli are),
and how the sessions present them (the ``[session]`` table, read into
:class:`SessionSettings`: ``replay``, ``break_every``, ``max_dropped_pct``,
``repeat_dropped``; these change no stimulus).  ``PAPER_DESIGN`` is the study of Majkowska & Faloutsos 2007,
Section 7: forward and backward somersaults; smooth and abrupt angular-momentum
increases and decreases at 0/17/25/37/50 %; take-off angle increases at
0/10/20/30/40 %; each motion shown twice.  As in the paper (its Table 2 gives the
one original 72 % in all four angular-momentum groups and 63 % in the take-off
group), the angular-momentum groups share one original per base clip
(``original = "shared"``) and the take-off group has its own.

Designs are strict: an unknown key (``repetitons``) is refused with a
did-you-mean, every number is bounded, names, clips, references and levels are
not repeated; every invalid field raises :class:`DesignError` naming the file,
section and key and the value as written (levels in percent).

A group's ``levels`` may be a dense grid ``{from, to, step}`` (at most 401 levels);
``method = "quest+"`` makes it adaptive (the session picks each level with
QUEST+; its settings are :class:`~flipstudy.stimuli.groupkeys.QuestSpec`), and
``task = "2afc"`` (default ``[study] task``, itself "yes-no") shows each modified
motion beside its original (see :mod:`flipstudy.stimuli.groupkeys`).

Designs written before the ``[session]`` table held ``replay`` and
``break_every`` in ``[study]``; they are still read, the same way, with a
``FutureWarning`` that names the file and asks to move them to ``[session]``
(both places at once is refused).

>>> d = parse_design(PAPER_DESIGN)
>>> d.session
SessionSettings(replay=False, break_every=40, max_dropped_pct=10.0, repeat_dropped=False)
>>> d.repetitions, len(d.stimulus_names())
(2, 46)
"""

from __future__ import annotations

import difflib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from flipstudy.errors import DesignError
from ._designkeys import _between, _check_keys, _get, _pct, _show  # noqa: F401

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from .groupkeys import (GRID_MAX, LEVELS_MAX, METHODS, QUEST_KEYS, TASKS, QuestSpec,  # noqa: F401
                        parse_levels, parse_method_task, parse_quest)
from .ballistic import BALLISTIC_LEVEL_BOUNDS, KIND_OPTIONS
from .injection import COM_POLICIES, KINDS, PROFILES


@dataclass
class ClipSpec:
    name: str
    source: str                 # built-in name or BVH path (relative to the design file)
    scale: float | None = None  # metres per file unit (BVH); None: guess
    fps: float | None = None    # override the file's frame rate (BVH)
    flips: int | None = None    # turn the clip into an N-flip one first (flipstudy edit)
    k_ratio: float = 0.7        # its retiming factor as a fraction of k*
    accept_unphysical: bool = False  # build it although its gravity or height contradicts physics


@dataclass
class Group:
    name: str
    kind: str                   # "angular-momentum" | "takeoff-angle"
    profile: str | None         # "smooth" | "abrupt" (angular momentum only)
    sign: int                   # +1 increase, -1 decrease
    levels: list[float]         # nominal error in percent (magnitude; 0 = original)
    original: str = "own"       # "shared": its level 0 is the clip's shared original
    style: str | None = None    # character style of its stimuli (None: the study's)
    method: str = "constant"    # "constant" stimuli | "quest+" (adaptive over the levels)
    task: str = "yes-no"        # "yes-no" | "2afc" (original and modified, which was correct?)
    quest: QuestSpec | None = None   # a quest+ group's settings
    policy: str | None = None   # gravity: what stays ("takeoff-velocity" | "apex-height" | "flight-time")
    axis: str | None = None     # acceleration: "horizontal" | "vertical"
    span: str | None = None     # time-scale: "flight" | "whole"

    @property
    def adaptive(self) -> bool:
        """Does the session choose this group's levels (quest+)?"""
        return self.method == "quest+"

    def trial_levels(self) -> list[float]:
        """The levels its trials show: level 0 is a 2AFC group's comparison, not a trial
        level, and a shared original is shown as the group ``original``."""
        return [v for v in self.levels
                if v != 0 or (self.task == "yes-no" and (self.adaptive or self.original != "shared"))]


@dataclass(frozen=True)
class SessionSettings:
    """How the sessions present a design's stimuli: the design file's ``[session]``
    table.  None of these changes a stimulus; the session code in
    :mod:`flipstudy.study` reads them from ``design.session``."""

    replay: bool = False              # may a participant replay a motion before answering
    break_every: int = 40             # trials between breaks
    max_dropped_pct: float = 10.0     # web: flag a trial whose video dropped more % of its frames
    repeat_dropped: bool = False      # web: show the flagged trials once more at the end


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
    original: str = "shared"          # "shared": AM groups share one original per clip
    fps_given: bool = True            # [study] fps written: BVH clips are resampled to it
    path: Path | None = None
    session: SessionSettings = field(default_factory=SessionSettings)  # the [session] table
    style: str | None = None          # character style of every stimulus (None: the renderer's)
    task: str = "yes-no"              # [study] task: the groups' default task

    def style_of(self, group) -> str | None:
        """The character style of a group's stimuli (None: nothing chosen)."""
        return (getattr(group, "style", None) if group is not None else None) or self.style

    @property
    def styled(self) -> bool:
        """Does the design choose a character style anywhere (the manifest then
        has a ``style`` column)?"""
        return self.style is not None or any(g.style for g in self.groups)

    def clip(self, name: str) -> ClipSpec:
        for c in self.clips:
            if c.name == name:
                return c
        raise KeyError(name)

    @property
    def shares_original(self) -> bool:
        """Do some groups show the clip's shared original as their level 0?"""
        return any(g.original == "shared" and 0.0 in g.levels for g in self.groups)

    def stimulus_names(self) -> list[str]:
        """Every stimulus name, in manifest order (see :func:`flipstudy.stimuli.stimset.plan`)."""
        out = [f"{r}_reference" for r in self.reference]
        for c in self.clips:
            if self.shares_original:
                out.append(f"{c.name}_{SHARED_ORIGINAL_GROUP}")
            for g in self.groups:
                out += [f"{c.name}_{g.name}_{lv:g}" for lv in g.levels
                        if not (lv == 0 and g.original == "shared")]
        return out

    def n_test_stimuli(self) -> int:
        return len(self.stimulus_names()) - len(self.reference)

    @property
    def shows_shared_original(self) -> bool:
        """Are the shared originals trials of their own (group ``original``)?  Only a
        constant yes/no group that shares them asks about them on their own."""
        return any(g.original == "shared" and 0.0 in g.levels and not g.adaptive
                   and g.task == "yes-no" for g in self.groups)

    def trials_per_participant(self) -> int:
        """Test trials of one session: ``repetitions`` × clips × trial levels of each
        constant group (and the shared originals), plus ``trials`` of each quest+ group."""
        nc = len(self.clips)
        n = sum(g.quest.trials if g.adaptive else self.repetitions * nc * len(g.trial_levels())
                for g in self.groups)
        return n + (self.repetitions * nc if self.shows_shared_original else 0)


PAPER_DESIGN = """\
# The perception study of Majkowska & Faloutsos 2007 ("Flipping with Physics"), Section 7.
# Forward and backward single somersaults; angular-momentum errors (smooth/abrupt,
# increase/decrease) and take-off angle errors. Level = nominal error in percent,
# 0 = the original motion. Each motion is shown `repetitions` times.

[study]
name = "flipping-with-physics-2007"
seed = 20070803
fps = 120                 # frame rate of the stimuli (BVH clips are resampled to it)
repetitions = 2           # each motion shown twice (1 to 20)
total_mass = 70.0         # kg, for the body model
com_policy = "angle"      # AM errors keep the take-off angle ("landing": keep the landing point)
tolerance_pct = 1.0       # refuse a stimulus whose measured error misses the nominal by more
original = "shared"       # the angular-momentum groups share one original per clip, shown
                          # `repetitions` times; the take-off group has its own ("per-group":
                          # every group its own level 0, as a [[groups]] original = "own" does)

# How the sessions show the stimuli (changes no stimulus).
[session]
replay = false            # participants may not replay a motion
break_every = 40          # a break every 40 trials
max_dropped_pct = 10      # online (export-web): a trial whose video dropped more than 10 % of
                          # its frames is flagged in the data (playback_flagged)
repeat_dropped = false    # online: true shows each flagged trial once more after the last one

# Base clips: a built-in name (backflip, frontflip, jump) or a BVH path relative to
# this file, with optional scale (metres per file unit) and fps (override the header),
# and optional flips = N (and k_ratio, default 0.7) to study the multi-flip method's
# own output: the clip is first made an N-flip one, as `flipstudy edit --flips N` does.
# A clip whose apparent gravity or body height contradicts physics (wrong fps or scale)
# is refused, naming the fix; accept_unphysical = true builds it anyway (the manifest
# records it).
[[clips]]
name = "backflip"
source = "backflip"

[[clips]]
name = "frontflip"
source = "frontflip"

# Reference examples (original, correct motions) shown before the test trials.
[reference]
clips = ["backflip", "frontflip"]

""" + "".join(f"""[[groups]]
name = "{profile}-{'increase' if sign > 0 else 'decrease'}"
kind = "angular-momentum"
profile = "{profile}"
sign = {sign}
levels = [0, 17, 25, 37, 50]

""" for profile in ("smooth", "abrupt") for sign in (1, -1)) + """\
[[groups]]
name = "takeoff-increase"
kind = "takeoff-angle"
sign = 1
levels = [0, 10, 20, 30, 40]
"""


#: the keys each section may hold (anything else is refused with a did-you-mean)
STUDY_KEYS = ("name", "seed", "fps", "repetitions", "total_mass", "com_policy", "tolerance_pct",
              "original", "style", "task")
SESSION_KEYS = ("replay", "break_every", "max_dropped_pct", "repeat_dropped")
OLD_SESSION_KEYS = ("replay", "break_every")   # also read from [study], as designs wrote them before
CLIP_KEYS = ("name", "source", "scale", "fps", "flips", "k_ratio", "accept_unphysical")
GROUP_KEYS = ("name", "kind", "profile", "sign", "levels", "original", "style", "method", "task",
              "policy", "axis", "span", *QUEST_KEYS)
#: the character styles a design may choose (drawn by flipstudy.render.characters)
CHARACTER_STYLES = ("ellipsoids", "capsules", "stick", "point-light", "mannequin")
REFERENCE_KEYS = ("clips",)
SECTIONS = ("study", "session", "clips", "groups", "reference")
ORIGINAL_MODES = ("shared", "per-group")   # [study] original
GROUP_ORIGINAL = ("shared", "own")         # [[groups]] original
#: the group name of the shared original in the manifest and the responses
SHARED_ORIGINAL_GROUP = "original"
RESERVED_GROUP_NAMES = ("reference", SHARED_ORIGINAL_GROUP)

#: bounds of every number of a design (inclusive unless said otherwise)
MAX_SEED = 2 ** 63 - 1
FPS_RANGE = (10.0, 1000.0)
REPETITIONS_MAX = 20
MASS_RANGE = (20.0, 200.0)            # kg
TOLERANCE_MAX = 50.0                  # percent; the lower bound 0 is excluded
BREAK_EVERY_MAX = 10000
SCALE_RANGE = (1e-4, 100.0)           # metres per file unit (mm is 0.001, m is 1)
TRIALS_MAX = 3000                     # test trials per participant (repetitions × stimuli, quest+ trials)
#: level bounds in percent by (kind, sign): (largest magnitude, is it excluded)
LEVEL_BOUNDS = {("angular-momentum", 1): (500.0, False),    # |L| up to 6× the original
                ("angular-momentum", -1): (90.0, True),     # a decrease of 90 % stops the rotation
                ("takeoff-angle", 1): (100.0, False),       # horizontal velocity up to doubled
                ("takeoff-angle", -1): (100.0, True),       # −100 % leaves no horizontal velocity
                **BALLISTIC_LEVEL_BOUNDS}                   # gravity, velocities, ... pose rate
MAX_DESIGN_BYTES = 1_000_000


def _kind_options(g: dict, kind: str, sign: int, wg: str) -> dict:
    """The group keys ``policy`` / ``axis`` / ``span`` of its kind (refused on the
    other kinds), and the sign a pose-rate group must have."""
    key = KIND_OPTIONS.get(kind, (None,))[0]
    for other in ("policy", "axis", "span"):
        if other in g and other != key:
            owner = [k for k, v in KIND_OPTIONS.items() if v[0] == other][0]
            raise DesignError(f"{wg}.{other}: only {owner} groups have a{'n' if other[0] in 'a' else ''} "
                              f"{other}")
    if kind == "pose-rate" and sign != 1:
        raise DesignError(f"{wg}.sign: a pose-rate group's levels are poses per second; its sign is 1")
    if key is None:
        return {}
    _, default, values = KIND_OPTIONS[kind]
    return {key: _get(g, key, str, wg, ... if default is None else default,
                      lambda v: None if v in values else f"must be one of {list(values)}")}


def _style_ok(v: str):
    """None if ``v`` is a character style, else what is wrong (with a did-you-mean)."""
    if v in CHARACTER_STYLES:
        return None
    close = difflib.get_close_matches(v, CHARACTER_STYLES, n=1, cutoff=0.5)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return f"unknown character style{hint}; expected one of {', '.join(CHARACTER_STYLES)}"


def parse_design(text: str, path: Path | str = "<design>") -> Design:
    """Parse and validate a design (TOML text).

    Every key must be one the section knows, every number lies in its bounds,
    names, clips, references and levels are not repeated; anything else raises
    :class:`DesignError` naming the file, section, key and the value as written."""
    src = str(path)
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DesignError(f"{src}: not valid TOML: {e}") from None
    except RecursionError:
        raise DesignError(f"{src}: not a usable design: its arrays or tables are nested too deeply "
                          f"to read (a design nests at most a few levels)") from None
    for k in d:
        if k not in SECTIONS:
            close = difflib.get_close_matches(str(k), SECTIONS, n=1, cutoff=0.6)
            hint = f"; did you mean [{close[0]}]?" if close else ""
            raise DesignError(f"{src}: unknown section [{k}]{hint} (expected "
                              f"{', '.join(SECTIONS)})")
    st = d.get("study")
    if not isinstance(st, dict):
        raise DesignError(f"{src}: missing [study] section")
    w = f"{src}: [study]"
    _check_keys({k: v for k, v in st.items() if k not in OLD_SESSION_KEYS}, STUDY_KEYS, w)
    design = Design(
        name=_get(st, "name", str, w, check=lambda v: None if 0 < len(v) <= 200 else
                  "expected 1 to 200 characters"),
        seed=_get(st, "seed", int, w, check=_between(0, MAX_SEED)),
        fps=_get(st, "fps", float, w, 120.0, _between(*FPS_RANGE, " frames per second")),
        repetitions=_get(st, "repetitions", int, w, 2, _between(1, REPETITIONS_MAX,
                                                                " presentations of each motion")),
        total_mass=_get(st, "total_mass", float, w, 70.0, _between(*MASS_RANGE, " kg")),
        clips=[], groups=[],
        com_policy=_get(st, "com_policy", str, w, "angle",
                        lambda v: None if v in COM_POLICIES else f"must be one of {list(COM_POLICIES)}"),
        tolerance_pct=_get(st, "tolerance_pct", float, w, 1.0,
                           lambda v: None if 0 < v <= TOLERANCE_MAX else
                           f"expected more than 0 and at most {TOLERANCE_MAX:g} (percent)"),
        original=_get(st, "original", str, w, "shared",
                      lambda v: None if v in ORIGINAL_MODES else f"must be one of {list(ORIGINAL_MODES)}"),
        fps_given="fps" in st,
        path=Path(path) if str(path) != "<design>" else None,
        session=_parse_session(d, st, src),
        style=_get(st, "style", str, w, None, _style_ok),
        task=_get(st, "task", str, w, "yes-no",
                  lambda v: None if v in TASKS else f"must be one of {list(TASKS)}"),
    )
    clips = d.get("clips")
    if not isinstance(clips, list) or not clips:
        raise DesignError(f"{src}: [[clips]]: at least one base clip is needed")
    seen_sources: dict[tuple, str] = {}
    for i, c in enumerate(clips):
        wc = f"{src}: clips[{i}]"
        if not isinstance(c, dict):
            raise DesignError(f"{wc}: expected a table")
        _check_keys(c, CLIP_KEYS, wc + (f" ({c['name']})" if isinstance(c.get("name"), str) else ""))
        spec = ClipSpec(
            name=_get(c, "name", str, wc, check=_name_ok),
            source=_get(c, "source", str, wc, check=lambda v: None if 0 < len(v) <= 4096 else
                        "expected a built-in name or a path"),
            scale=_get(c, "scale", float, wc, None,
                       _between(*SCALE_RANGE, " metres per file unit")),
            fps=_get(c, "fps", float, wc, None, _between(*FPS_RANGE, " frames per second")),
            flips=_get(c, "flips", int, wc, None,
                       lambda v: None if 1 <= v <= 6 else "expected a whole number of flips from 1 to 6"),
            k_ratio=_get(c, "k_ratio", float, wc, 0.7,
                         lambda v: None if 0.2 <= v <= 2 else "expected a fraction of k* from 0.2 to 2"),
            accept_unphysical=_get(c, "accept_unphysical", bool, wc, False))
        wc = f"{src}: clips[{i}] ({spec.name})"
        key = (spec.source, spec.scale, spec.fps, spec.flips, spec.k_ratio if spec.flips else None)
        if key in seen_sources:
            raise DesignError(f"{wc}: the same source {spec.source!r} with the same options as clip "
                              f"'{seen_sources[key]}'; each base clip is listed once")
        seen_sources[key] = spec.name
        design.clips.append(spec)
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
        _check_keys(g, GROUP_KEYS, wg + (f" ({g['name']})" if isinstance(g.get("name"), str) else ""))
        gname = _get(g, "name", str, wg, check=_name_ok)
        if gname in RESERVED_GROUP_NAMES:
            raise DesignError(f"{wg}.name: '{gname}' is reserved (the manifest's reference and "
                              f"shared-original rows); choose another name")
        wg = f"{src}: groups[{i}] ({gname})"
        kind = _get(g, "kind", str, wg, check=lambda v: None if v in KINDS else f"must be one of {list(KINDS)}")
        profile = None
        if kind == "angular-momentum":
            profile = _get(g, "profile", str, wg,
                           check=lambda v: None if v in PROFILES else f"must be one of {list(PROFILES)}")
        elif "profile" in g:
            raise DesignError(f"{wg}.profile: only angular-momentum groups have a profile")
        sign = _get(g, "sign", int, wg, 1, lambda v: None if v in (1, -1) else "must be 1 or -1")
        options = _kind_options(g, kind, sign, wg)
        top, excluded = LEVEL_BOUNDS[(kind, sign)]
        lv = parse_levels(g, wg, kind, sign, top, excluded)
        method, task = parse_method_task(g, wg, design.task)
        quest = parse_quest(g, wg, method, task, lv)
        if method == "quest+" and kind == "pose-rate":
            raise DesignError(f"{wg}.method: QUEST+ assumes the error grows with the level, and a "
                              f"pose rate's error grows as the level (poses per second) falls; run "
                              f"pose-rate groups with method = \"constant\"")
        if task == "2afc" and (0.0 not in lv or len(lv) < 2):
            raise DesignError(f"{wg}.levels: a 2afc group shows each level beside the original, so "
                              f"its levels need 0 (the original) and at least one error level, got "
                              f"{_show(g['levels'])}")
        default_orig = "shared" if design.original == "shared" and kind == "angular-momentum" else "own"
        orig = _get(g, "original", str, wg, default_orig,
                    lambda v: None if v in GROUP_ORIGINAL else f"must be one of {list(GROUP_ORIGINAL)}")
        if orig == "shared" and kind != "angular-momentum":
            raise DesignError(f"{wg}.original: only angular-momentum groups share their original "
                              f"(the paper's take-off group had its own); use original = \"own\"")
        gstyle = _get(g, "style", str, wg, None, _style_ok)
        if orig == "shared" and gstyle is not None and gstyle != (design.style or "ellipsoids"):
            raise DesignError(f"{wg}.style: a group drawn as {gstyle!r} cannot share the clip's "
                              f"original (drawn in the study's style); use original = \"own\"")
        design.groups.append(Group(gname, kind, profile, sign, lv, orig, gstyle, method, task, quest,
                                   **options))
    gnames = [g.name for g in design.groups]
    if len(set(gnames)) != len(gnames):
        raise DesignError(f"{src}: groups: duplicate group names "
                          f"{sorted({n for n in gnames if gnames.count(n) > 1})}")
    ref = d.get("reference", {})
    if not isinstance(ref, dict):
        raise DesignError(f"{src}: [reference]: expected a table with 'clips'")
    _check_keys(ref, REFERENCE_KEYS, f"{src}: [reference]")
    design.reference = _get(ref, "clips", list, f"{src}: [reference]", [])
    for r in design.reference:
        if r not in names:
            raise DesignError(f"{src}: [reference].clips: {_show(r)} is not one of the clips {names}")
    if len(set(design.reference)) != len(design.reference):
        raise DesignError(f"{src}: [reference].clips: {sorted({r for r in design.reference if design.reference.count(r) > 1})} "
                          f"listed more than once; each reference clip is shown once")
    stimuli = design.stimulus_names()
    if len(set(stimuli)) != len(stimuli):
        dup = sorted({s for s in stimuli if stimuli.count(s) > 1})
        raise DesignError(f"{src}: clip and group names give the same stimulus name twice ({dup[:3]}); "
                          f"rename a clip or group")
    n_trials = design.trials_per_participant()
    if any(g.adaptive or g.task != "yes-no" for g in design.groups) and n_trials > TRIALS_MAX:
        parts = [f"{g.name}: {g.quest.trials if g.adaptive else design.repetitions * len(design.clips) * len(g.trial_levels())}"
                 for g in design.groups]
        raise DesignError(f"{src}: {n_trials} test trials per participant ({', '.join(parts)}); "
                          f"at most {TRIALS_MAX} (fewer repetitions, clips, levels or quest+ trials)")
    if n_trials > TRIALS_MAX:
        raise DesignError(f"{src}: [study].repetitions = {design.repetitions} × {design.n_test_stimuli()} "
                          f"test stimuli = {n_trials} trials per participant; at most {TRIALS_MAX} "
                          f"(fewer repetitions, clips, groups or levels)")
    return design


def _parse_session(d: dict, st: dict, src: str) -> SessionSettings:
    """The ``[session]`` table; its keys written in ``[study]`` (designs before the
    table) are read the same way, with a ``FutureWarning``."""
    se = d.get("session", {})
    if not isinstance(se, dict):
        raise DesignError(f"{src}: [session]: expected a table ({', '.join(SESSION_KEYS)})")
    _check_keys(se, SESSION_KEYS, f"{src}: [session]")
    old = [k for k in OLD_SESSION_KEYS if k in st]
    for k in old:
        if k in se:
            raise DesignError(f"{src}: [study].{k} and [session].{k} are both given; {k} is a "
                              f"session setting: keep the one in [session]")

    def get(key, typ, default, check=None):
        table, where = (st, f"{src}: [study]") if key in st else (se, f"{src}: [session]")
        return _get(table, key, typ, where, default, check)

    settings = SessionSettings(replay=get("replay", bool, False),
                               break_every=get("break_every", int, 40,
                                               _between(1, BREAK_EVERY_MAX, " trials")),
                               max_dropped_pct=get("max_dropped_pct", float, 10.0,
                                                   _between(0, 100, " percent of a video's frames")),
                               repeat_dropped=get("repeat_dropped", bool, False))
    if old:
        warnings.warn(f"{src}: [study] {', '.join(old)}: session settings go in a [session] table "
                      f"now; read as [session] {', '.join(old)} (move them there)",
                      FutureWarning, stacklevel=3)
    return settings


def _name_ok(v: str):
    import re
    return None if re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}", v) else \
        "must be 1-64 letters, digits, '_', '.', '-' (it names files)"


def load_design(path) -> Design:
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_DESIGN_BYTES:
            raise DesignError(f"{p}: {size} bytes; a design is a short text file (at most "
                              f"{MAX_DESIGN_BYTES} bytes)")
        text = p.read_text()
    except OSError as e:
        raise DesignError(f"{p}: cannot read design: {e.strerror}") from None
    except UnicodeDecodeError:
        raise DesignError(f"{p}: not a text file (a design is TOML, UTF-8)") from None
    return parse_design(text, p)

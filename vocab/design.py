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

Designs are strict and valid when they exist: :class:`Design`, :class:`ClipSpec`,
:class:`Group` and :class:`SessionSettings` are frozen dataclasses that check every
field on construction (the keys a section may hold are the types' fields: an
unknown key such as ``repetitons`` is refused with a did-you-mean); every number
is bounded, names, clips, references and levels are not repeated; every invalid
field raises :class:`DesignError` naming the file, section and key and the value
as written (levels in percent).  ``Design.from_toml``/``from_dict`` read a design,
``to_dict``/``to_toml`` write it back to an equal one.

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
import json
import warnings
from dataclasses import InitVar, dataclass, field
from pathlib import Path

from flipstudy.errors import DesignError
from ._designkeys import TRIALS_MAX, _between, _check_keys, _get, _name_ok, _pct, _show  # noqa: F401

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from .groupkeys import (GRID_MAX, LEVELS_MAX, METHODS, QUEST_KEYS, TASKS, QuestSpec,  # noqa: F401
                        check_levels, check_quest, levels_table, quest_table, read_levels)
from . import kinds
from .kinds import COM_POLICIES
from .online import Exclusions, OnlineSettings
from ._sourcelimits import check_sources
from .tables import (  # noqa: F401  (the design's tables, re-exported)
    OLD_SESSION_KEYS, CHARACTER_STYLES, REFERENCE_KEYS, SECTIONS, ORIGINAL_MODES,
    GROUP_ORIGINAL, SHARED_ORIGINAL_GROUP, RESERVED_GROUP_NAMES, MAX_SEED, FPS_RANGE,
    REPETITIONS_MAX, MASS_RANGE, TOLERANCE_MAX, TOLERANCE_MIN, BREAK_EVERY_MAX, SCALE_RANGE,
    LEVEL_BOUNDS, MAX_DESIGN_BYTES, _field, _kinds_that, _one_of, CLIP_FIELDS, _TableSpec,
    ClipSpec, SOURCE_FIELDS, GIVEN_KIND, pair_group, SourceSpec, SourceGroup, GROUP_FIELDS,
    Group, SESSION_FIELDS, SessionSettings, _toml_value, _toml, _parse_session, _style_ok,
    SESSION_KEYS, CLIP_KEYS, GROUP_KEYS,)


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
kind = "{kinds.AM.name}"
profile = "{profile}"
sign = {sign}
levels = [0, 17, 25, 37, 50]

""" for profile in ("smooth", "abrupt") for sign in (1, -1)) + """\
[[groups]]
name = "takeoff-increase"
kind = \"""" + kinds.TAKEOFF_ANGLE.name + """\"
sign = 1
levels = [0, 10, 20, 30, 40]
"""



STUDY_FIELDS = {
    "name": (str, ..., lambda v: None if 0 < len(v) <= 200 else "expected 1 to 200 characters"),
    "seed": (int, ..., _between(0, MAX_SEED)),
    "fps": (float, 120.0, _between(*FPS_RANGE, " frames per second")),
    "repetitions": (int, 2, _between(1, REPETITIONS_MAX, " presentations of each motion")),
    "total_mass": (float, 70.0, _between(*MASS_RANGE, " kg")),
    "com_policy": (str, "angle", _one_of(COM_POLICIES)),
    "tolerance_pct": (float, 1.0, lambda v: None if TOLERANCE_MIN <= v <= TOLERANCE_MAX else
                      f"expected {TOLERANCE_MIN:g} to {TOLERANCE_MAX:g} percentage points (below "
                      f"{TOLERANCE_MIN:g} even an exact stimulus misses by its arithmetic)"),
    "original": (str, "shared", _one_of(ORIGINAL_MODES)),
    "style": (str, None, None),                  # checked by _style_ok (defined below)
    "task": (str, "yes-no", _one_of(TASKS)),
    "compare": (str, "first", _one_of(("first", "all"))),   # [[sources]] 2AFC: which pairs
}


@dataclass(frozen=True)
class Design:
    """A study design, valid when it exists: every ``[study]`` field is checked
    against :data:`STUDY_FIELDS`, its clips, groups and session settings are valid
    types, and what spans them (names not repeated, references among the clips,
    stimulus names unique, trials per participant bounded, a shared original in
    the study's style) is checked on construction; errors name the file (``path``,
    or ``where``), section and key.  :meth:`from_toml` / :meth:`from_dict` read it,
    :meth:`to_dict` / :meth:`to_toml` write it back to an equal design.

    >>> d = Design.from_toml_text(PAPER_DESIGN)
    >>> Design.from_dict(d.to_dict()) == d, Design.from_toml_text(d.to_toml()) == d
    (True, True)
    """
    name: str
    seed: int
    fps: float
    repetitions: int
    total_mass: float
    clips: tuple[ClipSpec, ...]
    groups: tuple[Group, ...]
    reference: tuple[str, ...] = ()
    com_policy: str = "angle"
    tolerance_pct: float = 1.0        # refuse stimuli whose measured error misses by more
    original: str = "shared"          # "shared": AM groups share one original per clip
    fps_given: bool = True            # [study] fps written: BVH clips are resampled to it
    path: Path | None = field(default=None, compare=False)   # where it was read from
    session: SessionSettings = field(default_factory=SessionSettings)  # the [session] table
    style: str | None = None          # character style of every stimulus (None: the renderer's)
    task: str = "yes-no"              # [study] task: the groups' default task
    compare: str = "first"            # [[sources]] 2AFC pairs: each source with the first, or all pairs
    sources: tuple[SourceSpec, ...] = ()   # [[sources]]: a comparison design (see _check_sources)
    online: OnlineSettings = field(default_factory=OnlineSettings)   # the [online] table (issue 32)
    exclusions: Exclusions = field(default_factory=Exclusions)        # the [exclusions] table
    where: InitVar[str | None] = None

    def __post_init__(self, where):
        src = where or (str(self.path) if self.path is not None else "<design>")
        w = f"{src}: [study]"
        for key, (typ, _, check) in STUDY_FIELDS.items():
            _field(self, key, typ, w, _style_ok if key == "style" else check, optional=key == "style")
        _field(self, "fps_given", bool, w)
        if not isinstance(self.session, SessionSettings):
            raise DesignError(f"{src}: [session]: expected SessionSettings, got {_show(self.session)}")
        for key, typ in (("online", OnlineSettings), ("exclusions", Exclusions)):
            if not isinstance(getattr(self, key), typ):
                raise DesignError(f"{src}: [{key}]: expected {typ.__name__}, got {_show(getattr(self, key))}")
        if self.sources:
            self._check_sources(src)
            if self.online.between or self.exclusions.catch_groups:
                raise DesignError(f"{src}: [online].between / [exclusions].catch_groups: a comparison "
                                  f"design ([[sources]]) has no between-subject conditions or catch "
                                  f"groups yet; remove them (recruiting, consent, preload and the other "
                                  f"exclusion rules work)")
            return
        if self.compare != "first":
            raise DesignError(f"{w}.compare: {self.compare!r} chooses the pairs of a [[sources]] design; "
                              f"this design has none (remove compare)")
        for key, typ in (("clips", ClipSpec), ("groups", Group)):
            items = getattr(self, key)
            if isinstance(items, (str, bytes, dict)) or not hasattr(items, "__iter__") \
                    or not all(isinstance(x, typ) for x in items):
                raise DesignError(f"{src}: [[{key}]]: expected {typ.__name__} entries, got {_show(items)}")
            object.__setattr__(self, key, tuple(items))
        if not self.clips:
            raise DesignError(f"{src}: [[clips]]: at least one base clip is needed")
        seen: dict[tuple, str] = {}
        for i, c in enumerate(self.clips):
            key = (c.source, c.scale, c.fps, c.flips, c.k_ratio if c.flips else None)
            if key in seen:
                raise DesignError(f"{src}: clips[{i}] ({c.name}): the same source {c.source!r} with the "
                                  f"same options as clip '{seen[key]}'; each base clip is listed once")
            seen[key] = c.name
        names = [c.name for c in self.clips]
        if len(set(names)) != len(names):
            raise DesignError(f"{src}: clips: duplicate clip names "
                              f"{sorted({n for n in names if names.count(n) > 1})}")
        if not self.groups:
            raise DesignError(f"{src}: [[groups]]: at least one error group is needed")
        for i, g in enumerate(self.groups):
            if g.name in RESERVED_GROUP_NAMES:
                raise DesignError(f"{src}: groups[{i}].name: '{g.name}' is reserved (the manifest's "
                                  f"reference and shared-original rows); choose another name")
            if g.original == "shared" and g.style is not None and g.style != (self.style or "ellipsoids"):
                raise DesignError(f"{src}: groups[{i}] ({g.name}).style: a group drawn as {g.style!r} "
                                  f"cannot share the clip's original (drawn in the study's style); use "
                                  f"original = \"own\"")
        gnames = [g.name for g in self.groups]
        if len(set(gnames)) != len(gnames):
            raise DesignError(f"{src}: groups: duplicate group names "
                              f"{sorted({n for n in gnames if gnames.count(n) > 1})}")
        ref = self.reference
        if isinstance(ref, (str, bytes)) or not isinstance(ref, (list, tuple)):
            raise DesignError(f"{src}: [reference].clips: expected an array, got {_show(ref)}")
        object.__setattr__(self, "reference", tuple(ref))
        for r in self.reference:
            if r not in names:
                raise DesignError(f"{src}: [reference].clips: {_show(r)} is not one of the clips {names}")
        if len(set(self.reference)) != len(self.reference):
            raise DesignError(f"{src}: [reference].clips: "
                              f"{sorted({r for r in self.reference if self.reference.count(r) > 1})} "
                              f"listed more than once; each reference clip is shown once")
        stimuli = self.stimulus_names()
        if len(set(stimuli)) != len(stimuli):
            dup = sorted({s for s in stimuli if stimuli.count(s) > 1})
            raise DesignError(f"{src}: clip and group names give the same stimulus name twice "
                              f"({dup[:3]}); rename a clip or group")
        by_name = {g.name: g for g in self.groups}
        self._check_catch_groups(src, by_name, gnames)
        for c in self.online.between:
            if c not in by_name:
                raise DesignError(f"{src}: [online].between: {c!r} is not one of the groups {gnames}")
            if c in self.exclusions.catch_groups:
                raise DesignError(f"{src}: [online].between: {c!r} is a catch group; every participant sees those")
            if by_name[c].adaptive:
                raise DesignError(f"{src}: [online].between: {c!r} is a quest+ group; conditions are "
                                  f"constant-stimuli groups")
        sizes = {c: len(by_name[c].trial_levels()) for c in self.online.between}
        if len(set(sizes.values())) > 1:
            raise DesignError(f"{src}: [online].between: the conditions' groups have different numbers of "
                              f"trial levels ({sizes}); give them as many, so every session is as long")
        if len(self.exclusions.catch_groups) == len(self.groups):
            raise DesignError(f"{src}: [exclusions].catch_groups: every group is a catch group; "
                              f"at least one group must be a test group")
        n_trials = self.trials_per_participant()
        if any(g.adaptive or g.task != "yes-no" for g in self.groups) and n_trials > TRIALS_MAX:
            parts = [f"{g.name}: {g.quest.trials if g.adaptive else self.repetitions * len(self.clips) * len(g.trial_levels())}"
                     for g in self.groups]
            raise DesignError(f"{src}: {n_trials} test trials per participant ({', '.join(parts)}); "
                              f"at most {TRIALS_MAX} (fewer repetitions, clips, levels or quest+ trials)")
        if n_trials > TRIALS_MAX:
            raise DesignError(f"{src}: [study].repetitions = {self.repetitions} × {self.n_test_stimuli()} "
                              f"test stimuli = {n_trials} trials per participant; at most {TRIALS_MAX} "
                              f"(fewer repetitions, clips, groups or levels)")

    def _check_catch_groups(self, src: str, by_name: dict, gnames) -> None:
        """``[exclusions].catch_groups``: groups of the design, yes/no and constant, with a
        gross error (a level above 0); a level 0 only as the group's own original."""
        for c in self.exclusions.catch_groups:
            g = by_name.get(c)
            if g is None:
                raise DesignError(f"{src}: [exclusions].catch_groups: {c!r} is not one of the groups {gnames}")
            if g.task != "yes-no" or g.adaptive or not any(lv != 0 for lv in g.levels):
                raise DesignError(f"{src}: [exclusions].catch_groups: {c!r}: a catch group shows gross "
                                  f"errors (yes-no, constant, at least one level above 0), whose right "
                                  f"answer is 'incorrect'")
            if 0.0 in g.levels and g.original != "own":
                raise DesignError(f"{src}: [exclusions].catch_groups: {c!r}: a catch group's level 0 is "
                                  f"its own original (right answer 'correct'), not the shared one every "
                                  f"error group compares against; write original = \"own\" in the group "
                                  f"or drop level 0")

    def _check_sources(self, src: str) -> None:
        """A comparison design: ``[[sources]]`` (at least two, names and folders not
        repeated), no ``[[clips]]`` (its items are the sources' clips, matched by file
        stem when it is built) and no ``[reference]``; its groups are one
        :class:`SourceGroup` per source, with the ``[study]`` task, then the
        ``[[groups]]`` of errors injected into every source's clips (constant, the
        study's task; their level 0 is each source's clip as given)."""
        srcs = self.sources
        if isinstance(srcs, (str, bytes, dict)) or not hasattr(srcs, "__iter__") \
                or not all(isinstance(x, SourceSpec) for x in srcs):
            raise DesignError(f"{src}: [[sources]]: expected SourceSpec entries, got {_show(srcs)}")
        object.__setattr__(self, "sources", tuple(srcs))
        if len(self.sources) < 2:
            raise DesignError(f"{src}: [[sources]]: a comparison needs at least two sources (e.g. the "
                              f"ground truth and a model), got {len(self.sources)}")
        if self.clips:
            raise DesignError(f"{src}: [[clips]] and [[sources]]: a comparison design takes its items "
                              f"from the [[sources]] folders (clips matched by file name); remove [[clips]]")
        if self.reference:
            raise DesignError(f"{src}: [reference] and [[sources]]: a comparison design has no reference "
                              f"clips; remove [reference]")
        groups = self.groups
        if isinstance(groups, (str, bytes, dict)) or not hasattr(groups, "__iter__") \
                or not all(isinstance(g, (Group, SourceGroup)) for g in groups):
            raise DesignError(f"{src}: [[groups]]: expected Group entries, got {_show(groups)}")
        errors = [g for g in groups if isinstance(g, Group)]
        check_sources(self, src)           # counts (with the number it would build), folders told apart
        names = [x.name for x in self.sources] + [g.name for g in errors]
        for i, g in enumerate(errors):
            w = f"{src}: groups[{i}] ({g.name})"
            if g.name in RESERVED_GROUP_NAMES or names.count(g.name) > 1:
                raise DesignError(f"{w}.name: '{g.name}' is a source's, another group's or a reserved "
                                  f"name; choose another")
            if g.adaptive:
                raise DesignError(f"{w}.method: a comparison design's error groups are constant "
                                  f"(quest+ picks among a clip list, and its items come from folders)")
            if g.task != self.task:
                raise DesignError(f"{w}.task: {g.task!r}, the study's is {self.task!r}; an error group "
                                  f"on given sources is judged like the sources (its level 0 is the "
                                  f"source's clip as given)")
            if g.style is not None and g.style != (self.style or "ellipsoids"):
                raise DesignError(f"{w}.style: one style for the whole comparison study; remove it")
        if self.compare == "all" and self.task != "2afc":
            raise DesignError(f"{src}: [study].compare: 'all' pairs the sources in 2AFC trials; the "
                              f"study's task is {self.task!r} (set task = \"2afc\" or remove compare)")
        pairs = tuple(SourceGroup(pair_group(b, a), "2afc") for a, b in self.source_pairs()
                      if a != self.sources[0].name)
        taken = {g.name for g in errors} | {x.name for x in self.sources}
        for g in pairs:
            if g.name in taken:
                raise DesignError(f"{src}: [[sources]]: the pair group {g.name!r} has the name of a source "
                                  f"or group; rename one")
            _field(g, "name", str, f"{src}: [[sources]] pair", _name_ok)
        object.__setattr__(self, "clips", ())
        object.__setattr__(self, "reference", ())
        object.__setattr__(self, "groups", tuple(SourceGroup(x.name, self.task) for x in self.sources)
                           + pairs + tuple(errors))

    def source_pairs(self) -> list[tuple[str, str]]:
        """The (comparison, shown) source pairs of a 2AFC comparison: each source with
        the first (``compare = "first"``), or every pair in the design's order (``"all"``)."""
        names = [x.name for x in self.sources]
        if self.task != "2afc":
            return []
        if self.compare == "all":
            return [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
        return [(names[0], b) for b in names[1:]]

    @property
    def error_groups(self) -> tuple:
        """The groups of injected errors (a comparison design's without its sources')."""
        return tuple(g for g in self.groups if isinstance(g, Group))

    @property
    def compares(self) -> bool:
        """Is it a comparison design (``[[sources]]``: given clips, no injected errors)?"""
        return bool(self.sources)

    # ------------------------------------------------------------ reading, writing
    @classmethod
    def from_dict(cls, d: dict, path: Path | str | None = None) -> "Design":
        """A design from its TOML tables (``study``, ``session``, ``clips``, ``groups``,
        ``reference``); ``path`` names the file in errors (and resolves BVH sources)."""
        src = str(path) if path is not None else "<design>"
        if not isinstance(d, dict):
            raise DesignError(f"{src}: expected the tables of a design, got {_show(d)}")
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
        study = {k: _get(st, k, typ, w, default, _style_ok if k == "style" else check)
                 for k, (typ, default, check) in STUDY_FIELDS.items()}
        session = _parse_session(d, st, src)
        if "sources" in d:
            return cls._from_sources(d, study, session, st, path, src)
        clips = d.get("clips")
        if not isinstance(clips, list) or not clips:
            raise DesignError(f"{src}: [[clips]]: at least one base clip is needed")
        specs = [ClipSpec.from_dict(c, f"{src}: clips[{i}]") for i, c in enumerate(clips)]
        groups = d.get("groups")
        if not isinstance(groups, list) or not groups:
            raise DesignError(f"{src}: [[groups]]: at least one error group is needed")
        gs = [Group.from_dict(g, f"{src}: groups[{i}]", study["task"], study["original"])
              for i, g in enumerate(groups)]
        ref = d.get("reference", {})
        if not isinstance(ref, dict):
            raise DesignError(f"{src}: [reference]: expected a table with 'clips'")
        _check_keys(ref, REFERENCE_KEYS, f"{src}: [reference]")
        reference = _get(ref, "clips", list, f"{src}: [reference]", [])
        p = Path(path) if path is not None and str(path) != "<design>" else None
        online = OnlineSettings.from_dict(d.get("online", {}), f"{src}: [online]")
        exclusions = Exclusions.from_dict(d.get("exclusions", {}), f"{src}: [exclusions]")
        return cls(**study, clips=tuple(specs), groups=tuple(gs), reference=tuple(reference),
                   fps_given="fps" in st, path=p, session=session, online=online,
                   exclusions=exclusions, where=src)

    @classmethod
    def _from_sources(cls, d, study, session, st, path, src) -> "Design":
        for k, label, what in (("clips", "[[clips]]", "takes its items from the [[sources]] folders "
                                "(clips matched by file name); remove [[clips]]"),
                               ("reference", "[reference]", "has no reference clips; remove [reference]")):
            if k in d:
                raise DesignError(f"{src}: {label} and [[sources]]: a comparison design {what}")
        sources = d["sources"]
        if not isinstance(sources, list):
            raise DesignError(f"{src}: [[sources]]: expected an array of tables, got {_show(sources)}")
        specs = [SourceSpec.from_dict(c, f"{src}: sources[{i}]") for i, c in enumerate(sources)]
        groups = d.get("groups", [])
        if not isinstance(groups, list):
            raise DesignError(f"{src}: [[groups]]: expected an array of tables, got {_show(groups)}")
        gs = [Group.from_dict(g, f"{src}: groups[{i}]", study["task"], "per-group")
              for i, g in enumerate(groups)]
        p = Path(path) if path is not None and str(path) != "<design>" else None
        online = OnlineSettings.from_dict(d.get("online", {}), f"{src}: [online]")
        exclusions = Exclusions.from_dict(d.get("exclusions", {}), f"{src}: [exclusions]")
        return cls(**study, clips=(), groups=tuple(gs), sources=tuple(specs), fps_given="fps" in st, path=p,
                   session=session, online=online, exclusions=exclusions, where=src)

    @classmethod
    def from_toml_text(cls, text: str, path: Path | str = "<design>") -> "Design":
        """A design from TOML text (``path`` names it in errors)."""
        src = str(path)
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise DesignError(f"{src}: not valid TOML: {e}") from None
        except RecursionError:
            raise DesignError(f"{src}: not a usable design: its arrays or tables are nested too "
                              f"deeply to read (a design nests at most a few levels)") from None
        return cls.from_dict(d, path)

    @classmethod
    def from_toml(cls, path) -> "Design":
        """A design from a TOML file (at most :data:`MAX_DESIGN_BYTES`, UTF-8)."""
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
        return cls.from_toml_text(text, p)

    def to_dict(self) -> dict:
        """The design's TOML tables; :meth:`from_dict` reads them back to an equal design
        (``[study] fps`` is written only when the design wrote it)."""
        study = {k: getattr(self, k) for k in STUDY_FIELDS
                 if getattr(self, k) is not None and (k != "fps" or self.fps_given)
                 and (k != "compare" or self.sources)}
        out = {"study": study, "session": self.session.to_dict()}
        if self.sources:
            out["sources"] = [s.to_dict() for s in self.sources]
            if self.error_groups:
                out["groups"] = [g.to_dict() for g in self.error_groups]
        else:
            out.update(clips=[c.to_dict() for c in self.clips], groups=[g.to_dict() for g in self.groups])
            if self.reference:
                out["reference"] = {"clips": list(self.reference)}
        for key in ("online", "exclusions"):      # written when given (older designs stay as they were)
            if not getattr(self, key).is_default:
                out[key] = getattr(self, key).to_dict()
        return out

    def to_toml(self) -> str:
        """The design as TOML text (:meth:`from_toml_text` reads it back to an equal design)."""
        return _toml(self.to_dict())

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


#: the keys of [study] (anything else is refused with a did-you-mean)
STUDY_KEYS = tuple(STUDY_FIELDS)


def parse_design(text: str, path: Path | str = "<design>") -> Design:
    """Parse and validate a design (TOML text): :meth:`Design.from_toml_text`.

    Every key must be one the section knows, every number lies in its bounds,
    names, clips, references and levels are not repeated; anything else raises
    :class:`DesignError` naming the file, section, key and the value as written."""
    return Design.from_toml_text(text, path)


def load_design(path) -> Design:
    """A design file: :meth:`Design.from_toml`."""
    return Design.from_toml(path)

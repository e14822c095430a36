"""The error kinds, declared once: the registry every part reads.

An error kind is the study's central word: the physical error a stimulus carries
and a motion is scored for.  Each kind is one :class:`ErrorKind` entry, made by
:func:`register`: its name and variants, the unit its levels and its measured
sizes are written in, its level bounds, how it is injected and how it is
measured (dotted names, resolved on first use), what it changes besides itself
(its side effects) and its calibration sources.  Design validation
(:mod:`flipstudy.vocab.design`), stimulus building
(:func:`flipstudy.stimuli.stimset.make_stimulus`), the measure
(:func:`flipstudy.stimuli.measure.measure`), the score, the analysis units
(:mod:`flipstudy.analysis.units`) and the documentation's format table read it,
so a new kind is one module that calls :func:`register`.

The injector and the measure are named, not imported (``"module:function"``):
this module sits on the floor below the physics and imports none of it, so that
reading a design loads no physics; :meth:`ErrorKind.injector` imports the
function when a stimulus is built.

>>> AM.name, AM.variants, AM.level_unit
('angular-momentum', ('smooth', 'abrupt'), '%')
>>> get("pose-rate").bounds
{1: (1000.0, False)}
>>> [k.name for k in study_kinds()][:3]
['angular-momentum', 'takeoff-angle', 'gravity']
>>> get("foot-skate").injected, get("foot-skate").unit
(False, 'mm')
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field

from flipstudy.errors import FlipstudyValueError

#: the kinds of the stimuli that carry an injected error the FwP manifest columns
#: describe (the others, "ballistic", add the columns of ``contract.EXTRA_COLUMNS``)
FAMILIES = ("paper", "ballistic", "measured")
#: what an angular-momentum stimulus keeps of the COM path ([study] com_policy): the
#: take-off angle, or the landing point
COM_POLICIES = ("angle", "landing")
#: the calibration source shipped with the package (FwP 2007 Table 2)
FWP_TABLE2 = "FwP 2007 Table 2 (shipped)"
#: a user's own study, fitted by ``flipstudy calibrate``
OWN_STUDIES = "own studies (flipstudy calibrate)"


@dataclass(frozen=True)
class ErrorKind:
    """One error kind (see the module doc).

    Examples
    --------
    >>> k = ErrorKind("toy-push", unit="%", bounds={1: (50.0, False)})
    >>> k.injected, k.signs
    (False, (1,))
    """
    name: str
    unit: str                        # the unit of a measured size (what ``score`` lists)
    level_unit: str = "%"            # the unit a design level is written in
    bounds: dict = field(default_factory=dict)   # sign -> (largest level magnitude, is it excluded)
    variants: tuple = ()             # measured variants (and the design's ``profile`` when ``profiled``)
    profiled: bool = False           # do its design groups name a ``profile`` (one of ``variants``)?
    option: tuple | None = None      # (group key, default or None if required, values)
    family: str = "paper"            # one of FAMILIES
    inject: str | None = None        # "module:function" (a, group, level, design) -> Injected
    check_measure: str | None = None  # "module:function" (original analysis, Injected) -> dict
    measure: str | None = None       # "module:function" (clip, analysis, add); None: by stimuli.measure
    quantity: tuple = ("", "")       # what is changed, in which physical unit (the manifest's)
    side_effects: tuple = ()         # what else it changes (sentences) ...
    same_as: tuple = ()              # ... and the kinds a measured item of it repeats
    calibration: tuple = ()          # the sources of its psychometric functions
    shares_original: bool = False    # may its groups share one original per clip?
    doc: str = ""                    # one line for the docs' table

    @property
    def injected(self) -> bool:
        """Can a design inject it (does it name an injector)?"""
        return self.inject is not None

    @property
    def signs(self) -> tuple:
        """The signs a design group of this kind may take."""
        return tuple(sorted(self.bounds, reverse=True))

    def _resolve(self, ref: str | None, what: str):
        if ref is None:
            raise FlipstudyValueError(f"error kind {self.name!r} has no {what}")
        mod, _, fn = ref.partition(":")
        return getattr(importlib.import_module(mod), fn)

    def injector(self):
        """The function that builds a stimulus of this kind (imported now)."""
        return self._resolve(self.inject, "injector")

    def checker(self):
        """The function that measures a stimulus of this kind against its original."""
        return self._resolve(self.check_measure, "stimulus measure")

    def measurer(self):
        """The extra measure of a motion (None: :func:`flipstudy.stimuli.measure.measure`
        measures it itself)."""
        return None if self.measure is None else self._resolve(self.measure, "measure")


_REGISTRY: dict[str, ErrorKind] = {}


def register(kind: ErrorKind) -> ErrorKind:
    """Add an error kind to the registry (a module's one call that makes a new kind).

    Registering an equal entry again is a no-op; another entry under a taken name is
    refused.

    Examples
    --------
    >>> k = register(ErrorKind("doc-toy", unit="%", bounds={1: (10.0, False)}))
    >>> get("doc-toy") is k
    True
    >>> unregister("doc-toy")
    """
    if kind.family not in FAMILIES:
        raise FlipstudyValueError(f"error kind {kind.name!r}: family must be one of {FAMILIES}")
    old = _REGISTRY.get(kind.name)
    if old is not None and old != kind:
        raise FlipstudyValueError(f"error kind {kind.name!r} is already registered")
    _REGISTRY[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Remove a kind (for tests that register a toy one)."""
    _REGISTRY.pop(name, None)


def get(name: str) -> ErrorKind:
    """The entry of a kind by name (:class:`FlipstudyValueError` naming the known ones)."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise FlipstudyValueError(f"unknown error kind {name!r}; known: {', '.join(_REGISTRY)}") from None


def find(name) -> ErrorKind | None:
    """The entry of a kind, or None for a name that is not one (``"reference"``, ``"given"``)."""
    return _REGISTRY.get(name)


def all_kinds() -> tuple:
    """Every registered kind, in registration order."""
    return tuple(_REGISTRY.values())


def study_kinds() -> tuple:
    """The kinds a design may inject, in registration order."""
    return tuple(k for k in _REGISTRY.values() if k.injected)


def study_kind_names() -> tuple:
    """The names of :func:`study_kinds`."""
    return tuple(k.name for k in study_kinds())


def ballistic_kind_names() -> tuple:
    """The injected kinds whose stimuli carry the ballistic manifest columns."""
    return tuple(k.name for k in study_kinds() if k.family == "ballistic")


def measured_units() -> dict:
    """Kind name → the unit its measured sizes are in."""
    return {k.name: k.unit for k in _REGISTRY.values()}


_S = "flipstudy.stimuli."
_BALLISTIC = dict(family="ballistic", inject=_S + "kindbuild:build_ballistic",
                  check_measure=_S + "ballistic_measure:measure_ballistic",
                  calibration=(OWN_STUDIES,))

AM = register(ErrorKind(
    "angular-momentum", unit="%", bounds={1: (500.0, True),     # |L| below 6× the original
                                          -1: (90.0, True)},    # a decrease of 90 % stops the rotation
    variants=("smooth", "abrupt"), profiled=True, shares_original=True,
    inject=_S + "kindbuild:build_angular_momentum", check_measure=_S + "injection:measure",
    quantity=("|L| change", "%"),
    side_effects=("the flight's duration changes, so its take-off speed does (the take-off angle "
                  "or the landing point is kept: [study] com_policy)",),
    calibration=(FWP_TABLE2, OWN_STUDIES),
    doc="the rotation's angular momentum retimed in the air (FwP §7)"))
TAKEOFF_ANGLE = register(ErrorKind(
    "takeoff-angle", unit="%", bounds={1: (100.0, False),       # horizontal velocity up to doubled
                                       -1: (100.0, True)},      # −100 % leaves no horizontal velocity
    inject=_S + "kindbuild:build_takeoff_angle", check_measure=_S + "injection:measure",
    quantity=("horizontal take-off velocity change", "%"),
    side_effects=("the landing and everything after it move along the jump direction",),
    calibration=(FWP_TABLE2, OWN_STUDIES),
    doc="the horizontal COM velocity in flight scaled (FwP §7)"))
GRAVITY = register(ErrorKind(
    "gravity", unit="% of 9.81", bounds={1: (300.0, False), -1: (100.0, True)},   # up to 4 g; 0 g never lands
    option=("policy", None, ("takeoff-velocity", "apex-height", "flight-time")),
    quantity=("apparent gravity", "m/s²"), side_effects=("a vertical acceleration and a time "
                                                         "scale of the same size",),
    same_as=(), doc="the flight's gravity changed", **_BALLISTIC))
register(ErrorKind(
    "horizontal-velocity", unit="%", bounds={1: (100.0, False), -1: (100.0, True)},
    quantity=("horizontal take-off velocity", "m/s"), doc="the horizontal take-off velocity scaled",
    **_BALLISTIC))
register(ErrorKind(
    "vertical-velocity", unit="%", bounds={1: (100.0, False),
                                           -1: (100.0, True)},  # the COM must come down to the floor
    quantity=("vertical take-off velocity", "m/s"), doc="the vertical take-off velocity scaled",
    **_BALLISTIC))
register(ErrorKind(
    "acceleration", unit="% of 9.81", bounds={1: (100.0, True),    # percent of 9.81 m/s²; a vertical
                                              -1: (100.0, True)},  # one of +100 % would cancel gravity
    variants=("horizontal", "vertical"), option=("axis", None, ("horizontal", "vertical")),
    quantity=("added in-flight acceleration", "m/s²"), doc="a constant acceleration added in flight",
    **_BALLISTIC))
register(ErrorKind(
    "time-scale", unit="%", bounds={1: (300.0, False),   # up to 4× speed
                                    -1: (100.0, True)},  # −100 % stops the motion
    option=("span", "flight", ("flight", "whole")), quantity=("playback rate of the flight", "×"),
    doc="the flight (or whole clip) played faster or slower", **_BALLISTIC))
POSE_RATE = register(ErrorKind(
    "pose-rate", unit="poses/s", level_unit="poses/s", bounds={1: (1000.0, False)},  # 0: the original
    quantity=("pose updates per second", "poses/s"), doc="poses held: fewer pose updates per second",
    **_BALLISTIC))
# measured only: no design injects them; score measures and lists them
for _name, _unit, _doc in (("air-jolt", "m/s", "a jump of the COM velocity in the air"),
                           ("takeoff-velocity-jump", "m/s", "the COM velocity change at take-off"),
                           ("landing-velocity-jump", "m/s", "the COM velocity change at landing"),
                           ("foot-skate", "mm", "a foot sliding while on the floor (skating)"),
                           ("penetration", "mm", "a point below the floor"),
                           ("floating", "mm", "a body held above the floor with no support")):
    register(ErrorKind(_name, unit=_unit, family="measured", doc=_doc))


def level_bounds() -> dict:
    """``{(kind, sign): (largest magnitude, excluded)}`` of every injected kind."""
    return {(k.name, s): b for k in study_kinds() for s, b in k.bounds.items()}


def kind_options() -> dict:
    """``{kind: (group key, default, values)}`` of the kinds that take a design option."""
    return {k.name: k.option for k in study_kinds() if k.option is not None}


__all__ = ["AM", "COM_POLICIES", "FAMILIES", "GRAVITY", "POSE_RATE", "TAKEOFF_ANGLE", "ErrorKind", "all_kinds",
           "ballistic_kind_names", "find", "get", "kind_options", "level_bounds", "measured_units",
           "register", "study_kind_names", "study_kinds", "unregister"]

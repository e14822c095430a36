"""The look of every rendered image, as data.

A :class:`Style` holds colours, sizes, background, ground and lighting.  One
style is used for a whole study ("the same style"), recorded in
``render/render.json`` and loadable from a dict or a TOML file::

    [style]                       # or at the top level of the file
    background = "#ffffff"
    body_color = "#3d6a9e"
    ghost_opacity = 0.3

Colours are anything :class:`pyvista.Color` accepts (``"#rrggbb"``, names,
RGB tuples in 0..1 or 0..255).
"""
from __future__ import annotations

from flipstudy.errors import StyleError

import dataclasses
import functools
import math
from dataclasses import dataclass
from pathlib import Path

#: Paul Tol's "muted" qualitative palette: nine colours distinguishable with the
#: common colour-vision deficiencies (https://personal.sron.nl/~pault/).
TOL_MUTED = ("#CC6677", "#332288", "#DDCC77", "#117733", "#88CCEE",
             "#882255", "#44AA99", "#999933", "#AA4499")

#: Okabe & Ito (2008) colour-blind-safe palette.
OKABE_ITO = ("#E69F00", "#56B4E9", "#009E73", "#F0E442", "#0072B2",
             "#D55E00", "#CC79A7", "#000000")


#: The anti-aliasing a :class:`Style` can ask for (offscreen EGL, Mesa llvmpipe;
#: costs measured by ``benchmarks/bench_render_ceiling.py --aa`` at 640x480, per
#: CPU-second): ``"fxaa"`` (the default: FXAA 3.11 on the read-back frame,
#: :mod:`flipstudy.render.antialias`; a frame costs about 1.3x what it costs with
#: ``"none"``; the error on the character's edges, against a supersampled
#: reference, falls as with VTK's filter — ``tests/render/test_render.py``),
#: ``"vtk-fxaa"`` (VTK's FXAA filter, the same algorithm on llvmpipe: about 3x,
#: the default before), ``"ssaa"`` (VTK's SSAA pass, 5x the pixels and a Lanczos
#: filter: about 8x, edges a little finer than FXAA's) and ``"none"``.  MSAA is
#: not offered: under depth peeling it drops every translucent surface (ghosts),
#: and on llvmpipe it costs more than VTK's FXAA.
ANTI_ALIASING = ("fxaa", "ssaa", "none", "vtk-fxaa")

#: What each anti-aliasing is, as ``render.json`` records it (``anti_aliasing``)
ANTI_ALIASING_METHODS = {
    "fxaa": "FXAA 3.11 on the read-back frame (flipstudy.render.antialias, numpy, VTK's default "
            "options); VTK's FXAA filter for frames read with alpha",
    "vtk-fxaa": "VTK's FXAA filter (vtkOpenGLFXAAFilter, default options)",
    "ssaa": "VTK's SSAA pass",
    "none": "none",
}


@dataclass(frozen=True)
class Style:
    """Colours, sizes, ground and lighting of the renders; frozen and valid when it
    exists: every field is checked on construction against :data:`STYLE_RANGES`
    (numbers finite and in range, colours parsed, mesh resolutions and ground tiles
    bounded so a render stays fast), else :class:`~flipstudy.errors.StyleError`
    naming the field, the allowed values and the value given (and the file, when
    read by :meth:`from_toml`).

    >>> Style(trail_rate=0)
    Traceback (most recent call last):
    ...
    flipstudy.errors.StyleError: Style.trail_rate: expected more than 0 and at most 240 (markers per second), got 0

    Parameters
    ----------
    background, body_color, label_color : str
        Colours (names or ``#rrggbb``).
    ground, ground_colors, ground_tile, ground_height, ground_margin : various
        The checkered ground: drawn or not, its two colours, tile size, height and
        margin (metres).
    character, sided, side_lightness, side_colors : various
        The character style (:data:`~flipstudy.render.characters.CHARACTER_STYLES`)
        and its left/right tones.
    ghost_color, ghost_opacity, ghost_last_opacity, ghost_ramp, ghost_late_opacity, ghost_spread : various
        The ghost composites.
    trail_palette, trail_rate, marker_size, trail_line, trail_line_width, trail_com_color, trail_body_color, trail_body_opacity : various
        The marker trails.
    legend, legend_size, font_size, scale_bar : various
        Labels on the pictures.
    ambient, diffuse, specular, specular_power, lighting, anti_aliasing, depth_peels, ellipsoid_resolution : various
        Shading and quality.
    **others
        Every other field (overlay, gizmo and point-light settings), each checked
        against :data:`STYLE_RANGES`.

    Examples
    --------
    >>> s = Style.from_dict({"background": "white", "ghost_opacity": 0.25})
    >>> s.ghost_opacity, Style.from_dict(s.to_dict()) == s
    (0.25, True)
    """

    # scene
    background: str = "#f7f7f4"
    ground: bool = True
    ground_colors: tuple = ("#dcdcd6", "#c9c9c2")   # checker tiles
    ground_tile: float = 0.5                         # metres
    ground_height: float = 0.0                       # metres (Y)
    ground_margin: float = 4.0                       # metres around the motion
    # character (the Body's mass ellipsoids)
    body_color: str = "#3d6a9e"
    ellipsoid_resolution: tuple = (20, 12)           # (around the bone, along the bone)
    ambient: float = 0.30
    diffuse: float = 0.75
    specular: float = 0.15
    specular_power: float = 20.0
    # ghosts and layered composites
    ghost_color: str | None = None                   # None: body_color
    ghost_opacity: float = 0.30
    ghost_last_opacity: float = 1.0
    layer_opacity: float = 0.75                      # Ooi's composited frames
    # original vs edited (Majkowska & Faloutsos, Figure 4)
    overlay_colors: tuple = ("#e8b500", "#19b2a8")   # yellow, turquoise
    overlay_opacity: float = 0.45
    # marker trails (Ooi, Figure 4.1)
    # Okabe–Ito without yellow and black, in the order of TRAIL_JOINTS: head purple, the left
    # hand and foot light and dark blue, the right ones light and dark orange
    trail_palette: tuple = ("#CC79A7", "#56B4E9", "#E69F00", "#0072B2", "#D55E00", "#009E73")
    trail_rate: float = 10.0                         # markers per second
    marker_size: float = 0.035                       # sphere radius, metres
    trail_line: bool = True                          # a thin line through each joint's path
    trail_line_width: float = 2.0
    trail_com_color: str = "#111111"                 # the COM trail is black
    trail_body_color: str = "#9b9b9b"                # neutral, so it does not read as a trail colour
    trail_body_opacity: float = 0.45                 # the character drawn with the trails
    legend: bool = True
    legend_size: tuple = (0.22, 0.36)                # fraction of the image (w, h)
    # labels (strips, legends)
    label_color: str = "#222222"
    font_size: float = 0.075                         # fraction of the panel height
    # debug gizmos (Ooi, Figure 4.5)
    com_color: str = "#D55E00"
    com_radius: float = 0.04
    L_color: str = "#CC79A7"
    L_scale: float = 0.02                            # metres per kg·m²/s
    v_color: str = "#0072B2"
    v_scale: float = 0.15                            # metres per m/s
    support_color: str = "#009E73"
    # character style and sided colours (flipstudy.render.characters)
    character: str = "ellipsoids"                    # ellipsoids, capsules, stick, point-light, mannequin
    sided: bool = True                               # left and right limbs in two tones
    side_lightness: float = 20.0                     # CIE L* of left above / right below the colour
    side_colors: tuple | None = None                 # (trunk, left, right) for body_color; None: tones
    point_light_radius: float = 0.03                 # metres
    point_light_extra: bool = False                  # sternum and pelvis markers (15, not 13)
    # framing and the time cues of composites
    frame_margin: float = 0.06                       # fraction of width/height left on each side
    ghost_ramp: tuple = ("#fde725", "#7ad151", "#22a884", "#2a788e")  # viridis, early → late ghosts
    ghost_late_opacity: float = 0.60                 # the ghost before the last; earlier ones down to ghost_opacity
    ghost_spread: float = 0.0                        # metres between successive ghosts along the travel (0: just enough for a motion in place)
    scale_bar: bool = True                           # a 1 m bar on the ground of ghosts and trails
    # rendering
    anti_aliasing: str = "fxaa"                      # "fxaa", "ssaa" (slow, finest), "none" or "vtk-fxaa"
    depth_peels: int = 8
    lighting: str = "key-fill"                       # "key-fill" or "light kit"

    def __post_init__(self):
        for name, value in _normalised(self).items():
            object.__setattr__(self, name, value)
        if self.character == "point-light":              # Johansson: white dots on black
            for name, value in POINT_LIGHT_LOOK.items():
                if getattr(self, name) == _DEFAULTS[name]:
                    object.__setattr__(self, name, value)

    # ------------------------------------------------------------ conversions
    def to_dict(self) -> dict:
        """Plain dict (JSON/TOML-serialisable; tuples become lists)."""
        d = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}

    @classmethod
    def from_dict(cls, d: dict | None, source=None) -> "Style":
        """A style from a dict; an unknown key (with a did-you-mean) or an invalid
        value raises :class:`~flipstudy.errors.StyleError` naming ``source`` (the
        style file, when given) and the key."""
        import difflib
        where = f"{source}: [style] " if source is not None else "Style."
        if d is not None and not isinstance(d, dict):
            raise StyleError(f"{source or 'style'}: expected a table of style keys, got "
                             f"{type(d).__name__}")
        d = dict(d or {})
        names = [f.name for f in dataclasses.fields(cls)]
        for k in d:
            if k not in names:
                close = difflib.get_close_matches(str(k), names, n=1, cutoff=0.6)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise StyleError(f"{where}{k}: unknown field{hint} (known fields: {', '.join(names)})",
                                 key=str(k))
        try:
            return cls(**d)
        except StyleError as e:
            if source is None:
                raise
            raise StyleError(f"{where}{e.key}: {e.detail}", key=e.key, detail=e.detail) from None

    @classmethod
    def from_toml(cls, path_or_text) -> "Style":
        """A style from a TOML file (or TOML text): the ``[style]`` table if there
        is one, else the top level.  Errors name the file and key."""
        import tomllib
        p = Path(path_or_text) if not (isinstance(path_or_text, str) and "\n" in path_or_text) else None
        src = p if p is not None else "style"
        try:
            text = p.read_text() if p is not None and p.exists() else str(path_or_text)
        except (OSError, UnicodeDecodeError) as e:
            raise StyleError(f"{p}: cannot read the style file: {getattr(e, 'strerror', None) or e}") \
                from None
        try:
            data = tomllib.loads(text)
        except (tomllib.TOMLDecodeError, RecursionError) as e:
            raise StyleError(f"{src}: not valid TOML: {e}") from None
        return cls.from_dict(data.get("style", data), source=src)

    def replace(self, **kw) -> "Style":
        return dataclasses.replace(self, **kw)

    def with_character(self, name: str) -> "Style":
        """This style with character style ``name``; leaving point-light restores
        the looks it set (background, ground, colour) to the defaults.

        >>> s = Style().with_character("point-light")
        >>> s.background, s.ground, s.with_character("stick").background == Style().background
        ('#000000', False, True)
        """
        kw = {"character": name}
        if self.character == "point-light" and name != "point-light":
            kw.update({k: _DEFAULTS[k] for k, v in POINT_LIGHT_LOOK.items()
                       if getattr(self, k) == v})
        return dataclasses.replace(self, **kw)

    @property
    def ghost(self) -> str:
        return self.ghost_color or self.body_color


def rgb(color) -> tuple:
    """A colour as an (r, g, b) tuple of floats in 0..1."""
    from ._pv import pv
    return tuple(float(c) for c in pv.Color(color).float_rgb)


def rgb8(color) -> tuple:
    """A colour as an (r, g, b) tuple of ints in 0..255."""
    from ._pv import pv
    return tuple(int(c) for c in pv.Color(color).int_rgb)


#: what point-light changes unless the style sets it (Johansson 1973: white dots on black)
POINT_LIGHT_LOOK = {"background": "#000000", "ground": False, "body_color": "#ffffff",
                    "sided": False}
_DEFAULTS = {f.name: f.default for f in dataclasses.fields(Style)}

#: the allowed values of every style field: ("number", low, high, low excluded, unit),
#: ("int", low, high, unit), ("bool",), ("colour",), ("colour?",) (or none),
#: ("colours", n_min, n_max), ("colours?", n, n) (or none), ("choice", values),
#: ("pair", low, high, unit) (two numbers, each in range), ("ints2", low, high, what).
#: The bounds keep a render fast (mesh resolutions, marker rates, ground tiles) and
#: its looks defined (fractions, opacities, VTK's lighting coefficients).
STYLE_RANGES = {
    "background": ("colour",), "ground": ("bool",),
    "ground_colors": ("colours", 2, 2), "ground_tile": ("number", 0.01, 100.0, True, "metres"),
    "ground_height": ("number", -100.0, 100.0, False, "metres"),
    "ground_margin": ("number", 0.0, 100.0, False, "metres around the motion"),
    "body_color": ("colour",),
    "ellipsoid_resolution": ("ints2", 3, 100, "mesh points (around, along the bone)"),
    "ambient": ("number", 0.0, 1.0, False, "VTK lighting coefficient"),
    "diffuse": ("number", 0.0, 1.0, False, "VTK lighting coefficient"),
    "specular": ("number", 0.0, 1.0, False, "VTK lighting coefficient"),
    "specular_power": ("number", 0.0, 128.0, False, "VTK specular exponent"),
    "ghost_color": ("colour?",), "ghost_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "ghost_last_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "layer_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "overlay_colors": ("colours", 2, 2), "overlay_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "trail_palette": ("colours", 1, 64),
    "trail_rate": ("number", 0.0, 240.0, True, "markers per second"),
    "marker_size": ("number", 0.0, 1.0, True, "metres, a sphere's radius"),
    "trail_line": ("bool",), "trail_line_width": ("number", 0.0, 50.0, True, "pixels"),
    "trail_com_color": ("colour",), "trail_body_color": ("colour",),
    "trail_body_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "legend": ("bool",), "legend_size": ("pair", 0.0, 1.0, "fractions of the image (w, h)"),
    "label_color": ("colour",),
    "font_size": ("number", 0.0, 0.5, True, "fraction of the panel height"),
    "com_color": ("colour",), "com_radius": ("number", 0.0, 1.0, True, "metres"),
    "L_color": ("colour",), "L_scale": ("number", 0.0, 10.0, True, "metres per kg·m²/s"),
    "v_color": ("colour",), "v_scale": ("number", 0.0, 10.0, True, "metres per m/s"),
    "support_color": ("colour",),
    "character": ("choice", None), "sided": ("bool",),
    "side_lightness": ("number", 0.0, 50.0, False, "CIE L*"),
    "side_colors": ("colours?", 3, 3),
    "point_light_radius": ("number", 0.0, 0.5, True, "metres"),
    "point_light_extra": ("bool",),
    "frame_margin": ("number", 0.0, 0.5, False, "fraction of width/height; below 0.5"),
    "ghost_ramp": ("colours", 2, 64),
    "ghost_late_opacity": ("number", 0.0, 1.0, False, "opacity"),
    "ghost_spread": ("number", 0.0, 10.0, False, "metres"),
    "scale_bar": ("bool",), "anti_aliasing": ("choice", ANTI_ALIASING),
    "depth_peels": ("int", 0, 100, "peels"), "lighting": ("choice", ("key-fill", "light kit")),
}
#: at most this many ground tiles from the motion to the ground's edge (ground_margin / ground_tile)
MAX_MARGIN_TILES = 200


def _show(v) -> str:
    r = repr(v)
    return r if len(r) <= 60 else r[:57] + "..."


@functools.lru_cache(maxsize=512)
def _colour_problem(v) -> str | None:
    """None if :class:`pyvista.Color` reads ``v`` (what the renderer draws with)."""
    from ._pv import pv
    try:
        pv.Color(v)
    except Exception:          # pyvista raises ValueError, TypeError or KeyError
        return "not a colour (a name such as 'white', '#rrggbb', or (r, g, b) in 0..1 or 0..255)"
    return None


def _colour(name: str, v):
    if isinstance(v, list):
        v = tuple(v)
    if not isinstance(v, (str, tuple)) or isinstance(v, tuple) and not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
        raise StyleError(f"Style.{name}: expected a colour, got {_show(v)}", key=name)
    try:
        problem = _colour_problem(v)
    except TypeError:
        problem = "not a colour"
    if problem:
        raise StyleError(f"Style.{name}: {problem}, got {_show(v)}", key=name)
    return v


def _check_field(name: str, v, spec):
    """The value of field ``name`` as the style holds it, or StyleError."""
    kind = spec[0]

    def bad(expected):
        raise StyleError(f"Style.{name}: expected {expected}, got {_show(v)}", key=name)

    def number(x, lo, hi, lo_excl, unit, typ=float):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or typ is int and not isinstance(x, int):
            bad(f"{'a whole number' if typ is int else 'a number'} ({unit})")
        if not (math.isfinite(x) and (lo < x if lo_excl else lo <= x) and x <= hi):
            bad(f"{'more than' if lo_excl else 'from'} {lo:g} {'and at most' if lo_excl else 'to'} "
                f"{hi:g} ({unit})")
        return typ(x)

    if kind == "bool":
        return v if isinstance(v, bool) else bad("true or false")
    if kind == "number":
        return number(v, spec[1], spec[2], spec[3], spec[4])
    if kind == "int":
        return number(v, spec[1], spec[2], False, spec[3], int)
    if kind == "choice":
        values = spec[1] if spec[1] is not None else _character_styles()
        if v in values and isinstance(v, str):
            return v
        import difflib
        close = difflib.get_close_matches(str(v), values, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        bad(f"one of {', '.join(map(repr, values))}{hint}")
    if kind == "colour" or kind == "colour?" and v is not None:
        return _colour(name, v)
    if kind == "colour?":
        return None
    if kind in ("colours", "colours?") and not (kind == "colours?" and v is None):
        lo, hi = spec[1], spec[2]
        if not isinstance(v, (list, tuple)) or not lo <= len(v) <= hi:
            bad(f"{lo if lo == hi else f'{lo} to {hi}'} colours in a list")
        return tuple(_colour(f"{name}[{i}]", c) for i, c in enumerate(v))
    if kind == "colours?":
        return None
    if kind in ("pair", "ints2"):
        if not isinstance(v, (list, tuple)) or len(v) != 2:
            bad(f"two numbers [{spec[1]:g}..{spec[2]:g}] ({spec[3]})")
        if kind == "pair":
            return tuple(number(x, spec[1], spec[2], True, spec[3]) for x in v)
        return tuple(number(x, spec[1], spec[2], False, spec[3], int) for x in v)
    raise AssertionError(kind)


def _character_styles():
    from flipstudy.stimuli.design import CHARACTER_STYLES
    return CHARACTER_STYLES


def _normalised(style: "Style") -> dict:
    """Every field of ``style`` checked (:data:`STYLE_RANGES`), as the style holds it
    (tuples for lists); a field equal to its default is known good and kept."""
    out = {}
    for f in dataclasses.fields(style):
        v = getattr(style, f.name)
        if isinstance(v, list):
            v = tuple(v)
        if f.name in _DEFAULTS and type(v) is type(_DEFAULTS[f.name]) and v == _DEFAULTS[f.name]:
            out[f.name] = v
            continue
        out[f.name] = _check_field(f.name, v, STYLE_RANGES[f.name])
    if out["ground_margin"] / out["ground_tile"] > MAX_MARGIN_TILES:
        raise StyleError(f"Style.ground_margin: {out['ground_margin']:g} m is "
                         f"{out['ground_margin'] / out['ground_tile']:.4g} tiles of ground_tile = "
                         f"{out['ground_tile']:g} m; at most {MAX_MARGIN_TILES} tiles (a larger "
                         f"ground_tile or a smaller margin)", key="ground_margin")
    return out
DEFAULT_STYLE = Style()
__all__ = ["Style", "DEFAULT_STYLE", "ANTI_ALIASING", "ANTI_ALIASING_METHODS", "TOL_MUTED", "OKABE_ITO", "rgb", "rgb8"]

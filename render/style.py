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

from flipstudy.errors import FlipstudyValueError

import dataclasses
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
#: CPU-second): ``"fxaa"`` (VTK's FXAA filter, the default: a frame costs about
#: 2.5x what it costs with ``"none"``; the error on the character's edges,
#: against a supersampled reference, halves — ``tests/test_render.py``),
#: ``"ssaa"`` (VTK's SSAA pass, 5x the pixels and a Lanczos filter: about 7x,
#: edges a little finer than FXAA's) and ``"none"``.  MSAA is not offered: under
#: depth peeling it drops every translucent surface (ghosts).
ANTI_ALIASING = ("fxaa", "ssaa", "none")


@dataclass
class Style:
    """Colours, sizes, ground and lighting of the renders.

    Example
    -------
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
    ghost_spread: float = 0.0                        # metres between successive ghosts along the travel
    scale_bar: bool = True                           # a 1 m bar on the ground of ghosts and trails
    # rendering
    anti_aliasing: str = "fxaa"                      # "fxaa", "ssaa" (slow, finest) or "none"
    depth_peels: int = 8
    lighting: str = "key-fill"                       # "key-fill" or "light kit"

    def __post_init__(self):
        from flipstudy.stimuli.design import CHARACTER_STYLES
        if self.character not in CHARACTER_STYLES:
            import difflib
            near = difflib.get_close_matches(str(self.character), CHARACTER_STYLES, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise FlipstudyValueError(f"Style.character: unknown style {self.character!r}{hint}; "
                                      f"choose from {', '.join(CHARACTER_STYLES)}")
        if self.side_colors is not None:
            self.side_colors = tuple(self.side_colors)
            if len(self.side_colors) != 3:
                raise FlipstudyValueError("Style.side_colors: three colours (trunk, left, right)")
        if self.character == "point-light":              # Johansson: white dots on black
            for name, value in POINT_LIGHT_LOOK.items():
                if getattr(self, name) == _DEFAULTS[name]:
                    setattr(self, name, value)
        for name in ("ground_colors", "ellipsoid_resolution", "overlay_colors",
                     "trail_palette", "legend_size", "ghost_ramp"):
            setattr(self, name, tuple(getattr(self, name)))
        if self.anti_aliasing not in ANTI_ALIASING:
            raise FlipstudyValueError(f"Style.anti_aliasing must be one of {', '.join(map(repr, ANTI_ALIASING))}, "
                                      f"got {self.anti_aliasing!r}")
        if self.lighting not in ("key-fill", "light kit"):
            raise FlipstudyValueError(f"Style.lighting must be 'key-fill' or 'light kit', got {self.lighting!r}")
        for name in ("ghost_opacity", "ghost_last_opacity", "layer_opacity", "overlay_opacity",
                     "trail_body_opacity", "ghost_late_opacity"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise FlipstudyValueError(f"Style.{name} must be in [0, 1], got {v!r}")
        if not 0.0 <= self.frame_margin < 0.5:
            raise FlipstudyValueError(f"Style.frame_margin must be in [0, 0.5), got {self.frame_margin!r}")
        if len(self.ghost_ramp) < 2:
            raise FlipstudyValueError("Style.ghost_ramp needs at least two colours (early, late)")
        if len(self.trail_palette) == 0:
            raise FlipstudyValueError("Style.trail_palette is empty")

    # ------------------------------------------------------------ conversions
    def to_dict(self) -> dict:
        """Plain dict (JSON/TOML-serialisable; tuples become lists)."""
        d = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}

    @classmethod
    def from_dict(cls, d: dict | None) -> "Style":
        """A style from a dict; unknown keys raise ``ValueError`` naming them."""
        d = dict(d or {})
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise FlipstudyValueError(f"Style: unknown field(s) {unknown}; known fields: {sorted(names)}")
        return cls(**d)

    @classmethod
    def from_toml(cls, path_or_text) -> "Style":
        """A style from a TOML file (or TOML text): the ``[style]`` table if there
        is one, else the top level."""
        import tomllib
        p = Path(path_or_text) if not (isinstance(path_or_text, str) and "\n" in path_or_text) else None
        text = p.read_text() if p is not None and p.exists() else str(path_or_text)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise FlipstudyValueError(f"{p or 'style'}: not valid TOML: {e}") from None
        return cls.from_dict(data.get("style", data))

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
DEFAULT_STYLE = Style()
__all__ = ["Style", "DEFAULT_STYLE", "ANTI_ALIASING", "TOL_MUTED", "OKABE_ITO", "rgb", "rgb8"]

"""The picture the participant instructions show: the character, seen from behind,
with its left and right side labelled by their tones (left and right limbs differ
only by tone, so nothing else tells a participant which is which)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import _mpl

#: the joints the labels point at (a built-in clip's names)
_POINTS = {"left": ("LeftForeArm", "LeftLeg"), "right": ("RightForeArm", "RightLeg")}


def side_words(style=None) -> dict:
    """How the tones of ``style`` (a :class:`~flipstudy.render.style.Style`; default
    the default style) tell the sides apart: ``{"left": "lighter", "right":
    "darker"}`` (by CIE L*), or None when the style draws both sides alike
    (``sided = false``).

    Examples
    --------
    >>> side_words()
    {'left': 'lighter', 'right': 'darker'}
    """
    from .sides import rgb_to_lab, side_tones
    from .style import Style, rgb
    st = style if style is not None else Style()
    if not st.sided:
        return None
    tones = (np.array([rgb(c) for c in st.side_colors]) if st.side_colors is not None
             else side_tones(st.body_color, st.side_lightness))
    left, right = (float(rgb_to_lab(tones[k])[0]) for k in (1, 2))
    if abs(left - right) < 1.0:
        return {"left": "coloured", "right": "coloured"}
    return {"left": "lighter", "right": "darker"} if left > right else \
        {"left": "darker", "right": "lighter"}


def sides_image(path, style=None, *, size=(220, 260), dpi: int = 100) -> Path:
    """Write a PNG of the built-in backflip's standing pose in ``style``, seen from
    behind (its left on the picture's left), with its left and right arm and leg
    labelled by side and tone (:func:`side_words`).  Returns ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     png = sides_image(pathlib.Path(tmp) / "sides.png")
    ...     png.read_bytes()[:4]
    b'\\x89PNG'
    """
    from flipstudy.stimuli.synth import builtin

    from ._stills import _fk
    from .camera import fit_camera
    from .scene import scene_for
    from .staging import stage
    from .style import Style, rgb
    st_style = style if style is not None else Style()
    words = side_words(st_style) or {"left": "", "right": ""}
    clip = builtin("backflip")
    names = clip.skeleton.joint_names
    J = _fk(clip, [0.0])[1][0]
    lateral = J[names.index("LeftUpLeg")] - J[names.index("RightUpLeg")]
    lateral[1] = 0.0
    size = (int(size[0]), int(size[1]))
    # looking "across" minus the body's left-to-right axis: from behind, left on the left
    cam = fit_camera(J, direction=-lateral / np.linalg.norm(lateral), size=size, margin=0.1,
                     elevation=12.0, top=0.1)         # top: the head reaches above its joint
    st = stage([clip], camera=cam, size=size, style=st_style)
    R, P, _ = _fk(st.clips[0], [0.0])
    with scene_for(st) as sc:
        ch = sc.character("main", st.bodies[0])
        ch.look(sc.style.body_color, 1.0)
        ch.pose(R[0], P[0])
        img = sc.grab()
    xy = {side: cam.project(P[0][[names.index(j) for j in joints]], size)
          for side, joints in _POINTS.items()}
    plt = _mpl()
    pad = 150                                         # room for a label on each side
    w, h = size[0] + 2 * pad, size[1]
    fig = plt.figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    fig.patch.set_facecolor(rgb(st_style.background))
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, w), ax.set_ylim(h, 0), ax.axis("off")
    ax.imshow(img, extent=(pad, pad + size[0], size[1], 0))
    colour = rgb(st_style.label_color)
    for side, x_text, ha in (("left", 8, "left"), ("right", w - 8, "right")):
        text = f"{side}\narm and leg\n({words[side]})" if words[side] else side
        y_text = 0.42 * h
        for x, y in xy[side]:
            ax.annotate("", xy=(x + pad, y), xytext=(x_text + (104 if ha == "left" else -104), y_text),
                        arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.2})
        ax.text(x_text, y_text, text, ha=ha, va="center", fontsize=11, color=colour,
                linespacing=1.2)
    path = Path(path)
    fig.savefig(path, dpi=dpi, facecolor=fig.get_facecolor())
    plt.close(fig)
    return path


__all__ = ["side_words", "sides_image"]

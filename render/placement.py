"""Placing clips for a picture: moved to the take-off spot, turned to travel along
one direction, grouped by base clip.

These are the steps :func:`flipstudy.render.staging.stage` takes before it fits the
camera (and the module :mod:`flipstudy.render.staging` re-exports them).  The
take-off spot is the COM in the *last frame on the ground* (``takeoff − 1``), so an
edit of the flight does not move the anchor.
"""
from __future__ import annotations

import numpy as np

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion.clip import Clip
from flipstudy.stimuli.physics import center_of_mass

from flipstudy.stimuli.edit.reposition import place, translate  # noqa: F401  (motion operations)

from .camera import UP


def takeoff_com(clip: Clip, body: Body, takeoff: int | None) -> np.ndarray:
    """COM of the take-off spot: the last frame on the ground, ``takeoff − 1``
    (``takeoff`` is the first airborne frame); frame 0 without a flight."""
    f = 0 if takeoff is None else int(np.clip(takeoff - 1, 0, clip.num_frames - 1))
    return center_of_mass(clip.slice(f, f + 1), body)[0]



def align_takeoff(clips, takeoffs, bodies=None) -> tuple[list, np.ndarray]:
    """Clips moved horizontally so each take-off COM (:func:`takeoff_com`) is at
    x = z = 0 (heights are kept: the ground stays at its level).  Returns
    (clips, offsets (K,3)).

    Parameters
    ----------
    clips : list of Clip
    takeoffs : list of int or None
        Each clip's first airborne frame.
    bodies : list of Body, optional
        Default: each clip's ``Body.from_clip``.

    Returns
    -------
    clips : list of Clip
    offsets : ndarray, shape (K, 3)

    Examples
    --------
    >>> from flipstudy import Body, analyse, builtin
    >>> clip = builtin("jump")
    >>> a = analyse(clip)
    >>> from flipstudy.render import align_takeoff
    >>> moved, offsets = align_takeoff([clip], [a.takeoff])
    >>> offsets.shape, float(offsets[0, 1])              # heights are kept
    ((1, 3), 0.0)
    """
    bodies = bodies or [Body.from_clip(c) for c in clips]
    out, offs = [], []
    for c, t, b in zip(clips, takeoffs, bodies):
        com = takeoff_com(c, b, t)
        o = np.array([-com[0], 0.0, -com[2]])
        out.append(translate(c, o))
        offs.append(o)
    return out, np.array(offs).reshape(-1, 3)



def travel_direction(clip: Clip, body: Body, takeoff: int | None, landing: int | None,
                     tiny: float = 0.05) -> np.ndarray | None:
    """Horizontal unit direction of the COM's travel from take-off to landing,
    or ``None`` when it travels less than ``tiny`` metres or has no flight."""
    if takeoff is None or landing is None:
        return None
    com = center_of_mass(clip.slice(int(takeoff), int(landing) + 1), body)
    d = com[-1] - com[0]
    d[1] = 0.0
    n = np.linalg.norm(d)
    return d / n if n >= tiny else None



def jump_direction(clip: Clip, body: Body, takeoff: int | None, landing: int | None,
                   tiny: float = 0.05) -> np.ndarray:
    """Horizontal unit direction of the COM's travel from take-off to landing;
    +Z when the travel is under ``tiny`` metres or there is no flight.

    Parameters
    ----------
    clip : Clip
    body : Body
    takeoff, landing : int or None
        The flight's frames (None: no flight).
    tiny : float
        Metres of travel below which the direction is +Z.

    Returns
    -------
    ndarray, shape (3,)
        A horizontal unit vector.

    Examples
    --------
    >>> from flipstudy import Body, analyse, builtin
    >>> clip = builtin("jump")
    >>> a = analyse(clip)
    >>> from flipstudy.render import jump_direction
    >>> d = jump_direction(clip, a.body, a.takeoff, a.landing)
    >>> round(float(d @ d), 6), float(d[1])
    (1.0, 0.0)
    """
    d = travel_direction(clip, body, takeoff, landing, tiny)
    return np.array([0.0, 0.0, 1.0]) if d is None else d



def _prefix_key(clip: Clip, takeoff: int | None) -> str:
    """Identity of a clip's motion before take-off (its first ``takeoff``
    frames): stimuli made from one base clip by editing the flight share it."""
    import hashlib
    n = clip.num_frames if takeoff is None else max(1, int(takeoff))
    h = hashlib.sha256()
    h.update(str((n, clip.skeleton.joint_names)).encode())
    for a in (clip.skeleton.offsets, clip.root_pos[:n], clip.rotations[:n]):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()



def nearest_axis(direction) -> np.ndarray:
    """The horizontal axis (±X or ±Z) nearest to ``direction``.

    >>> nearest_axis([0.3, 0.0, -0.9]).tolist()
    [0.0, 0.0, -1.0]
    """
    axes = np.array([(1.0, 0, 0), (-1.0, 0, 0), (0, 0, 1.0), (0, 0, -1.0)])
    return axes[int(np.argmax(axes @ np.asarray(direction, float)))].copy()



def orient_yaws(clips, bodies, takeoffs, landings, direction) -> list[float]:
    """Degrees to turn each clip about the vertical so that it travels along
    ``direction``.  Clips with the same motion before take-off (one base clip
    and its edits) get one angle, from the first of them, so they stay
    identical before take-off; clips that hardly travel are not turned.

    Parameters
    ----------
    clips, bodies : list
        The clips and their bodies.
    takeoffs, landings : list of int or None
    direction : array_like, shape (3,)
        The horizontal direction to travel along.

    Returns
    -------
    list of float
        Degrees, one per clip.

    Examples
    --------
    >>> from flipstudy import Body, analyse, builtin
    >>> clip = builtin("jump")
    >>> a = analyse(clip)
    >>> from flipstudy.render import orient_yaws
    >>> yaws = orient_yaws([clip, clip], [a.body, a.body], [a.takeoff] * 2, [a.landing] * 2, (0, 0, 1))
    >>> len(yaws), yaws[0] == yaws[1]                   # the same motion: one angle
    (2, True)
    """
    target = np.asarray(direction, float)
    yaw_of: dict = {}
    out = []
    for c, b, t0, t1 in zip(clips, bodies, takeoffs, landings):
        key = _prefix_key(c, t0)
        if key not in yaw_of:
            d = travel_direction(c, b, t0, t1)
            if d is None:
                yaw_of[key] = 0.0
            else:
                ang = float(np.degrees(np.arctan2(np.cross(d, target) @ UP, d @ target)))
                # a half turn is +180 whatever the sign of a zero cross product (arctan2
                # gives -180 for -0.0): the same rotation, one spelling in render.json
                yaw_of[key] = ang + 360.0 if ang <= -180.0 + 1e-9 else ang
        out.append(yaw_of[key])
    return out



def base_clip_groups(clips, takeoffs, names=None) -> dict:
    """Indices of ``clips`` grouped by base clip: by ``names`` (one per clip,
    e.g. the manifest's ``clip`` column) where given and not empty, else by the
    motion before take-off (stimuli made from one base clip by editing the
    flight share it).  Returns ``{key: [indices]}`` in first-seen order.

    Examples
    --------
    >>> from flipstudy import builtin
    >>> a, b = builtin("backflip"), builtin("frontflip")
    >>> list(base_clip_groups([a, b, a], [157, 157, 157]).values())
    [[0, 2], [1]]
    >>> base_clip_groups([a, b], [157, 157], names=["x", "x"])
    {'x': [0, 1]}
    """
    out: dict = {}
    for k, (c, t) in enumerate(zip(clips, takeoffs)):
        name = names[k] if names is not None else None
        out.setdefault(name or _prefix_key(c, t), []).append(k)
    return out

"""Motion operations on a whole clip, in one module: moving the centre of mass
(Section 5.4: the COM of a pose is an affine function of the root translation, so
shifting the root by d shifts the COM by d and leaves the angular momentum about the
COM untouched), a ballistic path, turning about a point, translating, placing on the
study's take-off spot, and sampling at other times (:func:`resample`,
:func:`poses_at`; :func:`resample_to`, a base clip at the design's frame rate).
:mod:`flipstudy.render` and :mod:`flipstudy.stimuli.stimset` re-export the ones they use."""

from __future__ import annotations

import numpy as np

from ..body import Body
from ..motion.clip import Clip
from ..physics import center_of_mass


def move_com(clip: Clip, body: Body, frames: slice, new_com: np.ndarray,
             carry: bool = True, com: np.ndarray | None = None) -> Clip:
    """Put the COM of ``frames`` on ``new_com`` (n,3) by shifting the root; with
    ``carry`` every later frame is offset by the shift of the last one, so the
    motion continues from where the flight now ends.

    Parameters
    ----------
    clip : Clip
    body : Body
    frames : slice
        The frames to move.
    new_com : ndarray, shape (n, 3)
        Their COM, metres.
    carry : bool
        Offset every later frame by the last one's shift.
    com : ndarray, optional
        The clip's COM (F,3), when already computed.

    Returns
    -------
    Clip

    Examples
    --------
    The flight of the built-in back flip 10 cm lower:

    >>> import numpy as np
    >>> from flipstudy import Body, analyse, builtin
    >>> from flipstudy.stimuli.physics import center_of_mass
    >>> clip = builtin("backflip")
    >>> body = Body.from_clip(clip)
    >>> a = analyse(clip, body)
    >>> flight, com = slice(a.takeoff, a.landing + 1), center_of_mass(clip, body)
    >>> lower = move_com(clip, body, flight, com[flight] - [0, 0.1, 0])
    >>> bool(np.allclose(center_of_mass(lower, body)[flight], com[flight] - [0, 0.1, 0]))
    True
    >>> (center_of_mass(lower, body)[-1] - com[-1]).round(3) + 0.0   # carried on to the end
    array([ 0. , -0.1,  0. ])
    """
    if com is None:
        com = center_of_mass(clip, body)
    idx = np.arange(clip.num_frames)[frames]
    new_com = np.asarray(new_com, dtype=float)
    if new_com.shape != (idx.size, 3):
        raise ValueError(f"new_com must be ({idx.size}, 3) for the {idx.size} frames, got {new_com.shape}")
    shift = np.zeros_like(clip.root_pos)
    shift[idx] = new_com - com[idx]
    if carry and idx.size and idx[-1] + 1 < clip.num_frames:
        shift[idx[-1] + 1:] = shift[idx[-1]]
    return clip.replace(root_pos=clip.root_pos + shift)


def ballistic_path(c0: np.ndarray, v0: np.ndarray, g: float, t: np.ndarray) -> np.ndarray:
    """(n,3) points of a ballistic path from ``c0`` with velocity ``v0`` under
    gravity ``g`` along −Y, at times ``t`` (s).

    Parameters
    ----------
    c0, v0 : ndarray, shape (3,)
        Start point (m) and velocity (m/s).
    g : float
        m/s², along −Y.
    t : ndarray, shape (n,)
        Seconds.

    Returns
    -------
    ndarray, shape (n, 3)

    Examples
    --------
    >>> ballistic_path(np.zeros(3), np.array([1.0, 4.9, 0.0]), 9.81, np.array([0.0, 0.5, 1.0])).round(3)
    array([[ 0.   ,  0.   ,  0.   ],
           [ 0.5  ,  1.224,  0.   ],
           [ 1.   , -0.005,  0.   ]])
    """
    t = np.asarray(t, dtype=float)[:, None]
    p = np.asarray(c0, float)[None] + np.asarray(v0, float)[None] * t
    p[:, 1] -= 0.5 * g * t[:, 0] ** 2
    return p


def rotate(clip: Clip, rotation, center: np.ndarray) -> Clip:
    """The whole clip rotated rigidly by ``rotation`` (a scipy ``Rotation``, one
    for all frames or one per frame) about the point(s) ``center`` ((3,) or
    (F,3)).  Angular momentum rotates with it: rotating about an axis along L
    through the COM leaves L unchanged (Section 5.1).

    Parameters
    ----------
    clip : Clip
    rotation : scipy.spatial.transform.Rotation
        One rotation, or one per frame.
    center : ndarray, shape (3,) or (F, 3)
        The point(s) turned about, metres.

    Returns
    -------
    Clip

    Examples
    --------
    A quarter turn about the vertical keeps every height:

    >>> from scipy.spatial.transform import Rotation
    >>> from flipstudy import builtin
    >>> clip = builtin("jump")
    >>> turned = rotate(clip, Rotation.from_rotvec([0, np.pi / 2, 0]), np.zeros(3))
    >>> bool(np.allclose(turned.joint_positions()[..., 1], clip.joint_positions()[..., 1]))
    True"""
    from scipy.spatial.transform import Rotation
    center = np.broadcast_to(np.asarray(center, float), clip.root_pos.shape)
    root = Rotation.from_quat(clip.rotations[:, 0])
    rot = clip.rotations.copy()
    rot[:, 0] = (rotation * root).as_quat()
    pos = center + rotation.apply(clip.root_pos - center)
    jp = clip.joint_pos
    return clip.replace(root_pos=pos, rotations=rot, joint_pos=jp)


def translate(clip: Clip, offset) -> Clip:
    """The clip moved by ``offset`` (3,) metres.

    Parameters
    ----------
    clip : Clip
    offset : array_like, shape (3,)
        Metres.

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy import builtin
    >>> from flipstudy.render import translate
    >>> clip = builtin("jump")
    >>> moved = translate(clip, (1.0, 0.0, 0.0))
    >>> (moved.joint_positions() - clip.joint_positions())[0, 0].round(6).tolist()
    [1.0, 0.0, 0.0]
    """
    o = np.asarray(offset, float)
    if not np.any(o):
        return clip
    return clip.replace(root_pos=clip.root_pos + o)



def place(clip: Clip, offset, yaw_deg: float = 0.0) -> Clip:
    """The clip moved by ``offset`` (3,), then turned by ``yaw_deg`` degrees
    about the vertical axis through the origin (the study's take-off spot).

    Parameters
    ----------
    clip : Clip
    offset : array_like, shape (3,)
        Metres.
    yaw_deg : float
        Degrees about the vertical axis through the origin.

    Returns
    -------
    Clip

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy import builtin
    >>> from flipstudy.render import place
    >>> clip = builtin("jump")
    >>> turned = place(clip, (0.0, 0.0, 0.0), 90.0)
    >>> P, Q = clip.joint_positions(), turned.joint_positions()
    >>> bool(np.allclose(P[..., 1], Q[..., 1]))                     # heights kept
    True
    >>> bool(np.allclose(np.hypot(P[..., 0], P[..., 2]), np.hypot(Q[..., 0], Q[..., 2])))
    True
    """
    clip = translate(clip, offset)
    if yaw_deg:
        from scipy.spatial.transform import Rotation
        clip = rotate(clip, Rotation.from_rotvec([0.0, np.radians(yaw_deg), 0.0]), np.zeros(3))
    return clip


def resample(clip: Clip, fps: float, start: float = 0.0, stop: float | None = None) -> Clip:
    """The clip sampled at display times ``start, start + 1/fps, …, ≤ stop``
    (seconds; default the whole clip): rotations slerped, root and joint
    translations linear (no uneven frame dropping).  The result has ``fps``
    frames per second.

    Parameters
    ----------
    clip : Clip
    fps : float
        The new frame rate.
    start, stop : float
        Seconds (``stop`` None: the clip's end).

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy import builtin
    >>> clip = builtin("backflip")                    # 120 fps
    >>> v = resample(clip, 60.0)
    >>> v.fps, v.num_frames, v.duration <= clip.duration
    (60.0, 199, True)
    """
    from .timing import sample
    fps = float(fps)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"resample: fps must be a positive number, got {fps!r}")
    stop = clip.duration if stop is None else min(float(stop), clip.duration)
    n = int(np.floor((stop - start) * fps + 1e-9)) + 1
    src = (start + np.arange(max(n, 1)) / fps) * clip.fps
    if clip.num_frames == 1:
        return clip.replace(fps=fps)
    if np.isclose(fps, clip.fps) and abs(start * clip.fps - round(start * clip.fps)) < 1e-9:
        i0 = int(round(start * clip.fps))
        return clip.slice(i0, i0 + n).with_fps(fps)
    return sample(clip, src).with_fps(fps)



def poses_at(clip: Clip, times) -> Clip:
    """A clip whose frames are ``clip`` at the given times (seconds, any order),
    interpolated as in :func:`resample`.

    Parameters
    ----------
    clip : Clip
    times : array_like
        Seconds.

    Returns
    -------
    Clip
        One frame per time.

    Examples
    --------
    >>> import numpy as np
    >>> from flipstudy import builtin
    >>> from flipstudy.render import poses_at
    >>> clip = builtin("jump")
    >>> two = poses_at(clip, [0.5, 0.0])
    >>> two.num_frames, bool(np.allclose(two.joint_positions()[1], clip.joint_positions()[0]))
    (2, True)
    """
    from .timing import sample
    t = np.atleast_1d(np.asarray(times, dtype=float))
    return sample(clip, np.clip(t * clip.fps, 0, clip.num_frames - 1))


def resample_to(clip: Clip, fps: float) -> Clip:
    """``clip`` at ``fps`` frames per second, the same motion in time (slerp of the
    rotations, linear root): frame k is the source at time k / fps; its ``meta``
    says it was resampled to the design's ``[study] fps`` (what
    :mod:`flipstudy.stimuli.stimset` does with a base clip of another rate).

    Parameters
    ----------
    clip : Clip
    fps : float
        The new frame rate.

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy import builtin
    >>> c = resample_to(builtin("jump"), 60.0)                 # 120 fps in
    >>> c.fps, c.meta["fps_source"]
    (60.0, 'read, resampled to 60 ([study] fps)')
    """
    from .timing import sample
    n = int(np.floor((clip.num_frames - 1) * fps / clip.fps + 1e-9)) + 1
    out = sample(clip, np.arange(n) * (clip.fps / fps))
    meta = dict(out.meta)
    meta["fps_read"] = clip.meta.get("fps_read", clip.fps)
    meta["fps_source"] = f"{clip.meta.get('fps_source', 'read')}, resampled to {fps:g} ([study] fps)"
    return Clip(out.skeleton, float(fps), out.root_pos, out.rotations, out.joint_pos, meta)

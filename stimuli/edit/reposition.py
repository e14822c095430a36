"""Moving the centre of mass (Section 5.4): the COM of a pose is an affine
function of the root translation, so shifting the root by d shifts the COM by d
and leaves the angular momentum about the COM untouched."""

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
    gravity ``g`` along −Y, at times ``t`` (s)."""
    t = np.asarray(t, dtype=float)[:, None]
    p = np.asarray(c0, float)[None] + np.asarray(v0, float)[None] * t
    p[:, 1] -= 0.5 * g * t[:, 0] ** 2
    return p


def rotate(clip: Clip, rotation, center: np.ndarray) -> Clip:
    """The whole clip rotated rigidly by ``rotation`` (a scipy ``Rotation``, one
    for all frames or one per frame) about the point(s) ``center`` ((3,) or
    (F,3)).  Angular momentum rotates with it: rotating about an axis along L
    through the COM leaves L unchanged (Section 5.1)."""
    from scipy.spatial.transform import Rotation
    center = np.broadcast_to(np.asarray(center, float), clip.root_pos.shape)
    root = Rotation.from_quat(clip.rotations[:, 0])
    rot = clip.rotations.copy()
    rot[:, 0] = (rotation * root).as_quat()
    pos = center + rotation.apply(clip.root_pos - center)
    jp = clip.joint_pos
    return clip.replace(root_pos=pos, rotations=rot, joint_pos=jp)

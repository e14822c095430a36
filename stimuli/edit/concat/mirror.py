"""Mirroring a motion left ↔ right (a right kick becomes a left kick), for the
concatenation's reverse-rule examples (Shum, Komura & Yadav 2009)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ...body import Body, _split_name
from ...motion.clip import Clip, derived_meta
from .motion import torso_facing
from flipstudy.errors import ConcatError
from .phases import UP


def mirror_pairs(sk) -> np.ndarray:
    """(J,) index of each joint's left/right partner (itself for the joints on the
    midline), paired by name ('LeftArm' ↔ 'RightArm', 'CC_Base_L_Thigh' ↔
    'CC_Base_R_Thigh', ...).

    Parameters
    ----------
    sk : Skeleton

    Returns
    -------
    ndarray, shape (J,)

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> sk = builtin("backflip").skeleton
    >>> pairs = mirror_pairs(sk)
    >>> sk.joint_names[pairs[sk.joint_names.index("LeftArm")]], sk.joint_names[pairs[0]]
    ('RightArm', 'Hips')
    """
    sp = [_split_name(n) for n in sk.joint_names]
    key = {(s, p, sk.depth()[j]): j for j, (s, p) in enumerate(sp) if s}
    out = np.arange(sk.num_joints)
    for j, (s, p) in enumerate(sp):
        if s:
            k = key.get(("r" if s == "l" else "l", p, sk.depth()[j]))
            if k is None:
                raise ConcatError(f"mirror: joint {sk.joint_names[j]!r} has no partner on the other side")
            out[j] = k
    return out


def mirror(clip: Clip, plane: str = "sagittal", body: Body | None = None) -> Clip:
    """The motion mirrored left ↔ right: a right kick becomes a left kick.

    ``plane="sagittal"`` mirrors across the performer's own midline plane at the
    first frame (vertical, through the root, along the torso's facing), so the
    mirrored motion starts where and as the original does; ``plane="x"`` across
    the world's x = 0 plane.  Joints are mirrored in their rest frames (BVH rest
    frames are the world's, and the rest pose is symmetric about its x = 0
    plane): each local rotation R becomes M R M with M = diag(−1, 1, 1), i.e. the
    quaternion (x, y, z, w) → (x, −y, −z, w), left and right joints swap, and the
    root takes the world reflection (R₀ → M_n R₀ M, p → M_n p).  The offsets stay
    the skeleton's own, so an asymmetric rest pose mirrors approximately: the
    largest left/right difference of the rest pose is :func:`rest_asymmetry`.
    ``meta`` records the provenance: ``name`` (with ``-mirrored``) and ``edit``.

    >>> import numpy as np
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import mirror
    >>> c = builtin("backflip")
    >>> m = mirror(c, plane="x")
    >>> m.meta["name"], bool(np.allclose(mirror(m, plane="x").joint_positions(), c.joint_positions()))
    ('backflip-mirrored', True)

    Parameters
    ----------
    clip : Clip
    plane : {"sagittal", "x"}
    body : Body, optional
        For the torso's facing (default: the skeleton's table body).

    Returns
    -------
    Clip

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> clip = builtin("backflip")
    >>> mirror(clip).num_frames == clip.num_frames
    True
    """
    sk = clip.skeleton
    pair = mirror_pairs(sk)
    Mx = np.diag([-1.0, 1.0, 1.0])
    if plane == "x":
        Mn = Mx
    elif plane == "sagittal":
        body = body if body is not None else Body.from_skeleton(sk)
        f = torso_facing(clip.slice(0, 1), body)[0]
        lat = np.cross(f, UP)
        lat /= np.linalg.norm(lat)
        Mn = np.eye(3) - 2.0 * np.outer(lat, lat)
    else:
        raise ConcatError(f"mirror plane must be 'sagittal' or 'x', got {plane!r}")
    q = clip.rotations[:, pair] * np.array([1.0, -1.0, -1.0, 1.0])     # M R M for every joint
    Q = Rotation.from_matrix(Mn @ Mx)                                    # a turn about the vertical
    q[:, 0] = (Q * Rotation.from_quat(q[:, 0])).as_quat()                # root: M_n R₀ M
    p0 = clip.root_pos[0]
    root = (np.array(clip.root_pos) - p0) @ Mn.T + p0
    meta = {**derived_meta(clip.meta, f"mirrored ({plane})"),
            "name": f"{clip.meta.get('name', 'clip')}-mirrored"}
    jp = None if clip.joint_pos is None else clip.joint_pos[:, pair] * np.diag(Mx)
    return clip.replace(root_pos=root, rotations=q, joint_pos=jp, meta=meta)


def rest_asymmetry(sk) -> tuple[float, str]:
    """How far :func:`mirror` is from exact for skeleton ``sk``: the largest
    distance (metres) between a joint of the rest pose mirrored across x = 0 and
    its partner's rest position, and that joint's name (0 for a symmetric rest pose).

    Parameters
    ----------
    sk : Skeleton

    Returns
    -------
    distance : float
        Metres.
    joint : str

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.edit.concat import rest_asymmetry
    >>> d, joint = rest_asymmetry(builtin("backflip").skeleton)
    >>> d < 1e-9
    True
    """
    pair = mirror_pairs(sk)
    P = sk.rest_positions()
    d = np.linalg.norm(P * np.array([-1.0, 1.0, 1.0]) - P[pair], axis=1)
    return float(d.max()), sk.joint_names[int(np.argmax(d))]

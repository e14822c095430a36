"""Pose similarity (Majkowska & Faloutsos 2007, Appendix A).

The distance between two frames ignores their positions and their rotation
about the angular-momentum axis u: the second frame is first turned about u by
the angle φ that the root's orientation has turned about u (the twist of
R₂R₁ᵀ about u), then the distance is a weighted sum of differences in global
orientation (the root), joint angles and angular velocities, with the paper's
weights::

    root 2, trunk 0.7, thigh 0.7, knee 0.5, shoulder 0.3, elbow 0.1

The parts are found through the body model's landmarks, so the same weights
apply to the built-in skeleton and to every CMU, MASS or iClone rig: *thigh* is
the hip joint's rotation relative to the pelvis, *knee* the knee's relative to
the thigh, *shoulder* and *elbow* likewise, and *trunk* the chest (the
shoulders' common ancestor) relative to the pelvis, whatever the number of
spine joints between them.  Angles are geodesic (radians); angular velocities
(rad/s) enter multiplied by ``tau`` seconds (default 0.1 s, a tenth of a
second of motion).

All frame pairs are computed at once from (F, K, 3, 3) arrays, no loop over
pairs.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..body import Body
from ..motion.clip import Clip, angular_velocity

#: the paper's weights (Appendix A)
WEIGHTS = {"root": 2.0, "trunk": 0.7, "thigh": 0.7, "knee": 0.5, "shoulder": 0.3, "elbow": 0.1}


def weighted_parts(body: Body) -> list[tuple[str, float, int, int]]:
    """(name, weight, reference joint, joint) of every weighted part but the root:
    the part's orientation is that of ``joint`` relative to ``reference joint``."""
    sk = body.skeleton
    ix = {k: sk.index(v) for k, v in body.landmarks.items() if isinstance(v, str)}
    pelvis = ix["pelvis"]
    chest = sk.common_ancestor(ix["shoulder_l"], ix["shoulder_r"])
    parts = [("trunk", WEIGHTS["trunk"], pelvis, chest)]
    for s in "lr":
        parts += [(f"thigh_{s}", WEIGHTS["thigh"], pelvis, ix[f"hip_{s}"]),
                  (f"knee_{s}", WEIGHTS["knee"], ix[f"hip_{s}"], ix[f"knee_{s}"]),
                  (f"shoulder_{s}", WEIGHTS["shoulder"], chest, ix[f"shoulder_{s}"]),
                  (f"elbow_{s}", WEIGHTS["elbow"], ix[f"shoulder_{s}"], ix[f"elbow_{s}"])]
    return parts


@dataclass
class PoseFeatures:
    """What the distance needs of a set of frames (see :func:`pose_features`)."""

    frames: np.ndarray          # (F,) source frame indices
    axis: np.ndarray            # (3,) unit angular-momentum axis u
    root_q: np.ndarray          # (F,4) world root orientation (scipy x,y,z,w)
    root_w: np.ndarray          # (F,3) world root angular velocity, rad/s
    part_R: np.ndarray          # (F,K,3,3) part orientations relative to their reference
    part_w: np.ndarray          # (F,K,3) their angular velocities (reference frame), rad/s
    weights: np.ndarray         # (K,) part weights
    names: list


def pose_features(clip: Clip, body: Body, axis, frames=None) -> PoseFeatures:
    """Features of ``frames`` (default all) of ``clip`` for :func:`distance_matrix`;
    ``axis`` is the angular-momentum direction (any length)."""
    u = np.asarray(axis, float)
    n = np.linalg.norm(u)
    if not n > 0:
        raise ValueError("pose similarity needs a non-zero angular-momentum axis")
    u = u / n
    frames = np.arange(clip.num_frames) if frames is None else np.asarray(frames, int)
    R = clip.joint_rotations()                                  # (F,J,3,3) world
    W = clip.angular_velocities()                               # (F,J,3) world
    parts = weighted_parts(body)
    ref = np.array([p[2] for p in parts])
    jnt = np.array([p[3] for p in parts])
    rel = np.einsum("fkba,fkbc->fkac", R[:, ref], R[:, jnt])    # R_refᵀ R_joint, all frames
    rel_w = angular_velocity(rel, clip.fps)                     # in the reference's frame
    root_q = Rotation.from_matrix(R[frames, 0]).as_quat()
    return PoseFeatures(frames, u, root_q, W[frames, 0], rel[frames], rel_w[frames],
                        np.array([p[1] for p in parts]), [p[0] for p in parts])


def _geodesic(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """(Fa,Fb,K) angles between rotation matrices Ra (Fa,K,3,3) and Rb (Fb,K,3,3)."""
    tr = np.einsum("akij,bkij->abk", Ra, Rb)                    # trace(Raᵀ Rb)
    return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))


def twist_angles(qa: np.ndarray, qb: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For all pairs: the twist φ (Fa,Fb) of the relative rotation q_b q_a⁻¹ about
    ``u`` (radians, in (−π, π]) and the angle left after removing it (the swing)."""
    # q_rel = q_b * conj(q_a), written for all pairs (Hamilton product, x,y,z,w)
    av, aw = -qa[:, :3], qa[:, 3]
    bv, bw = qb[:, :3], qb[:, 3]
    w = bw[None, :] * aw[:, None] - np.einsum("bi,ai->ab", bv, av)
    v = (bw[None, :, None] * av[:, None, :] + aw[:, None, None] * bv[None, :, :]
         + np.cross(bv[None, :, :], av[:, None, :]))
    vu = v @ u
    phi = 2.0 * np.arctan2(vu, w)
    phi = (phi + np.pi) % (2.0 * np.pi) - np.pi
    swing = 2.0 * np.arccos(np.clip(np.sqrt(w ** 2 + vu ** 2), 0.0, 1.0))
    return phi, swing


def distance_matrix(a: PoseFeatures, b: PoseFeatures | None = None, tau: float = 0.1
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Appendix A distance for every pair (frame i of ``a``, frame j of ``b``):
    returns ``D`` (Fa,Fb) and ``phi`` (Fa,Fb), the turn about u (radians) that
    takes frame i's root orientation to frame j's (what frame j is rotated back
    by before comparing)."""
    b = a if b is None else b
    u = a.axis
    phi, swing = twist_angles(a.root_q, b.root_q, u)
    # root angular velocity of b turned back by −φ about u (Rodrigues, all pairs)
    c, s = np.cos(-phi)[..., None], np.sin(-phi)[..., None]
    wb = b.root_w[None, :, :]
    wb_rot = wb * c + np.cross(u, wb) * s + u * (wb @ u)[..., None] * (1.0 - c)
    d_root = swing + tau * np.linalg.norm(a.root_w[:, None, :] - wb_rot, axis=-1)
    ang = _geodesic(a.part_R, b.part_R)                                     # (Fa,Fb,K)
    vel = np.linalg.norm(a.part_w[:, None] - b.part_w[None, :], axis=-1)    # (Fa,Fb,K)
    D = WEIGHTS["root"] * d_root + (ang + tau * vel) @ a.weights
    return D, phi

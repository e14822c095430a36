"""The jumper: the project's humanoid skeleton, its de Leva body, joint limits,
and batched forward kinematics for the controller.

Poses are arrays with a leading batch axis: root position (N,3) and local joint
rotations (N,J,4) as scipy quaternions (x, y, z, w).  The pelvis (root) faces
+Z, upright — rolled about the forward axis in the crouches of uneven legs
(:func:`.uneven.pelvis_roll`) and turned in flight; the controller moves its
position, the legs (hip, knee, ankle, toe) and the upper body (Spine, Spine1).
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.spatial.transform import Rotation

from ..body import Body
from ..motion.clip import Clip
from ..physics import center_of_mass
from ..synth.skeleton import _HEEL_BEHIND_ANKLE, make_skeleton, standing_root_height
from .muscles import bone_angle

SIDES = ("l", "r")
_NAMES = {"l": "Left", "r": "Right"}

#: joint limits (degrees) as intrinsic Euler angles (order, lows, highs), after
#: Boone & Azen's ranges of motion (rounded).  Signs in the skeleton's frames:
#: hip flexion (thigh forward) is −X, knee flexion +X, ankle dorsiflexion −X.
LIMITS = {
    "hip": ("XZY", (-125.0, -40.0, -15.0), (30.0, 40.0, 15.0)),
    "knee": (0.0, 150.0),                         # hinge about local X
    "ankle": ("XZY", (-45.0, -35.0, -20.0), (55.0, 35.0, 20.0)),
    "spine": ("XZY", (-15.0, -20.0, -10.0), (25.0, 20.0, 10.0)),   # each of Spine, Spine1
}
FOOT_HALF_WIDTH = 0.026      # fraction of height: half the width of a foot (0.045 m at 1.75 m)


@dataclass
class Jumper:
    """Skeleton, body and the geometry the controller needs.

    Parameters
    ----------
    height : float
        Standing height, metres.
    mass : float
        kg.

    Examples
    --------
    >>> j = Jumper()
    >>> round(j.standing_pelvis, 3), j.skeleton.num_joints
    (0.98, 21)
    """

    height: float = 1.75
    mass: float = 70.0
    skeleton: object = field(init=False)
    body: Body = field(init=False)

    def __post_init__(self):
        if not (np.isfinite(self.height) and 1.0 <= self.height <= 2.5):
            raise FlipstudyValueError(f"height: expected a standing height between 1.0 and 2.5 m, got {self.height!r}")
        if not (np.isfinite(self.mass) and self.mass > 0):
            raise FlipstudyValueError(f"mass: expected a positive body mass in kg, got {self.mass!r}")
        self.skeleton = make_skeleton(self.height)
        self.body = Body.from_skeleton(self.skeleton, self.mass)
        sk = self.skeleton
        self.J = sk.num_joints
        self.idx = {}
        for s in SIDES:
            n = _NAMES[s]
            self.idx[f"hip_{s}"] = sk.index(f"{n}UpLeg")
            self.idx[f"knee_{s}"] = sk.index(f"{n}Leg")
            self.idx[f"ankle_{s}"] = sk.index(f"{n}Foot")
            self.idx[f"toe_{s}"] = sk.index(f"{n}ToeBase")
        self.idx["spine"] = sk.index("Spine")
        self.idx["spine1"] = sk.index("Spine1")
        off = sk.offsets
        self.hip_offset = {s: off[self.idx[f"hip_{s}"]].copy() for s in SIDES}   # pelvis frame
        self.thigh = float(-off[self.idx["knee_l"]][1])
        self.shank = float(-off[self.idx["ankle_l"]][1])
        self.ball_offset = off[self.idx["toe_l"]].copy()       # ankle → ball of the foot (foot frame)
        self.toe_tip = sk.end_sites_of(self.idx["toe_l"])[0].copy()   # ball → toe tip
        H = self.height
        self.ankle_height = float(-self.ball_offset[1])
        self.heel_back = _HEEL_BEHIND_ANKLE * H
        self.foot_half_width = FOOT_HALF_WIDTH * H
        self.standing_pelvis = standing_root_height(sk)

    # ------------------------------------------------------------- stance
    def feet(self, centre=(0.0, 0.0, 0.0)) -> dict:
        """Ankle positions (3,) of the standing stance with the feet's midpoint
        (between the ankles, on the surface) at ``centre``."""
        c = np.asarray(centre, float)
        return {s: c + np.array([self.hip_offset[s][0], self.ankle_height, 0.0]) for s in SIDES}

    def foot_corners(self, ankle: np.ndarray) -> np.ndarray:
        """(4,3) heel/toe corners of a flat foot whose ankle is at ``ankle`` (...,3)."""
        a = np.asarray(ankle, float)
        w, y = self.foot_half_width, -self.ankle_height
        toe = self.ball_offset[2] + self.toe_tip[2]
        local = np.array([[-w, y, -self.heel_back], [w, y, -self.heel_back], [w, y, toe], [-w, y, toe]])
        return a[..., None, :] + local

    # ---------------------------------------------------------------- poses
    def rest_quats(self, n: int) -> np.ndarray:
        q = np.zeros((n, self.J, 4))
        q[..., 3] = 1.0
        return q

    def clip(self, root, quats, fps: float = 120.0, meta=None) -> Clip:
        return Clip(self.skeleton, fps, np.asarray(root, float), np.asarray(quats, float), meta=meta)

    def com(self, root, quats) -> np.ndarray:
        """(N,3) whole-body COM (the project's Body) of the poses."""
        return center_of_mass(self.clip(root, quats), self.body)

    def positions(self, root, quats) -> np.ndarray:
        return self.clip(root, quats).joint_positions()

    def lean_quats(self, lean: np.ndarray) -> np.ndarray:
        """(N,4) quaternion of one spine joint for a lean (N,2) = (forward tilt
        about X, sideways tilt about Z), shared equally by Spine and Spine1:
        intrinsic X then Z, so a sideways tilt moves the upper body sideways
        however far it leans forward."""
        lean = np.atleast_2d(lean)
        return Rotation.from_euler("XZ", lean / 2.0).as_quat()

    # -------------------------------------------------------------- muscles
    def muscle_angles(self, P: np.ndarray) -> np.ndarray:
        """(N,6) effective angle between the bones of each muscle (rad), from
        world joint positions P (N,J,3) — order of :data:`muscles.MUSCLES`.
        Hip: pelvis up-axis / thigh; knee: thigh / shank; ankle: shank / foot
        relative to the standing angle, stretched only by dorsiflexion."""
        out = []
        up = np.array([0.0, 1.0, 0.0])
        for s in SIDES:
            h, k, a, t = (P[:, self.idx[f"{n}_{s}"]] for n in ("hip", "knee", "ankle", "toe"))
            out.append(bone_angle(h + up, h, k))
            out.append(bone_angle(h, k, a))
            th = bone_angle(k, a, t)
            out.append(np.pi - np.maximum(self.ankle_rest_angle - th, 0.0))
        return np.clip(np.stack(out, axis=1), 1e-6, np.pi)

    @cached_property
    def ankle_rest_angle(self) -> float:
        P = self.skeleton.rest_positions()
        return float(bone_angle(P[self.idx["knee_l"]], P[self.idx["ankle_l"]], P[self.idx["toe_l"]]))

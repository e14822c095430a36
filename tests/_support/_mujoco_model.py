"""An independent momentum computation for the cross-check: MuJoCo free bodies.

Every body piece becomes one free-floating MuJoCo body whose frame origin is the
piece COM and whose axes are the piece's joint frame; its ``<inertial>`` carries
the piece mass and the full inertia tensor in that frame.  MuJoCo then computes
the whole-body COM (``subtree_com[0]``), linear velocity (``subtree_linvel[0]``)
and the angular momentum about that COM (``subtree_angmom[0]``) on its own.

Free-joint velocity convention (verified in ``test_free_joint_velocity_convention``):
``qvel[0:3]`` is the linear velocity of the body-frame origin in *world*
coordinates, ``qvel[3:6]`` the angular velocity in the body's *local* frame, so
a world angular velocity ω enters as ``Rᵀ ω``.
"""
from __future__ import annotations

import mujoco
import numpy as np


def _num(x: float) -> str:
    return f"{float(x):.17g}"


def free_pieces_xml(mass: np.ndarray, inertia: np.ndarray) -> str:
    """MJCF with one free body per piece: mass (P,), inertia (P,3,3) about the
    piece COM in the body frame.  No geoms, no gravity (only kinematics is used)."""
    bodies = []
    for i, (m, I) in enumerate(zip(np.asarray(mass, float), np.asarray(inertia, float))):
        full = " ".join(_num(v) for v in (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))
        bodies.append(f'    <body name="piece{i}">\n'
                      f'      <freejoint name="free{i}"/>\n'
                      f'      <inertial pos="0 0 0" mass="{_num(m)}" fullinertia="{full}"/>\n'
                      f'    </body>')
    return ('<mujoco model="flipstudy-pieces">\n'
            '  <option gravity="0 0 0"/>\n'
            '  <worldbody>\n' + "\n".join(bodies) + '\n  </worldbody>\n</mujoco>\n')


class FreePieces:
    """A compiled MuJoCo model of P free pieces and its data."""

    def __init__(self, mass: np.ndarray, inertia: np.ndarray):
        self.xml = free_pieces_xml(mass, inertia)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        self.num_pieces = len(mass)
        assert self.model.nbody == self.num_pieces + 1        # + the world body
        assert self.model.nq == 7 * self.num_pieces and self.model.nv == 6 * self.num_pieces

    @property
    def total_mass(self) -> float:
        return float(self.model.body_subtreemass[0])

    def set_state(self, pos: np.ndarray, R: np.ndarray, v: np.ndarray, omega_world: np.ndarray):
        """Pose and velocity of every piece: COM position (P,3), world rotation of
        its frame (P,3,3), COM velocity (P,3) and world angular velocity (P,3)."""
        d = self.data
        q = np.zeros(4)
        for i in range(self.num_pieces):
            mujoco.mju_mat2Quat(q, np.ascontiguousarray(R[i], dtype=float).reshape(9))  # (w,x,y,z)
            d.qpos[7 * i: 7 * i + 3] = pos[i]
            d.qpos[7 * i + 3: 7 * i + 7] = q
            d.qvel[6 * i: 6 * i + 3] = v[i]                          # world frame
            d.qvel[6 * i + 3: 6 * i + 6] = R[i].T @ omega_world[i]   # body (local) frame

    def momentum(self, pos, R, v, omega_world):
        """(com, p, L, xmat) from MuJoCo for one frame: subtree COM, linear
        momentum (subtree_linvel · total mass), angular momentum about the COM and
        the body orientations MuJoCo ended up with (P,3,3)."""
        self.set_state(pos, R, v, omega_world)
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        com = d.subtree_com[0].copy()
        p = d.subtree_linvel[0] * self.total_mass
        L = d.subtree_angmom[0].copy()
        xmat = d.xmat[1:].reshape(-1, 3, 3).copy()
        return com, p, L, xmat

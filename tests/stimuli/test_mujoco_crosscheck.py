"""Cross-check of our COM, linear and angular momentum against MuJoCo.

Each body piece is handed to MuJoCo as a free body (see ``_mujoco_model``) with
the same mass, inertia, pose and velocities that ``stimuli.physics.momentum``
uses; MuJoCo's ``subtree_com[0]``, ``subtree_linvel[0]`` and
``subtree_angmom[0]`` (angular momentum of all bodies about their joint COM)
must then equal ours.  Cases: a real CMU flip (88_01, needs ../shared), a
random smooth motion of a small CMU-named skeleton with table and with random
masses / inertias / COM offsets, and a rigid body spinning at constant ω.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

mujoco = pytest.importorskip("mujoco", reason="the cross-check needs the mujoco package "
                             "(pip install 'flipstudy[test]')")

from flipstudy.stimuli import physics  # noqa: E402
from flipstudy.stimuli.body import Body  # noqa: E402
from flipstudy.stimuli.motion import Clip, Skeleton, load_bvh  # noqa: E402

from _mujoco_model import FreePieces  # noqa: E402

SHARED = Path(__file__).resolve().parents[3] / "shared"
TOL = 1e-2            # the acceptance bound: 1 % relative error on |L|
ROUNDOFF = 1e-8       # two correct implementations agree to round-off (~1e-15 measured)


# ----------------------------------------------------------------- helpers
def our_inputs(clip: Clip, body: Body):
    """The per-piece quantities physics.momentum works from, frames first."""
    R = clip.joint_rotations()[:, body.joint]                 # (F,P,3,3)
    omega = clip.angular_velocities()[:, body.joint]           # (F,P,3) world frame
    c = physics.piece_positions(clip, body)                    # (F,P,3)
    v = clip.point_velocities(body.joint, body.com)            # (F,P,3) chain-propagated
    return R, omega, c, v


def crosscheck(clip: Clip, body: Body, frames) -> dict:
    """Ours vs MuJoCo on ``frames``; returns the per-frame errors."""
    ours = physics.momentum(clip, body)
    R, omega, c, v = our_inputs(clip, body)
    mj = FreePieces(body.mass, body.inertia)
    assert mj.total_mass == pytest.approx(body.mass.sum(), rel=1e-12)
    out = {"frames": list(frames), "L_rel": [], "p_rel": [], "com_abs": [], "L_ours": [],
           "L_mj": []}
    for f in frames:
        com, p, L, xmat = mj.momentum(c[f], R[f], v[f], omega[f])
        # the pose went in as meant (quaternion order w,x,y,z)
        assert np.allclose(xmat, R[f], atol=1e-12)
        out["com_abs"].append(np.linalg.norm(com - ours.com[f]))
        out["p_rel"].append(np.linalg.norm(p - ours.p[f]) / np.linalg.norm(ours.p[f]))
        out["L_rel"].append(np.linalg.norm(L - ours.L[f]) / np.linalg.norm(ours.L[f]))
        out["L_ours"].append(ours.L[f])
        out["L_mj"].append(L)
    return {k: np.array(v) for k, v in out.items()}


def assert_agree(res: dict, label: str):
    worst = int(np.argmax(res["L_rel"]))
    msg = (f"{label}: frame {res['frames'][worst]}: L ours {res['L_ours'][worst]} vs MuJoCo "
           f"{res['L_mj'][worst]} (relative error {res['L_rel'][worst]:.3g})")
    print(f"\n{label}: max |ΔL|/|L| = {res['L_rel'].max():.3g}, max |Δp|/|p| = "
          f"{res['p_rel'].max():.3g}, max |Δcom| = {res['com_abs'].max():.3g} m "
          f"over {len(res['frames'])} frames")
    assert np.all(res["com_abs"] < 1e-9), f"{label}: COM differs from MuJoCo's subtree_com"
    assert np.all(res["p_rel"] < 1e-9), f"{label}: p differs from MuJoCo's subtree_linvel·M"
    assert np.all(res["L_rel"] < TOL), msg
    assert np.all(res["L_rel"] < ROUNDOFF), "agreement within 1 % but above round-off: " + msg


def cmu_like_skeleton() -> Skeleton:
    """17 joints with CMU names, so ``Body.from_skeleton`` maps it."""
    J = [("Hips", -1, [0, 0, 0]),
         ("LeftUpLeg", 0, [0.10, -0.05, 0]), ("LeftLeg", 1, [0, -0.42, 0]),
         ("LeftFoot", 2, [0, -0.42, 0]),
         ("RightUpLeg", 0, [-0.10, -0.05, 0]), ("RightLeg", 4, [0, -0.42, 0]),
         ("RightFoot", 5, [0, -0.42, 0]),
         ("Spine", 0, [0, 0.10, 0]), ("Spine1", 7, [0, 0.25, 0]), ("Neck", 8, [0, 0.20, 0]),
         ("Head", 9, [0, 0.10, 0]),
         ("LeftArm", 8, [0.18, 0.15, 0]), ("LeftForeArm", 11, [0.28, 0, 0]),
         ("LeftHand", 12, [0.25, 0, 0]),
         ("RightArm", 8, [-0.18, 0.15, 0]), ("RightForeArm", 14, [-0.28, 0, 0]),
         ("RightHand", 15, [-0.25, 0, 0])]
    ends = [(10, [0, 0.20, 0]), (3, [0, -0.05, 0.14]), (6, [0, -0.05, 0.14]),
            (13, [0.08, 0, 0]), (16, [-0.08, 0, 0])]
    return Skeleton([n for n, _, _ in J], [p for _, p, _ in J], [o for _, _, o in J],
                    end_sites=ends)


def random_clip(sk: Skeleton, seed: int, frames: int = 48, fps: float = 60.0) -> Clip:
    """Smooth random motion: a ballistic root and a flip-like root spin, every
    joint turning with its own drift and wobble."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / fps
    J = sk.num_joints
    a = rng.normal(0, 0.6, (J, 3))
    b = rng.normal(0, 2.0, (J, 3))
    c = rng.normal(0, 0.5, (J, 3))
    w = rng.uniform(3, 12, (J, 1))
    ph = rng.uniform(0, 2 * np.pi, (J, 3))
    b[0] = [-9.0, 1.0, 0.5]                                    # backflip-like spin
    rv = a[None] + b[None] * t[:, None, None] + c[None] * np.sin(w[None] * t[:, None, None] + ph[None])
    quats = Rotation.from_rotvec(rv.reshape(-1, 3)).as_quat().reshape(frames, J, 4)
    root = np.array([0.1, 1.0, -0.2]) + np.outer(t, [0.8, 3.5, 0.3]) + 0.5 * np.outer(t ** 2, [0, -9.81, 0])
    return Clip(sk, fps, root, quats, meta={"name": f"random{seed}"})


def random_inertias(rng, mass: np.ndarray) -> np.ndarray:
    """Full (non-diagonal) inertia tensors of random boxes in random orientations."""
    dims = rng.uniform(0.03, 0.4, (len(mass), 3))
    d2 = dims ** 2
    principal = mass[:, None] / 12.0 * (d2.sum(1, keepdims=True) - d2)
    Q = Rotation.random(len(mass), random_state=rng.integers(1 << 31)).as_matrix()
    return Q @ (principal[:, :, None] * np.eye(3)) @ np.swapaxes(Q, -1, -2)


# ---------------------------------------------- MuJoCo's free-joint convention
def test_free_joint_velocity_convention():
    """qvel of a free joint = (world linear velocity of the body origin, angular
    velocity in the body frame): checked against mj_objectVelocity and against
    how mj_integratePos moves the body."""
    I = np.array([[0.30, 0.01, 0.02], [0.01, 0.25, 0.03], [0.02, 0.03, 0.20]])
    mj = FreePieces(np.array([2.0]), I[None])
    m, d = mj.model, mj.data
    R = Rotation.from_rotvec([0.7, -1.1, 0.4])
    q = R.as_quat()
    d.qpos[:] = [1.0, 2.0, 3.0, q[3], q[0], q[1], q[2]]
    d.qvel[:] = [0.1, 0.2, 0.3, 1.0, 2.0, 3.0]
    mujoco.mj_forward(m, d)
    Rm = R.as_matrix()
    assert np.allclose(d.xmat[1].reshape(3, 3), Rm)                  # quaternion is (w,x,y,z)
    res = np.zeros(6)                                                   # (angular, linear)
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, 1, res, 0)   # world axes
    assert np.allclose(res[3:], [0.1, 0.2, 0.3])                        # linear: world frame
    assert np.allclose(res[:3], Rm @ [1.0, 2.0, 3.0])                   # angular: R · qvel
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, 1, res, 1)   # body axes
    assert np.allclose(res[:3], [1.0, 2.0, 3.0])                        # angular: local frame
    # integrating the positions with this qvel: the body turns by exp(dt·qvel_ang)
    # on the right (body frame) and moves by dt·qvel_lin in world coordinates
    dt = 1e-3
    qp = d.qpos.copy()
    mujoco.mj_integratePos(m, qp, d.qvel, dt)
    R2 = Rotation.from_quat([qp[4], qp[5], qp[6], qp[3]])
    assert np.allclose((R.inv() * R2).as_rotvec() / dt, [1.0, 2.0, 3.0], atol=1e-9)
    assert not np.allclose((R2 * R.inv()).as_rotvec() / dt, [1.0, 2.0, 3.0], atol=1e-2)
    assert np.allclose((qp[:3] - d.qpos[:3]) / dt, [0.1, 0.2, 0.3], atol=1e-9)
    # and the angular momentum of a single body is R I Rᵀ ω_world = R I ω_local
    mujoco.mj_subtreeVel(m, d)
    assert np.allclose(d.subtree_angmom[0], Rm @ I @ [1.0, 2.0, 3.0], rtol=1e-12, atol=1e-14)


# ---------------------------------------------------------- synthetic motion
@pytest.mark.parametrize("masses", ["table", "random"])
def test_random_motion_matches_mujoco(masses):
    sk = cmu_like_skeleton()
    clip = random_clip(sk, seed=7)
    body = Body.from_skeleton(sk, total_mass=70.0)
    if masses == "random":
        rng = np.random.default_rng(11)
        mass = rng.uniform(0.2, 15.0, body.num_pieces)
        body = dataclasses.replace(body, mass=mass, inertia=random_inertias(rng, mass),
                                   com=body.com + rng.normal(0, 0.05, body.com.shape))
    res = crosscheck(clip, body, range(clip.num_frames))
    assert_agree(res, f"random motion, {masses} body")


# ------------------------------------------------------------- the real flip
def test_real_flip_88_01_matches_mujoco():
    path = SHARED / "mocap" / "88_01.bvh"
    if not path.exists():
        pytest.skip(f"needs the shared mocap data: {path} not found (../shared sits beside "
                    f"the checkout)")
    clip = load_bvh(path, fps=60)
    body = Body.from_skeleton(clip.skeleton, total_mass=70.0)
    flight = np.linspace(45, 80, 10).round().astype(int)               # SOURCES.md airborne span
    frames = sorted(set(flight) | {0, 20, 100, 150, clip.num_frames - 1})
    res = crosscheck(clip, body, frames)
    assert_agree(res, "88_01 real flip")
    # it is a real spin: |L| in flight is tens of kg·m²/s
    assert np.linalg.norm(res["L_ours"], axis=1)[[frames.index(f) for f in flight]].min() > 10


# -------------------------------------------------------------- a rigid spin
def rigid_spin_clip(sk: Skeleton, omega: np.ndarray, frozen_pose: bool, frames=40, fps=60.0):
    """The body turning as one rigid piece at constant world ω on a ballistic path;
    non-root joints fixed at a random pose (or identity)."""
    rng = np.random.default_rng(3)
    t = np.arange(frames) / fps
    R0 = Rotation.from_rotvec([0.3, -0.5, 0.2])
    root_R = Rotation.from_rotvec(np.outer(t, omega)) * R0              # constant world ω
    local = (Rotation.from_rotvec(rng.normal(0, 0.5, (sk.num_joints, 3))).as_quat()
             if frozen_pose else np.tile([0.0, 0, 0, 1], (sk.num_joints, 1)))
    quats = np.broadcast_to(local, (frames, sk.num_joints, 4)).copy()
    quats[:, 0] = root_R.as_quat()
    root = np.outer(t, [0.5, 3.0, 0.0]) + 0.5 * np.outer(t ** 2, [0, -9.81, 0])
    return Clip(sk, fps, root, quats)


@pytest.mark.parametrize("layout", ["same_joint", "frozen_pose"])
def test_rigid_spin_L_equals_I_omega_in_both_engines(layout):
    sk = cmu_like_skeleton()
    omega = np.array([-9.0, 2.0, 1.5])                   # rad/s, world, not a principal axis
    clip = rigid_spin_clip(sk, omega, frozen_pose=(layout == "frozen_pose"))
    body = Body.from_skeleton(sk, total_mass=70.0)
    if layout == "same_joint":
        # every piece hangs off the root joint, at its rest-pose place
        R, _, c, _ = our_inputs(clip, body)
        Rr, Pr = clip.joint_rotations()[0, 0], clip.joint_positions()[0, 0]
        body = dataclasses.replace(
            body, joint=np.zeros_like(body.joint),
            com=(c[0] - Pr) @ Rr,                                        # Rrᵀ (c − p_root)
            inertia=Rr.T @ R[0] @ body.inertia @ np.swapaxes(R[0], -1, -2) @ Rr)
    ours = physics.momentum(clip, body)
    W = clip.angular_velocities()[:, body.joint]
    assert np.allclose(W, omega, rtol=1e-10, atol=1e-10)                # every piece spins at ω
    # 1) our L vs our I_total ω
    I_omega = np.einsum("fab,b->fa", ours.inertia, omega)
    rel_ours = np.linalg.norm(ours.L - I_omega, axis=1) / np.linalg.norm(I_omega, axis=1)
    # 2) MuJoCo's L from the same per-piece inputs, and MuJoCo's own I_total ω: the
    #    L of the exactly rigid velocities v_i = v_c + ω × (c_i − c)
    R, omega_p, c, v = our_inputs(clip, body)
    mj = FreePieces(body.mass, body.inertia)
    rel_mj, rel_cross, rel_I = [], [], []
    for f in range(clip.num_frames):
        _, _, L_mj, _ = mj.momentum(c[f], R[f], v[f], omega_p[f])
        vc = ours.v_com[f]
        v_rigid = vc + np.cross(omega, c[f] - ours.com[f])
        I_cols = []
        for e in np.eye(3):                                                 # MuJoCo's I_total
            _, _, Le, _ = mj.momentum(c[f], R[f], np.cross(e, c[f] - ours.com[f]),
                                      np.broadcast_to(e, c[f].shape))
            I_cols.append(Le)
        I_mj = np.stack(I_cols, axis=1)
        _, _, L_rigid, _ = mj.momentum(c[f], R[f], v_rigid, np.broadcast_to(omega, c[f].shape))
        assert np.allclose(L_rigid, I_mj @ omega, rtol=1e-10)
        rel_I.append(np.linalg.norm(I_mj - ours.inertia[f]) / np.linalg.norm(ours.inertia[f]))
        rel_mj.append(np.linalg.norm(L_mj - I_mj @ omega) / np.linalg.norm(I_mj @ omega))
        rel_cross.append(np.linalg.norm(L_mj - ours.L[f]) / np.linalg.norm(ours.L[f]))
    rel_mj, rel_cross, rel_I = map(np.array, (rel_mj, rel_cross, rel_I))
    print(f"\nrigid spin ({layout}): max |L−Iω|/|Iω| ours {rel_ours.max():.3g}, MuJoCo "
          f"{rel_mj.max():.3g}; |L_ours−L_mj|/|L| {rel_cross.max():.3g}; "
          f"|I_ours−I_mj|/|I| {rel_I.max():.3g}")
    assert rel_I.max() < ROUNDOFF                     # the same whole-body inertia
    assert rel_cross.max() < ROUNDOFF                 # the same L from the same inputs
    assert rel_ours.max() < TOL and rel_mj.max() < TOL
    # Piece velocities are propagated along the chain (v_joint + ω × r), so a
    # constant spin is differentiated exactly: L = I_total ω to round-off, end frames
    # included (differencing each piece's COM instead would give (sin θ/θ)·orbital,
    # 0.4 % low here at 9.3 rad/s and 60 fps).
    assert rel_ours.max() < ROUNDOFF


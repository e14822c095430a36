"""AMASS / SMPL-H / SMPL-X motions: joint positions from SMPL parameters and the
user's own body-model file, in numpy.

A motion file (AMASS ``.npz``) holds ``poses`` (F, 3·K axis-angle rotations, the
SMPL-family joint order), ``trans`` (F, 3) root translations, ``betas`` (shape
coefficients) and ``mocap_framerate`` (SMPL-X AMASS: ``mocap_frame_rate``);
AMASS worlds are Z up.  The body model is the user's licensed SMPL-family model
as an ``.npz`` of dense arrays (the SMPL .npz format): ``v_template`` (V, 3),
``shapedirs`` (V, 3, B), ``J_regressor`` (J, V), ``kintree_table`` (2, J), and
``posedirs``/``weights`` (not used: they move the skin, not the joints).  flipstudy
never ships or downloads a body model.

The joints are the model's: the rest joints are regressed from the shaped
template, ``J = J_regressor · (v_template + shapedirs · betas)``, and posed down
the kinematic tree, ``G_j = G_parent(j) · R_j`` with ``R_j`` the pose's rotation
of joint ``j``; joint ``j`` sits at ``t + G_parent(j) · (J_j − J_parent(j))``.
The first 22 joints (the SMPL body, the layout ``humanml3d-22``) are kept; the
hands' and face's joints of SMPL-H / SMPL-X are dropped.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.errors import MotionFileError
from ._npyio import load_npz, real_array, scalar

#: The SMPL body's first 22 joints, in SMPL order (HumanML3D's ``new_joints``).
SMPL22_NAMES = ("pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
                "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
                "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
                "left_elbow", "right_elbow", "left_wrist", "right_wrist")
#: Their parents (SMPL's ``kintree_table`` row 0 for the first 22 joints).
SMPL22_PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19)


#: The arrays a body-model file must hold (``posedirs`` and ``weights`` are not needed for joints).
MODEL_KEYS = ("v_template", "shapedirs", "J_regressor", "kintree_table")
NUM_BODY_JOINTS = len(SMPL22_PARENTS)


def _load_npz(path: Path, what: str, keys, frames=()) -> dict:
    """The arrays ``keys`` of an ``.npz`` (those present; others, such as AMASS's
    ``gender`` or a model's ``f``, are not read), headers and sizes checked before
    reading (:func:`flipstudy.stimuli.motion._npyio.load_npz`)."""
    return load_npz(path, keys, what, frames)


def load_body_model(path) -> dict:
    """The rest joints' regressor and tree of a body-model ``.npz``: a dict with
    ``v_template``, ``shapedirs``, ``J_regressor`` (first 22 rows) and ``parents``
    (22,).  Raises :class:`MotionFileError` naming the file and the array."""
    path = Path(path)
    if not path.is_file():
        raise MotionFileError(f"--body-model {path}: no such file; expected your licensed SMPL, SMPL-H "
                              f"or SMPL-X model as an .npz (v_template, shapedirs, J_regressor, "
                              f"kintree_table)")
    m = _load_npz(path, "body model", MODEL_KEYS)
    missing = [k for k in MODEL_KEYS if k not in m]
    if missing:
        raise MotionFileError(f"{path}: not an SMPL-family body model: no array {', '.join(missing)} "
                              f"(expected {', '.join(MODEL_KEYS)}, as in the SMPL .npz format)")
    v, sd, jr, kt = (real_array(np.asarray(m[k]), f"{path}: {k}") for k in MODEL_KEYS)
    V = v.shape[0] if v.ndim == 2 else -1
    if v.ndim != 2 or v.shape[1] != 3:
        raise MotionFileError(f"{path}: v_template has shape {v.shape}; expected (vertices, 3)")
    if sd.ndim != 3 or sd.shape[:2] != (V, 3):
        raise MotionFileError(f"{path}: shapedirs has shape {sd.shape}; expected ({V}, 3, betas)")
    if jr.ndim != 2 or jr.shape[1] != V or jr.shape[0] < NUM_BODY_JOINTS:
        raise MotionFileError(f"{path}: J_regressor has shape {jr.shape}; expected (joints >= "
                              f"{NUM_BODY_JOINTS}, {V})")
    if kt.ndim != 2 or kt.shape[0] != 2 or kt.shape[1] != jr.shape[0]:
        raise MotionFileError(f"{path}: kintree_table has shape {kt.shape}; expected (2, {jr.shape[0]})")
    parents = kt[0, :NUM_BODY_JOINTS].astype(np.int64)      # finite: checked by real_array
    parents[0] = -1                                      # SMPL stores the root's parent as 2**32 - 1
    if tuple(parents.tolist()) != SMPL22_PARENTS:
        raise MotionFileError(f"{path}: the first {NUM_BODY_JOINTS} joints of kintree_table have parents "
                              f"{parents.tolist()}; expected the SMPL body's {list(SMPL22_PARENTS)}")
    return {"v_template": v.astype(np.float64), "shapedirs": sd.astype(np.float64),
            "J_regressor": jr[:NUM_BODY_JOINTS].astype(np.float64), "parents": parents}


def smpl_joints(model: dict, poses, trans, betas) -> np.ndarray:
    """(F, 22, 3) joint positions of the SMPL body for ``poses`` (F, >= 66 axis-angle
    values, root first), ``trans`` (F, 3) and ``betas`` (shape coefficients; those
    beyond the model's are ignored), in the model's world (metres)."""
    nb = min(len(betas), model["shapedirs"].shape[2])
    v = model["v_template"] + model["shapedirs"][:, :, :nb] @ np.asarray(betas, float)[:nb]
    J = model["J_regressor"] @ v                                         # (22,3) rest joints
    F = poses.shape[0]
    R = Rotation.from_rotvec(poses[:, :3 * NUM_BODY_JOINTS].reshape(-1, 3)).as_matrix()
    R = R.reshape(F, NUM_BODY_JOINTS, 3, 3)
    parents = model["parents"]
    G = np.empty_like(R)
    P = np.empty((F, NUM_BODY_JOINTS, 3))
    G[:, 0] = R[:, 0]
    P[:, 0] = J[0]
    for j in range(1, NUM_BODY_JOINTS):                                 # 21 joints, vectorised over frames
        p = parents[j]
        G[:, j] = G[:, p] @ R[:, j]
        P[:, j] = P[:, p] + G[:, p] @ (J[j] - J[p])
    return P + np.asarray(trans, float)[:, None, :]


def read_amass(path, body_model) -> tuple[np.ndarray, float | None]:
    """(F, 22, 3) joint positions (the motion file's world, Z up for AMASS) and the
    file's frame rate (None when it has none) of an AMASS-style ``.npz``.
    ``body_model`` None: :class:`MotionFileError` naming ``--body-model``."""
    path = Path(path)
    d = _load_npz(path, "motion", ("poses", "trans", "betas", "mocap_framerate", "mocap_frame_rate", "fps"),
                  frames=("poses", "trans"))
    if body_model is None:
        raise MotionFileError(f"{path}: an AMASS/SMPL motion (poses, trans, betas) needs the body model "
                              f"to place its joints; pass --body-model PATH to your licensed SMPL, SMPL-H "
                              f"or SMPL-X .npz model (flipstudy does not ship or download one)")
    model = load_body_model(body_model)
    poses, trans = np.asarray(d["poses"]), np.asarray(d["trans"])
    if poses.ndim != 2 or poses.shape[1] < 3 * NUM_BODY_JOINTS or poses.shape[1] % 3:
        raise MotionFileError(f"{path}: poses has shape {poses.shape}; expected (frames, 3 x joints) "
                              f"with at least the {NUM_BODY_JOINTS} body joints ({3 * NUM_BODY_JOINTS} values)")
    if trans.shape != (poses.shape[0], 3):
        raise MotionFileError(f"{path}: trans has shape {trans.shape}; expected ({poses.shape[0]}, 3), "
                              f"one root translation per frame of poses")
    betas = np.asarray(d.get("betas", np.zeros(0))).reshape(-1)
    for k, a in (("poses", poses), ("trans", trans), ("betas", betas)):
        if a.dtype.kind not in "biuf":
            raise MotionFileError(f"{path}: {k} holds {a.dtype}; expected real numbers")
        if not np.all(np.isfinite(a)):
            bad = np.flatnonzero(~np.isfinite(a).reshape(a.shape[0], -1).all(axis=1)) if a.ndim > 1 else []
            raise MotionFileError(f"{path}: {k} holds NaN or infinite values"
                                  + (f" (frames {', '.join(map(str, bad[:10]))})" if len(bad) else "")
                                  + "; expected finite numbers")
    fps = next((scalar(d[k], f"{path}: {k}") for k in ("mocap_framerate", "mocap_frame_rate", "fps") if k in d),
               None)
    return smpl_joints(model, poses.astype(np.float64), trans, betas), fps


__all__ = ["SMPL22_NAMES", "SMPL22_PARENTS", "MODEL_KEYS", "load_body_model", "smpl_joints", "read_amass"]

"""Motions given as joint positions: a named joint layout, and the clip of
rotations that reproduces the positions.

A joint-position sequence is an array (F, J, 3) of world positions, one row of
J joints per frame, with a *layout* naming the joints and their parents:

* ``humanml3d-22``: the SMPL body's first 22 joints in SMPL order (the HumanML3D
  ``new_joints`` arrays of motion-generation models), 20 fps, Y up, metres;
* a layout file (JSON or TOML) for any other: ``joints`` (names), ``parents``
  (index or name of each joint's parent, -1 / "" for the root), and optionally
  ``fps``, ``up`` (``"y"`` or ``"z"``), ``scale`` (metres per file unit) and
  ``landmarks`` (body landmark → joint name, for names the body model does not
  recognise: ``hip_l``, ``knee_l``, ``ankle_l``, ``shoulder_l``, ``elbow_l``,
  ``wrist_l``, the same with ``_r``, ``neck``, ``head``).

:func:`clip_from_positions` turns positions into a :class:`Clip` (the body from
joint positions): the rest pose is one of the clip's own frames (the one with the
legs most extended), each bone keeps its median length, and each joint's
rotation comes from the directions of the bones below it:

* a joint with two or more non-collinear bones below it (pelvis, chest) gets the
  rotation that best maps its rest bones onto the observed ones (Kabsch, a batched
  SVD);
* a joint with one bone below it gets the shortest rotation of the bone's rest
  direction onto its observed direction (in the parent's frame), plus a twist
  about the bone that is transported frame to frame without spin: the twist
  increment of each frame step is removed (a cumulative sum), so there is no
  flip when the bone passes through the direction opposite its rest direction.
  The twist of a limb about its own axis is not in the data; this choice gives it
  zero angular velocity about its axis relative to the parent;
* a leaf joint (wrist, head, toe) keeps its parent's orientation;
* where a source is not rigid (a child that the rigid fit of several bones misses by
  more than 1 mm, e.g. CMU's spine seen through SMPL's joints, or a model's
  stretching bones), that child gets position channels holding its exact place
  (``meta["moving_joints"]``), so the joints are reproduced exactly.

:class:`~flipstudy.stimuli.body.Body` then puts de Leva segments on the bones
(masses, ellipsoid inertias along the bone) exactly as for a BVH skeleton.

Example
-------
>>> from flipstudy import builtin
>>> from flipstudy.stimuli.motion.positions import clip_from_positions, Layout
>>> src = builtin("jump")
>>> sk = src.skeleton
>>> layout = Layout("builtin", sk.joint_names, sk.parents.tolist(), fps=src.fps)
>>> clip = clip_from_positions(src.joint_positions(), layout)
>>> bool(abs(clip.joint_positions() - src.joint_positions()).max() < 1e-6)
True
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from flipstudy.errors import MotionFileError
from ._bvh_units import FPS_RANGE
from ._npyio import load_npy, load_npz, npz_names, scalar
from .clip import Clip
from .skeleton import POSITION_CHANNELS, Skeleton
from .smpl import SMPL22_NAMES, SMPL22_PARENTS, read_amass

#: A bone shorter than this (m) is a helper joint at its parent's place (CMU's hip joints).
_COINCIDENT = 1e-3


@dataclass(frozen=True)
class Layout:
    """Joint names and parents of a joint-position array, with its defaults:
    ``fps`` (None: must be given), ``up`` axis (``"y"``/``"z"``) and ``scale``
    (metres per unit; None: guessed from the body's size like a BVH file's)."""

    name: str
    joints: tuple
    parents: tuple
    fps: float | None = None
    up: str = "y"
    scale: float | None = None
    #: body landmark → joint name, for joints whose names the body model does not
    #: recognise (see :func:`flipstudy.stimuli.body.auto_landmarks`)
    landmarks: dict | None = None

    def __post_init__(self):
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "parents", tuple(int(p) for p in self.parents))


LAYOUTS = {"humanml3d-22": Layout("humanml3d-22", SMPL22_NAMES, SMPL22_PARENTS, fps=20.0, up="y", scale=1.0)}


#: Bytes of a layout file (1 MiB: a layout of a thousand joints is a few tens of kB).
MAX_LAYOUT_BYTES = 2**20
#: Metres per file unit a layout may give (as ``--scale``).
SCALE_RANGE = (1e-6, 1e3)


def _layout_data(p: Path):
    """The table of a JSON/TOML layout file: UTF-8, at most :data:`MAX_LAYOUT_BYTES`."""
    try:
        with open(p, "rb") as f:
            raw = f.read(MAX_LAYOUT_BYTES + 1)
    except OSError as e:
        raise MotionFileError(f"{p}: cannot read the layout file: {e.strerror}") from None
    if len(raw) > MAX_LAYOUT_BYTES:
        raise MotionFileError(f"{p}: a layout file larger than {MAX_LAYOUT_BYTES // 1024} KiB "
                              f"(stimuli.motion.positions.MAX_LAYOUT_BYTES)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise MotionFileError(f"{p}: not UTF-8 text (byte {e.start}); expected a JSON or TOML layout file") from None
    try:
        if p.suffix.lower() == ".toml":
            import tomllib
            return tomllib.loads(text)
        return json.loads(text)
    except RecursionError:
        raise MotionFileError(f"{p}: not a readable layout file (nested too deeply)") from None
    except ValueError as e:
        raise MotionFileError(f"{p}: not a readable layout file ({str(e).splitlines()[0]})") from None


def read_layout(spec) -> Layout:
    """A layout by name (:data:`LAYOUTS`) or from a JSON/TOML file with ``joints``
    and ``parents`` (indices, or parent names with ``""``/``null`` for the root),
    optionally ``fps``, ``up`` and ``scale``.  Raises :class:`MotionFileError`
    naming the file and field."""
    if isinstance(spec, Layout):
        return spec
    spec = str(spec)
    if spec in LAYOUTS:
        return LAYOUTS[spec]
    p = Path(spec)
    if not p.is_file():
        raise MotionFileError(f"layout {spec!r}: neither a known layout ({', '.join(LAYOUTS)}) nor a "
                              f"layout file (JSON or TOML with 'joints' and 'parents')")
    d = _layout_data(p)
    if not isinstance(d, dict) or "joints" not in d or "parents" not in d:
        raise MotionFileError(f"{p}: a layout file needs 'joints' (a list of names) and 'parents' "
                              f"(each joint's parent: index or name, -1 or \"\" for the root)")
    joints, parents = d["joints"], d["parents"]
    if not (isinstance(joints, list) and all(isinstance(n, str) and n for n in joints)):
        raise MotionFileError(f"{p}: 'joints' must be a list of non-empty names")
    if not isinstance(parents, list) or len(parents) != len(joints):
        raise MotionFileError(f"{p}: 'parents' must list one parent per joint ({len(joints)} joints)")
    if len(set(joints)) != len(joints):
        raise MotionFileError(f"{p}: 'joints' names a joint twice")
    index = {n: i for i, n in enumerate(joints)}
    par = []
    for i, q in enumerate(parents):
        if q is None or q == "" or q == -1:
            par.append(-1)
        elif isinstance(q, str) and q in index:
            par.append(index[q])
        elif isinstance(q, int) and not isinstance(q, bool) and 0 <= q < len(joints):
            par.append(q)
        else:
            raise MotionFileError(f"{p}: parents[{i}] (joint {joints[i]!r}) = {q!r}: expected the index "
                                  f"or name of another joint, or -1 for the root")
    if par[0] != -1 or any(q < 0 or q >= i for i, q in enumerate(par) if i):
        raise MotionFileError(f"{p}: the joints must be listed root first and every joint after its "
                              f"parent (one root, parents[0] = -1)")
    up = str(d.get("up", "y")).lower()
    if up not in ("y", "z"):
        raise MotionFileError(f"{p}: up = {d['up']!r}: expected \"y\" or \"z\"")
    fps, scale = d.get("fps"), d.get("scale")
    for key, v, (lo, hi) in (("fps", fps, FPS_RANGE), ("scale", scale, SCALE_RANGE)):
        if v is not None and not (isinstance(v, (int, float)) and not isinstance(v, bool)
                                  and math.isfinite(v) and lo <= v <= hi):
            raise MotionFileError(f"{p}: {key} = {v!r}: expected a number between {lo:g} and {hi:g}")
    lm = d.get("landmarks")
    if lm is not None:
        from ..body import LANDMARKS
        if not isinstance(lm, dict):
            raise MotionFileError(f"{p}: landmarks must be a table of landmark = joint name")
        for k, v in lm.items():
            if k not in LANDMARKS:
                raise MotionFileError(f"{p}: landmarks.{k}: unknown landmark; expected one of {', '.join(LANDMARKS)}")
            if not isinstance(v, str) or v not in index:
                raise MotionFileError(f"{p}: landmarks.{k} = {v!r}: not one of the layout's joints")
    return Layout(p.stem, joints, par, None if fps is None else float(fps), up,
                  None if scale is None else float(scale), lm)


def z_up_to_y_up(X: np.ndarray) -> np.ndarray:
    """(…,3) points of a Z-up world in the library's Y-up world (a rotation of −90°
    about X: x stays, y ← z, z ← −y)."""
    return np.stack([X[..., 0], X[..., 2], -X[..., 1]], axis=-1)


def check_positions(X, where: str, J: int | None = None) -> np.ndarray:
    """``X`` as a float (F, J, 3) array of finite numbers, else :class:`MotionFileError`
    naming ``where`` and what was expected (frames with NaN are listed)."""
    X = np.asarray(X)
    if X.ndim == 2 and X.shape[1] == 263:
        raise MotionFileError(f"{where}: an array (F, 263) holds HumanML3D's motion features, not joint "
                              f"positions; expected (frames, joints, 3), e.g. HumanML3D's new_joints")
    if X.ndim != 3 or X.shape[2] != 3 or X.shape[0] < 2 or X.shape[1] < 2:
        raise MotionFileError(f"{where}: expected joint positions of shape (frames >= 2, joints, 3), "
                              f"got an array of shape {X.shape}")
    if J is not None and X.shape[1] != J:
        raise MotionFileError(f"{where}: {X.shape[1]} joints per frame, but the layout names {J}")
    if X.dtype.kind == "c":
        raise MotionFileError(f"{where}: complex positions ({X.dtype}); expected real numbers")
    if not np.issubdtype(X.dtype, np.number):
        raise MotionFileError(f"{where}: expected numbers, got an array of {X.dtype}")
    X = X.astype(np.float64)
    bad = ~np.isfinite(X).all(axis=(1, 2))
    if bad.any():
        frames = np.flatnonzero(bad)
        shown = ", ".join(str(f) for f in frames[:10]) + (" …" if len(frames) > 10 else "")
        raise MotionFileError(f"{where}: {len(frames)} frame(s) hold NaN or infinite positions "
                              f"(frames {shown}); expected finite numbers in every frame")
    return X


# ---------------------------------------------------------------- rotations
def _swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(…,4) scalar-last quaternions of the shortest rotations taking unit ``a`` to
    unit ``b`` (a half-turn about a perpendicular axis when they are opposite)."""
    a, b = np.broadcast_arrays(a, b)
    c = np.cross(a, b)
    w = 1.0 + np.einsum("...i,...i->...", a, b)
    q = np.concatenate([c, w[..., None]], axis=-1)
    opp = w < 1e-9
    if np.any(opp):
        perp = np.cross(a[opp], np.array([1.0, 0.0, 0.0]))
        weak = np.linalg.norm(perp, axis=-1) < 1e-6
        perp[weak] = np.cross(a[opp][weak], np.array([0.0, 1.0, 0.0]))
        q[opp] = np.concatenate([perp, np.zeros((perp.shape[0], 1))], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _twist_angle(q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Angle (−π, π] of the twist of quaternions ``q`` (…,4) about unit ``axis``."""
    s = q[..., :3] @ axis
    ang = 2.0 * np.arctan2(s, q[..., 3])
    return (ang + np.pi) % (2.0 * np.pi) - np.pi


def _transported(v: np.ndarray, d: np.ndarray, rest: int) -> np.ndarray:
    """(F,4) rotations taking unit ``d`` (the rest direction) to unit ``v`` (F,3),
    with the twist about the bone transported without spin: the swing's twist
    increment from each frame to the next is taken away (cumulative sum), and the
    rotation is the swing alone at frame ``rest``."""
    s = Rotation.from_quat(_swing(d[None], v))
    step = (s[:-1].inv() * s[1:]).as_quat()
    tau = _twist_angle(step, d)
    phi = np.concatenate([[0.0], -np.cumsum(tau)])
    phi -= phi[rest]
    return (s * Rotation.from_rotvec(phi[:, None] * d[None])).as_quat()


def _kabsch(r: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(F,4) rotations best taking the rest vectors ``r`` (K,3) onto ``t`` (F,K,3)
    (least squares, proper rotations)."""
    H = np.einsum("ka,fkb->fab", r, t)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.einsum("fba,fcb->fac", Vt, U)))
    D = np.zeros_like(H)
    D[:, 0, 0] = D[:, 1, 1] = 1.0
    D[:, 2, 2] = np.where(d == 0, 1.0, d)
    R = np.einsum("fba,fbc,fdc->fad", Vt, D, U)
    return Rotation.from_matrix(R).as_quat()


def _targets(parents: np.ndarray, length: np.ndarray, j: int) -> list[int]:
    """The joints whose directions orient joint ``j``: its children away from its
    place; when all are at its own place (zero-length helper bones, such as CMU's hip
    and clavicle joints), their targets."""
    kids = np.flatnonzero(parents == j)
    direct = [int(c) for c in kids if length[c] >= _COINCIDENT]
    if direct:               # its own bones: placed exactly when there is one, rigidly fitted when more
        return direct
    return [t for c in kids for t in _targets(parents, length, c)]


def rest_frame(X: np.ndarray) -> int:
    """The frame whose pose becomes the rest pose: the one with the root highest
    above the lowest joint (legs most extended: standing, not crouched)."""
    return int(np.argmax(X[:, 0, 1] - X[:, :, 1].min(axis=1)))


def clip_from_positions(X, layout: Layout, fps: float | None = None, meta: dict | None = None) -> Clip:
    """The clip (skeleton, root translation, local rotations) that reproduces joint
    positions ``X`` (F, J, 3) in metres, Y up, for the joints of ``layout``.

    Bones keep their median length; ``meta["fit_mm"]`` holds the largest distance
    between a joint of the clip and the given position (0 for rigid bones, more
    when the source stretches its bones), with a warning above 10 mm."""
    meta = dict(meta or {})
    where = meta.get("path", "positions")
    X = check_positions(X, where, len(layout.joints))
    fps = fps if fps is not None else layout.fps
    F, J = X.shape[:2]
    parents = np.asarray(layout.parents)
    vec = X[:, 1:] - X[:, parents[1:]]                          # (F,J-1,3) bone vectors
    blen = np.linalg.norm(vec, axis=-1)
    length = np.concatenate([[np.inf], np.median(blen, axis=0)])
    r = rest_frame(X)
    rest_vec = vec[r]
    rest_len = np.linalg.norm(rest_vec, axis=-1)
    offsets = np.zeros((J, 3))
    ok = rest_len > 1e-9
    offsets[1:][ok] = rest_vec[ok] / rest_len[ok, None] * length[1:][ok, None]
    skel = Skeleton(list(layout.joints), parents, offsets)
    P0 = skel.rest_positions()
    world = np.zeros((F, J, 3, 3))
    local = np.zeros((F, J, 4))
    moved: dict = {}
    for j in range(J):                                         # parents before children
        p = parents[j]
        Wp = np.broadcast_to(np.eye(3), (F, 3, 3)) if p < 0 else world[:, p]
        tg = _targets(parents, length, j)
        rv = P0[tg] - P0[j]                                    # (K,3) rest, j's frame
        tv = np.einsum("fba,fkb->fka", Wp, X[:, tg] - X[:, j, None])   # (F,K,3) parent frame
        rn = np.linalg.norm(rv, axis=-1)
        keep = rn > _COINCIDENT
        rv, tv = rv[keep], tv[:, keep]
        if len(rv) >= 2 and np.linalg.svd(rv, compute_uv=False)[1] > 0.05 * np.linalg.norm(rv, axis=1).max():
            q = _kabsch(rv, tv)
        elif len(rv) >= 1:
            k = int(np.argmax(np.linalg.norm(rv, axis=1)))
            v = tv[:, k] / np.maximum(np.linalg.norm(tv[:, k], axis=-1, keepdims=True), 1e-12)
            q = _transported(v, rv[k] / np.linalg.norm(rv[k]), r)
        else:
            q = np.tile([0.0, 0.0, 0.0, 1.0], (F, 1))         # a leaf: its parent's frame
        local[:, j] = q
        world[:, j] = Wp @ Rotation.from_quat(q).as_matrix()
        if len(tg) >= 2:          # a rigid fit of several bones: children it misses keep their place
            for c in np.flatnonzero(parents == j):
                t = np.einsum("fba,fb->fa", world[:, j], X[:, c] - X[:, j])
                if np.abs(t - offsets[c]).max() > 1e-3:
                    moved[c] = t
    meta.setdefault("warnings", [])
    joint_pos = None
    if moved:
        joint_pos = np.broadcast_to(offsets, (F, J, 3)).copy()
        for c, t in moved.items():
            joint_pos[:, c] = t
        rot = ("Zrotation", "Yrotation", "Xrotation")
        skel = Skeleton(skel.joint_names, parents, offsets,
                        [POSITION_CHANNELS + rot if j == 0 or j in moved else rot for j in range(J)])
        meta["moving_joints"] = [layout.joints[c] for c in sorted(moved)]
    clip = Clip(skel, fps, X[:, 0], local, joint_pos, meta)
    err = np.linalg.norm(clip.joint_positions() - X, axis=-1)
    clip.meta["fit_mm"] = float(1000.0 * err.max())
    clip.meta["rest_frame"] = r
    real = length[1:] >= _COINCIDENT
    stretch = np.abs(blen[:, real] / length[1:][real] - 1.0).max(initial=0.0)
    if clip.meta["fit_mm"] > 10.0:
        clip.meta["warnings"].append(
            f"the bones change length over the clip (up to {100 * stretch:.0f} % of their median); the "
            f"rigid body built from the positions is up to {clip.meta['fit_mm']:.0f} mm off them")
    return clip


def positions_of(clip: Clip, tips: bool = True) -> tuple[np.ndarray, Layout]:
    """(F, J', 3) joint positions of a clip and their :class:`Layout` (with each end
    site as a leaf joint named ``<parent>Tip`` when ``tips``): what a position-only
    source would give for the same motion."""
    sk = clip.skeleton
    X = clip.joint_positions()
    names, parents = list(sk.joint_names), sk.parents.tolist()
    if tips and sk.end_sites:
        E = clip.end_site_positions()
        counts: dict = {}
        for e, (p, _) in enumerate(sk.end_sites):
            counts[p] = counts.get(p, 0) + 1
            names.append(f"{sk.joint_names[p]}Tip" + (str(counts[p]) if counts[p] > 1 else ""))
            parents.append(p)
        X = np.concatenate([X, E], axis=1)
    return X, Layout(clip.meta.get("name", "clip"), names, parents, fps=clip.fps)


#: Keys of a positions ``.npz`` that hold the array (else its only array is taken).
POSITION_KEYS = ("joints", "positions", "joint_positions")


def _read_array(path: Path) -> tuple[np.ndarray | dict, float | None]:
    """The positions array of an ``.npy``, or of an ``.npz`` (with its ``fps`` if any);
    an ``.npz`` with ``poses`` and ``trans`` is returned as its dict (an AMASS motion).
    Headers are checked before reading (:mod:`._npyio`: frames and bytes limited)."""
    if path.suffix.lower() == ".npy":
        return load_npy(path), None
    keys = npz_names(path)
    if "poses" in keys and "trans" in keys:
        return {k: None for k in keys}, None
    key = next((k for k in POSITION_KEYS if k in keys), keys[0] if len(keys) == 1 else None)
    if key is None:
        raise MotionFileError(f"{path}: an .npz with arrays {keys}: expected joint positions under one of "
                              f"{list(POSITION_KEYS)} (or a single array), or an AMASS motion "
                              f"(poses, trans, betas, mocap_framerate)")
    rate = next((k for k in ("fps", "mocap_framerate") if k in keys), None)
    d = load_npz(path, [key] + ([rate] if rate else []), frames=(key,))
    fps = scalar(d[rate], f"{path}: {rate}") if rate else None
    return d[key], fps


def load_positions(path, scale: float | None = None, fps: float | None = None, layout=None,
                   up: str | None = None, body_model=None) -> Clip:
    """Read joint positions (``.npy``/``.npz`` (F, J, 3) with ``layout``) or an AMASS/SMPL
    ``.npz`` (with ``body_model``) into a clip built by :func:`clip_from_positions`.

    ``scale``: metres per file unit (default the layout's, else guessed from the body's
    size); ``fps``: default the file's, else the layout's; ``up``: ``"y"`` or ``"z"``
    (default the layout's; ``"z"`` for AMASS).  ``layout``: a name of :data:`LAYOUTS` or
    a layout file; default ``humanml3d-22`` for 22 joints.  Every bad input raises
    :class:`MotionFileError` naming the file and what was expected.  The clip's joints
    are in depth-first order (as BVH lists them), not necessarily the file's: find
    them by name."""
    from ._bvh_units import check_fps, guess_scale
    path = Path(path)
    arr, file_fps = _read_array(path)
    meta: dict = {"name": path.stem, "path": str(path), "warnings": [], "dropped_frames": []}
    if isinstance(arr, dict):
        X, file_fps = read_amass(path, body_model)
        lay = LAYOUTS["humanml3d-22"]
        lay = Layout("amass-smpl-22", lay.joints, lay.parents, None, "z", 1.0)
        meta["source_format"] = f"AMASS/SMPL parameters through {Path(body_model).name}"
    else:
        X = arr
        if layout is None:
            n = X.shape[1] if X.ndim == 3 else None
            if n != 22:
                check_positions(X, str(path))
                raise MotionFileError(f"{path}: {n} joints per frame and no layout; pass --layout NAME "
                                      f"({', '.join(LAYOUTS)}) or --layout FILE (JSON/TOML with "
                                      f"'joints' and 'parents')")
            layout = "humanml3d-22"
        lay = read_layout(layout)
        meta["source_format"] = f"joint positions, layout {lay.name}"
    X = check_positions(X, str(path), len(lay.joints))
    up = (up or lay.up).lower()
    if up not in ("y", "z"):
        raise MotionFileError(f"up axis {up!r}: expected 'y' or 'z'")
    if up == "z":
        X = z_up_to_y_up(X)
    meta["up"] = up
    if fps is not None:
        fps, meta["fps_source"] = check_fps(fps), "given"
    elif file_fps is not None:
        fps, meta["fps_source"] = check_fps(file_fps, f"{path}: fps"), "file"
    elif lay.fps is not None:
        fps, meta["fps_source"] = lay.fps, f"layout {lay.name}"
    else:
        raise MotionFileError(f"{path}: neither the file nor layout {lay.name!r} gives a frame rate; pass --fps")
    meta["header_fps"] = file_fps or lay.fps or fps       # what the file (or its layout) says
    if scale is not None:
        s, meta["scale_source"] = float(scale), "given"
        if not (np.isfinite(s) and 1e-6 <= s <= 1e3):
            raise MotionFileError(f"scale: expected metres per file unit between 1e-06 and 1000, got {scale!r}")
    elif lay.scale is not None:
        s, meta["scale_source"] = lay.scale, f"layout {lay.name}"
    else:
        _check_extent(X, 1e-3, path, "the smallest unit guessed, mm")
        s, unit = guess_scale(clip_from_positions(X, lay, fps, {"path": str(path)}).skeleton)
        meta["scale_source"] = f"guess: {unit}"
    _check_extent(X, s, path, meta["scale_source"])
    meta["scale"] = s
    meta["layout"] = lay.name
    if lay.landmarks:
        meta["body_mapping"] = dict(lay.landmarks)
    # joints in depth-first order, as BVH writes them (stimuli, edit, convert); find them by name
    return depth_first(clip_from_positions(X * s, lay, fps, meta))


def _check_extent(X: np.ndarray, s: float, path, source: str) -> None:
    """Refuse positions farther than :data:`~flipstudy.stimuli.motion.bvh.MAX_POSITION_M`
    metres from the origin at ``s`` metres per file unit (as the BVH reader does)."""
    from .bvh import MAX_POSITION_M
    far = float(np.abs(X).max()) * s
    if far > MAX_POSITION_M:
        raise MotionFileError(f"{path}: positions reach {far:.3g} m from the origin at {s:g} m per unit "
                              f"({source}), beyond the {MAX_POSITION_M:g} m a motion may span; check the "
                              f"units (--scale)")


def depth_first(clip: Clip) -> Clip:
    """The same clip with its joints in depth-first order (children in their order),
    as BVH writes them; a clip already in that order is returned as it is."""
    sk = clip.skeleton
    order: list[int] = []
    stack = [0]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(np.flatnonzero(sk.parents == j)[::-1].tolist())
    if order == list(range(sk.num_joints)):
        return clip
    new = {j: i for i, j in enumerate(order)}
    parents = [-1] + [new[int(sk.parents[j])] for j in order[1:]]
    skel = Skeleton([sk.joint_names[j] for j in order], parents, sk.offsets[order],
                    [sk.channels[j] for j in order], [(new[p], o) for p, o in sk.end_sites])
    jp = None if clip.joint_pos is None else clip.joint_pos[:, order]
    return Clip(skel, clip.fps, clip.root_pos, clip.rotations[:, order], jp, clip.meta)


__all__ = ["CMU_AS_SMPL22", "depth_first", "load_positions", "POSITION_KEYS", "Layout", "LAYOUTS", "SMPL22_NAMES", "SMPL22_PARENTS", "read_layout", "check_positions",
           "clip_from_positions", "positions_of", "rest_frame", "z_up_to_y_up"]


#: the CMU joint at each of the 22 SMPL body joints, in SMPL order (CMU has two spine
#: joints above the hips and its neck and clavicles at the top of the spine)
CMU_AS_SMPL22 = {
    "pelvis": "Hips", "left_hip": "LeftUpLeg", "right_hip": "RightUpLeg", "spine1": "Spine",
    "left_knee": "LeftLeg", "right_knee": "RightLeg", "spine2": "Spine1", "left_ankle": "LeftFoot",
    "right_ankle": "RightFoot", "spine3": "Neck", "left_foot": "LeftToeBase",
    "right_foot": "RightToeBase", "neck": "Neck1", "left_collar": "LeftShoulder",
    "right_collar": "RightShoulder", "head": "Head", "left_shoulder": "LeftArm",
    "right_shoulder": "RightArm", "left_elbow": "LeftForeArm", "right_elbow": "RightForeArm",
    "left_wrist": "LeftHand", "right_wrist": "RightHand"}

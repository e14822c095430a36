"""How the character is drawn: five styles of one posable mesh, and sided colours.

A *character style* (``Style.character``) is the look of the body — itself a
variable of perception studies (Hodgins, O'Brien & Tumblin 1998; Chaminade,
Hodgins & Kawato 2007; Reitsma, Andrews & Pollard 2008):

``ellipsoids``
    the Body's mass ellipsoids, the body the physics weighs
    (:class:`~flipstudy.render.geometry.BodyMesh`);
``capsules``
    one capsule per segment (the segment's length and 80 % of its radius);
``stick``
    bones as thin tubes, joints as dots, a round head;
``point-light``
    Johansson's (1973) 13 markers (head, shoulders, elbows, wrists, hips,
    knees, ankles; ``Style.point_light_extra`` adds sternum and pelvis): white
    dots on black;
``mannequin``
    one smooth closed surface over the segments: the segments' ellipsoids
    blended into one implicit surface (a smooth minimum of their distance
    fields, blending only segments that meet in the skeleton), meshed once by
    marching cubes in a pose with the limbs spread, and skinned to the bones
    (linear blend skinning, weights from the distance to the segments).

Every style but ``ellipsoids`` is a :class:`SkinnedMesh`: points ``X`` (N,3) in
a meshing pose, a sparse weight matrix ``W`` (N,J) (one-hot for the rigid
styles) and the joints' meshing-pose frames.  Posing a frame is two small matrix
products — ``M = W @ (R_j R0_jᵀ)``, ``t = W @ (P_j − R_j R0_jᵀ P0_j)``,
``x = M X + t`` — written into the VTK point array in place: one PolyData, no
per-segment loop, no re-meshing.

Sided colours: every point has a side (0 trunk and head, 1 left, 2 right) from
its joint's name (``Left*``/``Right*``, ``L*``/``R*`` as CMU's ``LHipJoint``,
``lhip``, ``*_l``…); :func:`side_tones` turns one colour into three tones of
different CIE lightness (left lighter, right darker), so left and right stay
apart in grey scale too.
"""
from __future__ import annotations


import numpy as np

from flipstudy.stimuli.body import Body

from .geometry import BodyMesh, _perp_basis, piece_frames, piece_templates, unit_sphere

#: The character styles, in the order the docs show them (a design chooses among them).
from flipstudy.stimuli.design import CHARACTER_STYLES  # noqa: E402

from .sides import (LEFT, RIGHT, TRUNK, delta_e, joint_side, joint_sides, lab_to_rgb,  # noqa: F401
                    rgb_to_lab, side_tones)


# ------------------------------------------------------------------- meshes
def _segment_names(body: Body) -> list[str]:
    return [body.segment_names[s] for s in range(len(body.segment_names)) if np.any(body.segment == s)]


def _rest(body: Body):
    """Rest pose (all rotations identity): joint positions (J,3)."""
    return body.skeleton.rest_positions()


class SkinnedMesh:
    """One :class:`pyvista.PolyData` posed by (linear blend) skinning, in place.

    ``X`` (N,3) points and ``normals`` in the meshing pose, ``faces`` (T,3),
    ``W`` sparse (N,J) weights (rows sum to 1), ``R0`` (J,3,3) and ``P0`` (J,3)
    the joints' world frames in the meshing pose, ``side`` (N,) per point.
    """

    def __init__(self, body, X, normals, faces, W, R0, P0, side, inflate: float = 0.0,
                 lines: bool = False):
        from ._pv import pv
        import scipy.sparse as sp
        self.body = body
        X = np.asarray(X, float)
        if inflate:
            X = X + float(inflate) * normals
        self._X = X
        self._N = np.asarray(normals, float)
        self._W = sp.csr_matrix(W)
        self._R0t = np.swapaxes(np.asarray(R0, float), -1, -2)
        self._P0 = np.asarray(P0, float)
        self.side = np.asarray(side, np.int8)
        faces = np.asarray(faces, np.int64)
        cells = np.hstack([np.full((faces.shape[0], 1), 3), faces]).ravel()
        self.mesh = pv.PolyData(X.copy(), cells)
        self.mesh.point_data["Normals"] = self._N.copy()
        self.mesh.point_data.active_normals_name = "Normals"
        self._pts = np.asarray(self.mesh.points)
        self._nrm = np.asarray(self.mesh.point_data["Normals"])

    def pose(self, R: np.ndarray, P: np.ndarray) -> None:
        """Pose from world joint rotations ``R`` (J,3,3) and positions ``P`` (J,3)."""
        A = R @ self._R0t                                           # (J,3,3)
        T = P - np.einsum("jab,jb->ja", A, self._P0)
        M = (self._W @ A.reshape(-1, 9)).reshape(-1, 3, 3)
        np.einsum("nab,nb->na", M, self._X, out=self._pts)
        self._pts += self._W @ T
        n = np.einsum("nab,nb->na", M, self._N)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        self._nrm[:] = n
        self.mesh.GetPoints().Modified()
        self.mesh.GetPointData().GetNormals().Modified()
        self.mesh.Modified()

    def world_points(self) -> np.ndarray:
        return self._pts


def _one_hot(joints, J):
    import scipy.sparse as sp
    joints = np.asarray(joints)
    return sp.csr_matrix((np.ones(joints.size), (np.arange(joints.size), joints)),
                         shape=(joints.size, J))


def _rigid(body, parts, inflate, lines=False):
    """A SkinnedMesh of rigid parts: ``parts`` = [(joint (n,), points (n,3) at
    rest, normals (n,3), faces (t,3), side (n,)), ...]."""
    J = body.skeleton.num_joints
    off, X, N, F, S, jj = 0, [], [], [], [], []
    for j, x, n, f, s in parts:
        X.append(x)
        N.append(n)
        F.append(f + off)
        S.append(s)
        jj.append(j)
        off += x.shape[0]
    X, N, F, S, jj = (np.concatenate(a) for a in (X, N, F, S, jj))
    R0 = np.broadcast_to(np.eye(3), (J, 3, 3))
    return SkinnedMesh(body, X, N, F, _one_hot(jj, J), R0, _rest(body), S, inflate)


def _capsule_template(n_around: int, n_along: int):
    u, tris = unit_sphere(n_around, n_along | 1)        # odd: no ring on the equator
    return u, tris


def capsules(body: Body, resolution=(20, 12), inflate: float = 0.0, radius_scale: float = 0.8):
    """Every segment as a capsule: the ellipsoid's length, ``radius_scale`` of
    its radius, hemispherical ends."""
    sides = joint_sides(body.skeleton)
    joint, centre, Q, semi = piece_frames(body)
    u, tris = _capsule_template(*resolution)
    rest = _rest(body)
    parts = []
    for p in range(joint.size):
        r = semi[p, 1] * radius_scale
        h = max(semi[p, 0] - r, 0.0)
        loc = np.column_stack([np.sign(u[:, 0]) * h + r * u[:, 0], r * u[:, 1], r * u[:, 2]])
        x = loc @ Q[p].T + centre[p] + rest[joint[p]]
        n = u @ Q[p].T
        parts.append((np.full(u.shape[0], joint[p]), x, n, tris, np.full(u.shape[0], sides[joint[p]])))
    return _rigid(body, parts, inflate)


def _tube(a, b, r, n_around=10):
    """Points, normals, faces of an open cylinder from a to b (rest, world)."""
    d = b - a
    L = np.linalg.norm(d)
    Q = _perp_basis((d / L)[None])[0]
    th = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    ring = np.column_stack([np.zeros(n_around), np.cos(th), np.sin(th)])
    n = ring @ Q.T
    x = np.vstack([a + r * n, b + r * n])
    i = np.arange(n_around)
    k = (i + 1) % n_around
    f = np.vstack([np.column_stack([i, k, n_around + k]), np.column_stack([i, n_around + k, n_around + i])])
    return x, np.vstack([n, n]), f[:, ::-1]


def _sphere(c, r, res=(12, 8)):
    u, tris = unit_sphere(*res)
    return c + r * u, u.copy(), tris


def stick(body: Body, inflate: float = 0.0, bone_radius: float = 0.014, joint_radius: float = 0.028):
    """Bones as thin tubes (rigid in the parent joint's frame), joints as dots,
    the head as a ball of the head segment's width."""
    sk = body.skeleton
    sides = joint_sides(sk)
    rest = _rest(body)
    bones = [(int(p), j, rest[p], rest[j]) for j, p in enumerate(sk.parents) if p >= 0]
    bones += [(int(p), int(p), rest[p], rest[p] + np.asarray(o)) for p, o in sk.end_sites]
    parts, dots = [], set()
    for p, child, a, b in bones:
        L = np.linalg.norm(b - a)
        if L < 0.01:
            continue
        x, n, f = _tube(a, b, bone_radius)
        parts.append((np.full(x.shape[0], p), x, n, f, np.full(x.shape[0], sides[child])))
        if L >= 0.05:
            dots.add(p)
            if child != p:
                dots.add(child)
    for j in sorted(dots):
        x, n, f = _sphere(rest[j], joint_radius)
        parts.append((np.full(x.shape[0], j), x, n, f, np.full(x.shape[0], sides[j])))
    names = _segment_names(body)
    if "head" in names:
        joint, centre, Q, semi = piece_frames(body)
        h = names.index("head")
        x, n, f = _sphere(centre[h] + rest[joint[h]], 0.8 * semi[h, 1], (20, 12))
        parts.append((np.full(x.shape[0], joint[h]), x, n, f, np.zeros(x.shape[0], int)))
    return _rigid(body, parts, inflate)


#: Johansson's markers: (segment, where along it: 0 proximal end, 0.5 centre)
POINT_LIGHTS = (("head", 0.5),
                ("upperarm_l", 0.0), ("upperarm_r", 0.0), ("forearm_l", 0.0), ("forearm_r", 0.0),
                ("hand_l", 0.0), ("hand_r", 0.0), ("thigh_l", 0.0), ("thigh_r", 0.0),
                ("shank_l", 0.0), ("shank_r", 0.0), ("foot_l", 0.0), ("foot_r", 0.0))
POINT_LIGHTS_EXTRA = (("trunk", 0.75), ("trunk", 0.0))        # sternum, pelvis


def point_light_positions(body: Body, extra: bool = False):
    """Joints (M,) and joint-local positions (M,3) of the point-light markers
    (segments a body does not have are left out)."""
    names = _segment_names(body)
    joint, centre, Q, semi = piece_frames(body)
    want = POINT_LIGHTS + (POINT_LIGHTS_EXTRA if extra else ())
    js, xs = [], []
    for seg, f in want:
        if seg not in names:
            continue
        k = names.index(seg)
        js.append(joint[k])
        xs.append(centre[k] + (2 * f - 1) * semi[k, 0] * Q[k][:, 0])
    if not js:                                           # unknown segment names: every piece's ends
        js = list(joint) + list(joint)
        xs = list(centre - semi[:, :1] * Q[:, :, 0]) + list(centre + semi[:, :1] * Q[:, :, 0])
    return np.array(js), np.array(xs)


def point_lights(body: Body, inflate: float = 0.0, radius: float = 0.03, extra: bool = False):
    """Johansson's markers as small balls (drawn unlit: white dots)."""
    sides = joint_sides(body.skeleton)
    rest = _rest(body)
    js, xs = point_light_positions(body, extra)
    parts = []
    for j, x in zip(js, xs):
        p, n, f = _sphere(x + rest[j], radius)
        parts.append((np.full(p.shape[0], j), p, n, f, np.full(p.shape[0], sides[j])))
    return _rigid(body, parts, inflate)


# ---------------------------------------------------------------- mannequin
def _segment_tree(body: Body) -> np.ndarray:
    """(S,) parent segment of each drawn segment (-1 for the root)."""
    sk = body.skeleton
    joint_seg = {}
    order = [s for s in range(len(body.segment_names)) if np.any(body.segment == s)]
    for i, s in enumerate(order):
        for j in body.joint[body.segment == s]:
            joint_seg.setdefault(int(j), i)
    parent = np.full(len(order), -1)
    for i, s in enumerate(order):
        j = int(body.joint[body.segment == s][0])
        p = sk.parents[j]
        while p >= 0 and joint_seg.get(int(p), i) == i:
            p = sk.parents[p]
        parent[i] = joint_seg[int(p)] if p >= 0 else -1
    return parent


def _spread_pose(body: Body, arm_deg=40.0, leg_deg=12.0):
    """World rotations (J,3,3) and positions (J,3) of the rest pose with the
    arms and legs turned away from the trunk (so the meshing sees them apart)."""
    from scipy.spatial.transform import Rotation
    sk = body.skeleton
    rest = _rest(body)
    R = np.broadcast_to(np.eye(3), (sk.num_joints, 3, 3)).copy()
    P = rest.copy()
    names = _segment_names(body)
    if "trunk" not in names:
        return R, P
    joint, centre, Q, semi = piece_frames(body)
    t = names.index("trunk")
    c = centre[t] + rest[joint[t]]
    up = Q[t][:, 0] if (Q[t][:, 0] @ (rest[sk.parents.argmin()] - c)) < 0 else -Q[t][:, 0]
    children = [[] for _ in range(sk.num_joints)]
    for j, p in enumerate(sk.parents):
        if p >= 0:
            children[p].append(j)
    for seg, deg in (("upperarm_l", arm_deg), ("upperarm_r", arm_deg),
                     ("thigh_l", leg_deg), ("thigh_r", leg_deg)):
        if seg not in names:
            continue
        k = names.index(seg)
        j0 = int(joint[k])
        a = rest[j0]
        d = Q[k][:, 0] if Q[k][:, 0] @ up < 0 else -Q[k][:, 0]      # down the limb
        lat = (a - c) - ((a - c) @ up) * up
        if np.linalg.norm(lat) < 1e-6:
            continue
        lat /= np.linalg.norm(lat)
        ang = np.degrees(np.arccos(np.clip(d @ -up, -1, 1)))
        if ang >= deg:                                   # already away from the trunk
            continue
        axis = np.cross(d, lat)
        if np.linalg.norm(axis) < 1e-9:
            axis = np.cross(-up, lat)
        axis /= np.linalg.norm(axis)
        rot = Rotation.from_rotvec(np.radians(deg - ang) * axis).as_matrix()
        stack = [j0]
        while stack:
            j = stack.pop()
            R[j] = rot @ R[j]
            P[j] = a + rot @ (P[j] - a)
            stack.extend(children[j])
    return R, P


_MANNEQUIN_CACHE: dict = {}


def _mannequin_surface(body: Body, spacing: float, blend: float):
    """Meshing-pose points, normals, faces, weights and frames (cached per body)."""
    import scipy.sparse as sp
    from ._pv import pv
    joint, centre, Q, semi = piece_frames(body)
    key = (tuple(body.skeleton.joint_names), np.round(body.skeleton.offsets, 6).tobytes(),
           np.round(semi, 6).tobytes(), float(spacing), float(blend))
    if key in _MANNEQUIN_CACHE:
        return _MANNEQUIN_CACHE[key]
    R0, P0 = _spread_pose(body)
    S = joint.size
    # the segments' ellipsoids in the meshing pose, a little longer so they meet at the joints
    C = np.einsum("sab,sb->sa", R0[joint], centre) + P0[joint]
    Qw = R0[joint] @ Q
    ax = semi.copy()
    names = _segment_names(body)
    limb = np.array([n.split("_")[0] in ("upperarm", "forearm", "thigh", "shank") for n in names])
    ax[limb, 0] = semi[limb, 0] + 0.35 * semi[limb, 1]      # limbs meet at the joints
    if "head" in names:                                      # a round head over a neck
        h = names.index("head")
        top = 1.0 if "trunk" not in names else np.sign(Qw[h][:, 0] @ (C[h] - C[names.index("trunk")]))
        base = C[h] - top * semi[h, 0] * Qw[h][:, 0]          # C7, where the trunk ends
        C[h] = C[h] + top * 0.25 * semi[h, 0] * Qw[h][:, 0]
        ax[h] = [0.75 * semi[h, 0], 0.95 * semi[h, 1], 0.95 * semi[h, 1]]
        neck = (base + top * 0.35 * semi[h, 0] * Qw[h][:, 0], Qw[h],
                np.array([0.45 * semi[h, 0], 0.5 * semi[h, 1], 0.5 * semi[h, 1]]), h)
    else:
        neck = None
    if {"trunk", "thigh_l", "thigh_r"} <= set(names):        # a trunk flatter front to back
        t = names.index("trunk")
        lat = C[names.index("thigh_l")] - C[names.index("thigh_r")]
        a0 = Qw[t][:, 0]
        lat = lat - (lat @ a0) * a0
        if np.linalg.norm(lat) > 1e-6:
            lat /= np.linalg.norm(lat)
            Qw[t] = np.column_stack([a0, lat, np.cross(a0, lat)])
            ax[t] = [semi[t, 0], semi[t, 1], 0.62 * semi[t, 1]]
    lo = (C - ax.max(1, keepdims=True)).min(0) - 3 * spacing
    hi = (C + ax.max(1, keepdims=True)).max(0) + 3 * spacing
    dims = np.ceil((hi - lo) / spacing).astype(int) + 1
    grid = pv.ImageData(dimensions=dims, spacing=(spacing,) * 3, origin=lo)
    g = np.asarray(grid.points)
    d = np.empty((S, g.shape[0]))
    def field(x, s):
        q = (x - C[s]) @ Qw[s] / ax[s]
        v = (np.linalg.norm(q, axis=1) - 1.0) * ax[s].min()
        if neck is not None and s == neck[3]:                # the neck belongs to the head
            q = (x - neck[0]) @ neck[1] / neck[2]
            v = np.minimum(v, (np.linalg.norm(q, axis=1) - 1.0) * neck[2].min())
        return v

    for s in range(S):                       # S ≈ 14 distance fields, each vectorised over the grid
        d[s] = field(g, s)
    parent = _segment_tree(body)
    # blend each segment with its skeleton neighbours (smooth minimum), the rest a hard minimum
    f = np.full(g.shape[0], np.inf)
    for s in range(S):
        nb = [s] + [t for t in range(S) if parent[t] == s or parent[s] == t]
        ds = d[nb]
        m = ds.min(0)
        f = np.minimum(f, m - blend * np.log(np.exp(-(ds - m) / blend).sum(0)))
    grid.point_data["f"] = f
    surf = grid.contour([0.0], scalars="f").triangulate().clean()
    surf = surf.smooth_taubin(n_iter=20, pass_band=0.1)
    surf = surf.compute_normals(auto_orient_normals=True, split_vertices=False,
                                consistent_normals=True)
    X = np.asarray(surf.points, float)
    N = np.asarray(surf.point_data["Normals"], float)
    F = np.asarray(surf.faces).reshape(-1, 4)[:, 1:]
    # weights: the nearest segment and its neighbours, falling off with distance
    dx = np.empty((S, X.shape[0]))
    for s in range(S):
        dx[s] = field(X, s)
    near = dx.argmin(0)
    adj = np.eye(S, dtype=bool)
    for t in range(S):
        if parent[t] >= 0:
            adj[t, parent[t]] = adj[parent[t], t] = True
    w = np.exp(-((dx - dx.min(0)) / 0.04) ** 2) * adj[near].T
    w[w < 1e-3] = 0.0
    w /= w.sum(0, keepdims=True)
    J = body.skeleton.num_joints
    Wj = sp.csr_matrix((w.T.ravel(), (np.repeat(np.arange(X.shape[0]), S), np.tile(joint, X.shape[0]))),
                       shape=(X.shape[0], J))
    Wj.eliminate_zeros()
    sides = joint_sides(body.skeleton)[joint][near]
    out = (X, N, F, Wj, R0, P0, sides)
    _MANNEQUIN_CACHE[key] = out
    return out


def mannequin(body: Body, inflate: float = 0.0, spacing: float = 0.015, blend: float = 0.03):
    """One smooth closed surface over the segments, meshed once and skinned."""
    X, N, F, W, R0, P0, side = _mannequin_surface(body, spacing, blend)
    return SkinnedMesh(body, X, N, F, W, R0, P0, side, inflate)


def ellipsoids(body: Body, resolution=(20, 12), inflate: float = 0.0) -> BodyMesh:
    """The Body's mass ellipsoids (:class:`~flipstudy.render.geometry.BodyMesh`),
    with a side per point."""
    bm = BodyMesh(body, resolution, inflate)
    bm.side = np.repeat(joint_sides(body.skeleton)[bm.joint], bm.points_per_piece)
    return bm


def character_mesh(body: Body, style, inflate: float = 0.0):
    """The posable mesh of ``body`` in ``style.character`` (a BodyMesh or a
    SkinnedMesh: ``.mesh``, ``.pose(R, P)``, ``.side``).

    Examples
    --------
    >>> from flipstudy import Body, builtin
    >>> from flipstudy.render.style import Style
    >>> clip = builtin("jump")
    >>> body = Body.from_clip(clip)
    >>> for name in CHARACTER_STYLES:
    ...     m = character_mesh(body, Style(character=name))
    ...     m.pose(clip.joint_rotations()[0], clip.joint_positions()[0])
    ...     assert m.side.shape == (m.mesh.n_points,)
    """
    name = style.character
    if name == "ellipsoids":
        return ellipsoids(body, style.ellipsoid_resolution, inflate)
    if name == "capsules":
        return capsules(body, style.ellipsoid_resolution, inflate)
    if name == "stick":
        return stick(body, inflate)
    if name == "point-light":
        return point_lights(body, inflate, style.point_light_radius, style.point_light_extra)
    if name == "mannequin":
        return mannequin(body, inflate)
    raise ValueError(f"unknown character style {name!r}")


__all__ = ["CHARACTER_STYLES", "joint_side", "joint_sides", "side_tones", "rgb_to_lab",
           "lab_to_rgb", "delta_e", "SkinnedMesh", "capsules", "stick", "point_lights",
           "point_light_positions", "mannequin", "ellipsoids", "character_mesh"]

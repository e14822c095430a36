"""The body model: the mass-carrying segments on top of a skeleton.

Segment masses and centre-of-mass locations follow

    de Leva, P. (1996). Adjustments to Zatsiorsky-Seluyanov's segment inertia
    parameters. Journal of Biomechanics 29(9), 1223-1230 (Table 4, males),

and segment densities follow

    Dempster, W. T. (1955). Space requirements of the seated operator.
    WADC Technical Report 55-159 (as tabulated in Winter, Biomechanics and Motor
    Control of Human Movement, Table 4.1),

which the paper (Majkowska & Faloutsos 2007, Section 4.2) also uses.  As in the
paper (after Liu, Hertzmann & Popović 2005), each piece of a segment is a solid
ellipsoid of constant density: its long semi-axis is half the bone length and
its two short semi-axes follow from mass and density.  The renderer draws the
same ellipsoids, so what the viewer sees is what the physics weighs.

A segment (thigh, trunk, ...) covers the chain of bones between two landmarks;
its mass is shared among the bones of that chain in proportion to their length.
A bone ``a → b`` is rigid in the frame of joint ``a``.
"""

from __future__ import annotations

from flipstudy.errors import BodyMappingError, FlipstudyValueError

import re
import warnings
from dataclasses import dataclass

import numpy as np

from .motion.skeleton import Skeleton

#: de Leva (1996) Table 4, males: mass fraction of body mass, COM position as a
#: fraction of the segment length from its proximal landmark, and the Dempster
#: (1955) density in kg/m³.
SEGMENT_TABLE = {
    #  group       mass     com_frac  density
    "head":     (0.0694, 0.4998, 1110.0),   # head+neck, C7 → vertex (CM 50.02 % from vertex)
    "trunk":    (0.4346, 0.5690, 1030.0),   # mid-hip → mid-shoulder (CM 43.10 % from MIDS; see below)
    "upperarm": (0.0271, 0.5772, 1070.0),   # shoulder → elbow joint centre
    "forearm":  (0.0162, 0.4574, 1130.0),   # elbow → wrist joint centre
    "hand":     (0.0061, 0.7900, 1160.0),   # wrist → 3rd metacarpal
    "thigh":    (0.1416, 0.4095, 1050.0),   # hip → knee joint centre
    "shank":    (0.0433, 0.4459, 1090.0),   # knee → lateral malleolus
    "foot":     (0.0137, 0.4415, 1100.0),   # heel → toe tip (here: ankle → toe tip)
}
GROUPS = list(SEGMENT_TABLE)

#: The trunk's COM (its com_frac above).  De Leva (1996) Table 4 (males) gives it for two pairs of
#: endpoints of the same segment: CERV (C7) → MIDH, 603.3 mm, CM 51.38 % from
#: CERV (48.62 % from MIDH), and MIDS (the midpoint of the shoulder joint
#: centres) → MIDH, 515.5 mm, CM 43.10 % from MIDS (56.90 % from MIDH); both put
#: it 293 mm above the mid-hip point.  The trunk here ends at the shoulder joints
#: (MIDS), so its COM is at 56.90 % of the mid-hip → mid-shoulder distance,
#: measured along that line in the reference pose (the trunk is a chain of spine
#: bones; every piece's COM sits at the same fraction of its bone, chosen so the
#: segment's COM lands there; see ``_trunk_and_head``).  Other segments made of
#: several bones put each piece's COM at its bone's midpoint.
SEGMENTS = ["head", "trunk",
            "upperarm_l", "upperarm_r", "forearm_l", "forearm_r", "hand_l", "hand_r",
            "thigh_l", "thigh_r", "shank_l", "shank_r", "foot_l", "foot_r"]

#: Landmark → joint-name parts (after the side token is removed), by priority.
_PART_NAMES = {
    "hip": ["upleg", "thigh", "upperleg", "hip"],
    "knee": ["leg", "calf", "knee", "shin", "lowerleg"],
    "ankle": ["ankle", "foot"],          # SMPL has both: its "foot" is the toe joint
    "shoulder": ["arm", "upperarm", "shoulder"],
    "elbow": ["forearm", "lowerarm", "elbow"],
    "wrist": ["hand", "wrist"],
}
_EXCLUDE = re.compile(r"rigmesh|twist|sharebone|_end$|end$|nub", re.I)
_PREFIX = re.compile(r"^(character\d*_|cc_base_|bip\d*[_ ]|bip\d*|mixamorig\d*_?)", re.I)

LANDMARKS = (["pelvis", "neck", "head", "head_top"] +
             [f"{k}_{s}" for s in "lr" for k in ("hip", "knee", "ankle", "toe_tip",
                                                    "shoulder", "elbow", "wrist", "hand_tip")])


def _split_name(name: str) -> tuple[str | None, str]:
    """(side, part) of a joint name: ('l', 'upleg') for 'LeftUpLeg', 'CC_Base_L_Thigh'..."""
    base = name.split(":")[-1]
    base = _PREFIX.sub("", base)
    low = base.lower()
    m = re.match(r"^(left|right)[_ ]?(.*)$", low)
    if m:
        return m.group(1)[0], re.sub(r"[^a-z0-9]", "", m.group(2))
    m = re.match(r"^([lr])[_ .](.*)$", low)
    if m:
        return m.group(1), re.sub(r"[^a-z0-9]", "", m.group(2))
    if len(base) > 1 and base[0] in "LR" and base[1].isupper():  # LHipJoint, RThumb
        return base[0].lower(), re.sub(r"[^a-z0-9]", "", low[1:])
    m = re.match(r"^(.*?)[_ .]([lr])$", low)
    if m:
        return m.group(2), re.sub(r"[^a-z0-9]", "", m.group(1))
    return None, re.sub(r"[^a-z0-9]", "", low)


def _is_ancestor(sk: Skeleton, a: int, b: int) -> bool:
    return a in sk.path_to_root(b)


def _farthest_descendant_point(sk: Skeleton, j: int) -> tuple[int, int | None]:
    """The descendant point of joint j farthest from it in the rest pose:
    (joint, end-site index or None).  Excluded helper joints are skipped."""
    P = sk.rest_positions()
    best = (j, None)
    best_d = 0.0
    for e, (p, o) in enumerate(sk.end_sites):
        if p == j or _is_ancestor(sk, j, p):
            if any(_EXCLUDE.search(sk.joint_names[k]) for k in sk.path_to_root(p) if k != j
                   and _is_ancestor(sk, j, k)):
                continue
            d = np.linalg.norm(P[p] + o - P[j])
            if d > best_d:
                best, best_d = (p, e), d
    for k in range(j + 1, sk.num_joints):
        if _is_ancestor(sk, j, k) and not _EXCLUDE.search(sk.joint_names[k]):
            d = np.linalg.norm(P[k] - P[j])
            if d > best_d + 1e-9:
                best, best_d = (k, None), d
    return best


def auto_landmarks(sk: Skeleton) -> dict:
    """Find the landmark joints of a skeleton from its joint names and tree.

    Returns a dict landmark → joint name (or (joint name, end-site index) for tips).
    Works for the CMU, MASS/MotionBuilder, iClone/Character Creator, Mixamo and
    mocapbank skeletons and for our synthetic one; raise ``BodyMappingError``
    naming what is missing otherwise (pass ``mapping=`` to override)."""
    names = sk.joint_names
    split = [_split_name(n) for n in names]
    found: dict = {"pelvis": names[0]}
    for side in "lr":
        for lm, parts in _PART_NAMES.items():
            pick = None
            for part in parts:
                for j, (s, p) in enumerate(split):
                    if s == side and p == part and not _EXCLUDE.search(names[j]):
                        pick = j
                        break
                if pick is not None:
                    break
            if pick is not None:
                found[f"{lm}_{side}"] = names[pick]
    heads = [j for j, (s, p) in enumerate(split) if s is None and p == "head"
             and not _EXCLUDE.search(names[j])]
    if heads:
        h = heads[0]
        found["head"] = names[h]
        path = sk.path_to_root(h)[::-1]
        necks = [j for j in path if "neck" in split[j][1]]
        found["neck"] = names[necks[0]] if necks else names[sk.parents[h]]
    return found


@dataclass(frozen=True, eq=False)
class Body:
    """Segments as ellipsoid pieces attached to joint frames.

    Arrays have one row per piece (P pieces): ``joint`` (P,) frame joint,
    ``prox``/``dist`` (P,3) bone ends in that frame, ``com`` (P,3) piece COM in
    that frame, ``mass`` (P,), ``inertia`` (P,3,3) about the piece COM in that
    frame, ``radius`` (P,) short semi-axis, ``segment`` (P,) index into
    ``segment_names``.

    Build one with :meth:`from_clip` (trunk and head measured on the clip's
    poses) or :meth:`from_skeleton` (anthropometric tables only).

    Attributes
    ----------
    skeleton : Skeleton
        The skeleton the pieces hang on.
    total_mass : float
        Kilograms; the pieces' masses sum to it.
    segment_names : list of str
        The segments, in the order ``segment`` indexes.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> body = Body.from_skeleton(builtin("backflip").skeleton, total_mass=70)
    >>> round(sum(body.segment_masses().values()), 6)
    70.0
    """

    skeleton: Skeleton
    total_mass: float
    segment_names: list
    joint: np.ndarray
    prox: np.ndarray
    dist: np.ndarray
    com: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    radius: np.ndarray
    segment: np.ndarray
    landmarks: dict
    #: (positions (F,J,3), rotations (F,J,3,3)) of the frames the trunk and head
    #: geometry was measured on (see :meth:`from_clip`); None: the rest pose
    reference: tuple | None = None

    @property
    def num_pieces(self) -> int:
        return self.joint.shape[0]

    def segment_masses(self) -> dict:
        """Segment name → kg."""
        m = np.bincount(self.segment, weights=self.mass, minlength=len(self.segment_names))
        return {n: float(v) for n, v in zip(self.segment_names, m)}

    def group_masses(self) -> dict:
        """Symmetric group (head, trunk, upperarm, ...) → kg, both sides summed."""
        out = {g: 0.0 for g in GROUPS}
        for n, v in self.segment_masses().items():
            out[n.split("_")[0]] += v
        return out

    # ------------------------------------------------------------ construction
    @classmethod
    def from_clip(cls, clip, total_mass: float = 70.0, mapping: dict | None = None,
                  segment_masses: dict | None = None, max_frames: int = 60) -> "Body":
        """The body of a clip's skeleton, with the trunk's ends (mid-hip, mid-shoulder)
        and the shoulder line measured on the clip's own poses (up to ``max_frames``
        frames spread over the clip) instead of the rest pose.

        Use this for motion capture: some rigs' rest poses are not poses (iClone's
        rest pose has its clavicles folded, the shoulders 13 cm too high and 12 cm
        too close together), while every frame of the motion is."""
        F = clip.num_frames
        pick = np.unique(np.linspace(0, F - 1, min(F, max_frames)).round().astype(int))
        ref = (clip.joint_positions()[pick], clip.joint_rotations()[pick])
        if mapping is None:                    # a position layout's landmarks (its file says them)
            mapping = clip.meta.get("body_mapping")
        try:
            return cls.from_skeleton(clip.skeleton, total_mass, mapping, segment_masses, pose=ref)
        except BodyMappingError as e:          # name the file the skeleton came from
            src = clip.meta.get("path")
            hint = (" (for a position file: a 'landmarks' table of landmark = joint name in its "
                    "layout file)") if clip.meta.get("layout") else ""
            if src and not str(e).startswith(f"{src}: "):
                raise BodyMappingError(f"{src}: {e}{hint}") from None
            raise

    @classmethod
    def from_skeleton(cls, skeleton: Skeleton, total_mass: float = 70.0,
                      mapping: dict | None = None, segment_masses: dict | None = None,
                      pose: tuple | None = None) -> "Body":
        """Build the body of a skeleton.

        ``mapping`` overrides landmarks (landmark → joint name); the landmarks are
        ``pelvis, neck, head`` and per side ``hip, knee, ankle, shoulder, elbow,
        wrist`` (suffix ``_l``/``_r``).  ``segment_masses`` (segment or group name
        → kg) overrides the table; the rest keep their table fraction of
        ``total_mass``."""
        if not (np.isfinite(total_mass) and total_mass > 0):
            raise FlipstudyValueError(f"total_mass must be a positive number of kg, got {total_mass!r}")
        lm = auto_landmarks(skeleton)
        if mapping:
            for k, v in mapping.items():
                if k not in LANDMARKS:
                    raise BodyMappingError(f"unknown landmark {k!r}; expected one of {LANDMARKS}")
                if isinstance(v, str) and v not in skeleton:
                    raise BodyMappingError(f"mapping[{k!r}] = {v!r}: no such joint in the skeleton")
                lm[k] = v
        need = ["neck", "head"] + [f"{k}_{s}" for s in "lr" for k in _PART_NAMES]
        missing = [k for k in need if k not in lm]
        if missing:
            raise BodyMappingError(
                f"cannot map the skeleton (root {skeleton.joint_names[0]!r}) to body segments: "
                f"no joint found for {missing}; pass mapping={{landmark: joint name}}")
        idx = {k: skeleton.index(v) for k, v in lm.items() if isinstance(v, str)}
        # tips
        tips = {}
        for key, start in (("head_top", "head"), ("toe_tip_l", "ankle_l"), ("toe_tip_r", "ankle_r"),
                           ("hand_tip_l", "wrist_l"), ("hand_tip_r", "wrist_r")):
            if key in lm and not isinstance(lm[key], str):
                j, e = lm[key]
                tips[key] = (skeleton.index(j) if isinstance(j, str) else int(j), e)
            elif key in idx:
                tips[key] = (idx[key], None)
            else:
                tips[key] = _farthest_descendant_point(skeleton, idx[start])
        # segment chains: (segment, start joint, end point)
        chains = []
        for s in "lr":
            chains += [(f"upperarm_{s}", idx[f"shoulder_{s}"], (idx[f"elbow_{s}"], None)),
                       (f"forearm_{s}", idx[f"elbow_{s}"], (idx[f"wrist_{s}"], None)),
                       (f"hand_{s}", idx[f"wrist_{s}"], tips[f"hand_tip_{s}"]),
                       (f"thigh_{s}", idx[f"hip_{s}"], (idx[f"knee_{s}"], None)),
                       (f"shank_{s}", idx[f"knee_{s}"], (idx[f"ankle_{s}"], None)),
                       (f"foot_{s}", idx[f"ankle_{s}"], tips[f"toe_tip_{s}"])]
        masses = {seg: SEGMENT_TABLE[seg.split("_")[0]][0] * total_mass for seg in SEGMENTS}
        for k, v in (segment_masses or {}).items():
            if k in ("head", "trunk") or k in masses:
                masses[k] = float(v)
            elif k in SEGMENT_TABLE:
                masses[f"{k}_l"] = masses[f"{k}_r"] = float(v) / 2.0
            else:
                raise FlipstudyValueError(f"segment_masses: unknown segment {k!r}; expected one of "
                                 f"{SEGMENTS} or {GROUPS}")
            if not (np.isfinite(v) and v >= 0):
                raise FlipstudyValueError(f"segment_masses[{k!r}] must be a mass >= 0 kg, got {v!r}")
        total_mass = float(sum(masses.values()))
        if pose is None:
            pose = (skeleton.rest_positions()[None], np.broadcast_to(np.eye(3), (1, skeleton.num_joints, 3, 3)))
        rows = list(_trunk_and_head(skeleton, idx, tips, pose))
        for seg, start, (end_j, end_site) in chains:
            bones = _chain_bones(skeleton, start, end_j, end_site, seg)
            rows.append((seg, bones))
        body = _assemble(skeleton, total_mass, masses, rows,
                         {**{k: skeleton.joint_names[v] for k, v in idx.items()},
                          **{k: (skeleton.joint_names[t[0]], t[1]) for k, t in tips.items()}})
        object.__setattr__(body, "reference", pose)
        return body

    def with_segment_masses(self, masses: dict) -> "Body":
        """The same body with new segment masses (segment name → kg); inertias are
        recomputed at the same densities."""
        with warnings.catch_warnings():        # the mapping was reported when built
            warnings.simplefilter("ignore", UserWarning)
            return Body.from_skeleton(self.skeleton, self.total_mass,
                                      mapping={k: v for k, v in self.landmarks.items()},
                                      segment_masses=masses, pose=self.reference)


#: Length (m) given to a head/hand/foot with nothing of length beyond its joint:
#: skull base → vertex, wrist → fingertips, ankle → toe tip.
_TIP_STUB = {"head": 0.15, "hand": 0.08, "foot": 0.12}


def _trunk_and_head(sk: Skeleton, idx: dict, tips: dict, pose: tuple):
    """The trunk and head rows, following de Leva's landmarks: trunk from the
    mid-hip point to C7 (taken as the mid-shoulder point), head from C7 to the
    vertex.

    Skeletons put their spine joints anywhere (CMU's ``Neck`` sits at mid-chest,
    iClone's waist joints near the pelvis), so the segments are not the bones
    between the ``pelvis`` and ``neck`` joints: the trunk runs from the mid-hip
    point along the spine joints to the mid-shoulder point, both fixed in the
    frame of the joint below them on the spine, and the head keeps only the part
    of its chain above the shoulder line.  Points are measured on ``pose``
    (positions (F,J,3), rotations (F,J,3,3)): the rest pose, or a clip's frames
    (then averaged in the joint's frame).  Without this the trunk of a CMU
    skeleton is 24 cm long, a flat disc 49 cm wide."""
    P, R = pose
    hl, hr, sl, sr = idx["hip_l"], idx["hip_r"], idx["shoulder_l"], idx["shoulder_r"]
    sj = sk.common_ancestor(sl, sr)
    hj = sk.common_ancestor(sk.common_ancestor(hl, hr), sj)   # on the path root → shoulders
    mid_hip = (P[:, hl] + P[:, hr]) / 2.0              # (F,3)
    mid_sh = (P[:, sl] + P[:, sr]) / 2.0
    axis = mid_sh - mid_hip
    n = np.linalg.norm(axis, axis=1)
    if np.any(n < 1e-6):
        raise BodyMappingError("the shoulders and hips coincide in the reference pose; "
                               "pass a mapping")
    u = axis / n[:, None]

    def local(j, x):                                   # x (F,3) world → j's frame, averaged
        return np.einsum("fba,fb->fa", R[:, j], x - P[:, j]).mean(axis=0)

    path = sk.path_to_root(sj)
    path = path[: path.index(hj) + 1][::-1]           # hj ... sj
    trunk = [(hj, local(hj, mid_hip), np.zeros(3))]   # mid-hip → the spine's base joint
    trunk += [(a, np.zeros(3), sk.offsets[b].copy()) for a, b in zip(path[:-1], path[1:])]
    trunk.append((sj, np.zeros(3), local(sj, mid_sh)))
    yield ("trunk", trunk, _chain_com_fraction(trunk, P, R, mid_hip, u, n, SEGMENT_TABLE["trunk"][1]))

    head = _chain_bones(sk, idx["neck"], *tips["head_top"], "head", tip_from=idx["head"])

    def height(j, x):                                  # mean height above the shoulder line
        w = P[:, j] + np.einsum("fab,b->fa", R[:, j], x)
        return float(np.mean(np.einsum("fa,fa->f", w - mid_sh, u)))

    clipped = []
    for j, p, d in head:
        hp, hd = height(j, p), height(j, d)
        if hd <= 0.0:
            continue                                   # below the shoulder line
        if hp < 0.0:                                   # straddles it: start at the line
            p = p + (d - p) * (-hp) / (hd - hp)
        clipped.append((j, p, d))
    yield ("head", clipped if clipped else head)


def _chain_com_fraction(bones, P, R, start, u, length, frac) -> float:
    """The fraction f of its bone at which every piece of a chain puts its COM so
    that the chain's COM (pieces weighted by length, as ``_assemble`` shares the
    mass) lies at ``frac`` of ``length`` from ``start`` along ``u``, averaged over
    the reference frames (positions P (F,J,3), rotations R (F,J,3,3); start (F,3),
    u (F,3) unit, length (F,)).  The projection of the chain's COM on u is linear
    in f: Σ w (a + f b) with a the piece start's and b the piece's own projection."""
    lengths = np.array([np.linalg.norm(d - p) for _, p, d in bones])
    w = lengths / lengths.sum()
    j = np.array([b[0] for b in bones])
    prox = np.array([b[1] for b in bones])
    dist = np.array([b[2] for b in bones])
    wp = P[:, j] + np.einsum("fpab,pb->fpa", R[:, j], prox)      # (F,pieces,3)
    wd = P[:, j] + np.einsum("fpab,pb->fpa", R[:, j], dist)
    a = np.einsum("fpa,fa->fp", wp - start[:, None], u) @ w
    b = np.einsum("fpa,fa->fp", wd - wp, u) @ w
    f = float(np.mean(frac * length - a) / np.mean(b))
    if not 0.0 <= f <= 1.0:
        warnings.warn(f"the trunk's bones cannot put its COM at {100 * frac:.1f} % of its length "
                      f"(each piece would need {100 * f:.0f} % of its bone); clipped", stacklevel=4)
    return float(np.clip(f, 0.0, 1.0))


def _chain_bones(sk: Skeleton, start: int, end_j: int, end_site: int | None, seg: str,
                 tip_from: int | None = None):
    """Bones (frame joint, prox, dist) along the tree path start → end point.

    Bones shorter than 1 mm are dropped.  For a head, hand or foot, when less than a
    quarter of its typical length (``_TIP_STUB``) lies beyond its joint ``tip_from``
    (default ``start``) — a zero-length End Site, a leaf hand, helper bones of a few
    mm — those bones are replaced by a stub of the typical length along the bone
    that leads into that joint; so are bones beyond it longer than 4× that length
    (a broken End Site), with a warning."""
    if not _is_ancestor(sk, start, end_j):
        raise BodyMappingError(f"segment {seg}: joint {sk.joint_names[end_j]!r} is not below "
                               f"{sk.joint_names[start]!r} in the hierarchy")
    path = sk.path_to_root(end_j)
    path = path[: path.index(start) + 1][::-1]        # start ... end_j
    bones = [(a, np.zeros(3), sk.offsets[b].copy()) for a, b in zip(path[:-1], path[1:])]
    if end_site is not None:
        bones.append((end_j, np.zeros(3), sk.end_sites[end_site][1].copy()))
    bones = [b for b in bones if np.linalg.norm(b[2] - b[1]) >= 1e-3]
    group = seg.split("_")[0]
    k = start if tip_from is None else tip_from
    beyond = [b for b in bones if _is_ancestor(sk, k, b[0])]
    beyond_len = sum(np.linalg.norm(d - p) for _, p, d in beyond)
    if group in _TIP_STUB and beyond_len > 4.0 * _TIP_STUB[group]:
        # e.g. the MASS rig's right-hand End Site, 1.62 m long: a broken tip, not a hand
        warnings.warn(f"segment {seg}: the bones beyond joint {sk.joint_names[k]!r} are "
                      f"{beyond_len:.2f} m long, implausible for a {group}; using a "
                      f"{_TIP_STUB[group]:.2f} m {group} instead (pass mapping= to choose "
                      f"its tip)", stacklevel=4)
    if group in _TIP_STUB and not (0.25 * _TIP_STUB[group] <= beyond_len <= 4.0 * _TIP_STUB[group]):
        # the direction of the bone into k, in k's frame (equal to its parent's at rest)
        u = sk.offsets[k] if sk.parents[k] >= 0 else np.array([0.0, 1.0, 0.0])
        n = np.linalg.norm(u)
        u = u / n if n > 1e-9 else np.array([0.0, 1.0, 0.0])
        bones = [b for b in bones if not any(b is x for x in beyond)] + [(k, np.zeros(3), u * _TIP_STUB[group])]
    if not bones:
        raise BodyMappingError(f"segment {seg}: the joints from {sk.joint_names[start]!r} to "
                               f"{sk.joint_names[end_j]!r} have no length; pass a mapping")
    return bones


def ellipsoid_inertia(mass: np.ndarray, a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Inertia about the centre of solid ellipsoids with semi-axes (a, b, b), the
    long one along unit vectors ``axis`` (P,3): I = m/5 (a²+b²)(1 − uuᵀ) + 2m/5 b² uuᵀ."""
    uu = axis[:, :, None] * axis[:, None, :]
    eye = np.eye(3)[None]
    return ((mass * (a ** 2 + b ** 2) / 5.0)[:, None, None] * (eye - uu)
            + (2.0 * mass * b ** 2 / 5.0)[:, None, None] * uu)


def _assemble(sk, total_mass, masses, rows, landmarks) -> Body:
    joint, prox, dist, com, mass, seg_idx, dens = [], [], [], [], [], [], []
    for seg, bones, *piece_frac in rows:
        group = seg.split("_")[0]
        _, frac, rho = SEGMENT_TABLE[group]
        lengths = np.array([np.linalg.norm(d - p) for _, p, d in bones])
        keep = lengths > 1e-6
        lengths = lengths[keep]
        bones = [b for b, k in zip(bones, keep) if k]
        share = lengths / lengths.sum()
        for (j, p, d), w in zip(bones, share):
            f = piece_frac[0] if piece_frac else frac if len(bones) == 1 else 0.5
            joint.append(j)
            prox.append(p)
            dist.append(d)
            com.append(p + f * (d - p))
            mass.append(masses[seg] * w)
            seg_idx.append(SEGMENTS.index(seg))
            dens.append(rho)
    joint = np.array(joint)
    prox, dist, com = np.array(prox), np.array(dist), np.array(com)
    mass, dens = np.array(mass), np.array(dens)
    axis = dist - prox
    L = np.linalg.norm(axis, axis=1)
    axis = axis / L[:, None]
    a = np.maximum(L / 2.0, 0.02)
    b = np.sqrt(3.0 * mass / (4.0 * np.pi * dens * a))
    inertia = ellipsoid_inertia(mass, a, b, axis)
    return Body(sk, total_mass, list(SEGMENTS), joint, prox, dist, com, mass, inertia, b,
                np.array(seg_idx), landmarks)

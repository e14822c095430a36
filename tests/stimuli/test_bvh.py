"""BVH reading and writing: the behaviour a user relies on.

* Euler conventions (intrinsic, in the CHANNELS order) against scipy and against
  forward kinematics done by hand with elementary rotation matrices;
* the three root-translation conventions of real files;
* read -> write -> read round trips (the real files, and a property test on random
  skeletons);
* malformed files: a ``BVHError`` naming the line;
* the real clips of ../shared/ (units, hip heights, T-pose, frame rates, orders).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from scipy.spatial.transform import Rotation

from flipstudy.errors import BVHError
from flipstudy.stimuli.motion import Clip, Skeleton, bvh_text, load_bvh, save_bvh

CMU_UNIT = 0.0254 / 0.45          # metres per CMU/ASF length unit (0.056444)
ORDERS = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]


# ------------------------------------------------------------------ helpers
def write(tmp_path, lines, name="clip.bvh", newline="\n"):
    p = tmp_path / name
    p.write_bytes((newline.join(lines) + newline).encode("ascii"))
    return p


def rot_channels(order):
    return " ".join(f"{a}rotation" for a in order)


def elementary(axis, deg):
    """Rotation matrix about one axis, written out by hand (right-handed)."""
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return {"X": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "Y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "Z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def intrinsic(order, angles):
    """BVH semantics: rotate about the first listed axis, then the second *moved*
    axis, then the third: R = R_first @ R_second @ R_third."""
    R = np.eye(3)
    for axis, deg in zip(order, angles):
        R = R @ elementary(axis, deg)
    return R


def angle_between(q1, q2):
    """Rotation angle (rad) between quaternions (..., 4), whatever their signs."""
    dot = np.abs(np.sum(np.asarray(q1) * np.asarray(q2), axis=-1))
    return 2 * np.arccos(np.clip(dot, 0.0, 1.0))


def assert_same_rotations(q1, q2, tol=1e-7):
    q1 = np.asarray(q1) / np.linalg.norm(q1, axis=-1, keepdims=True)
    q2 = np.asarray(q2) / np.linalg.norm(q2, axis=-1, keepdims=True)
    worst = float(np.max(angle_between(q1, q2))) if q1.size else 0.0
    assert worst < tol, f"rotations differ by up to {worst:.3g} rad"


def assert_same_skeleton(a: Skeleton, b: Skeleton):
    assert b.joint_names == a.joint_names
    assert np.array_equal(b.parents, a.parents)
    assert b.channels == a.channels
    assert b.euler_orders == a.euler_orders
    assert sorted(p for p, _ in b.end_sites) == sorted(p for p, _ in a.end_sites)


def end_sites_by_parent(clip):
    """(F,E,3) end-site positions, ordered by parent joint (stable).  A file lists a
    joint's End Site after its child joints, so a skeleton with an End Site on a joint
    that also has children reads back with its end sites in file order."""
    order = np.argsort([p for p, _ in clip.skeleton.end_sites], kind="stable")
    return clip.end_site_positions()[:, order]


def motion_values(path):
    """The raw MOTION numbers of a file, parsed independently of the reader."""
    text = path.read_text()
    after = text.split("Frame Time", 1)[1].splitlines()[1:]
    return np.array([[float(v) for v in ln.split()] for ln in after if ln.strip()])


# ========================================================== Euler conventions
def three_joint_file(tmp_path, order, frames):
    """Root (ZYX) -> J (``order``) -> K (ZYX) -> End Site; frames are
    (root xyz, root zyx, J angles in listed order)."""
    lines = ["HIERARCHY", "ROOT Root", "{", "\tOFFSET 0 0 0",
             "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
             "\tJOINT J", "\t{", "\t\tOFFSET 1 2 3", f"\t\tCHANNELS 3 {rot_channels(order)}",
             "\t\tJOINT K", "\t\t{", "\t\t\tOFFSET 0.5 -1 2",
             "\t\t\tCHANNELS 3 Zrotation Yrotation Xrotation",
             "\t\t\tEnd Site", "\t\t\t{", "\t\t\t\tOFFSET 0 1 0", "\t\t\t}",
             "\t\t}", "\t}", "}", "MOTION", f"Frames: {len(frames)}", "Frame Time: 0.04"]
    for pos, root_zyx, ang in frames:
        lines.append(" ".join(str(v) for v in (*pos, *root_zyx, *ang, 0, 0, 0)))
    return write(tmp_path, lines)


@pytest.mark.parametrize("order", ORDERS)
def test_euler_order_is_intrinsic_in_listed_order(tmp_path, order):
    frames = [((0.1, 0.2, 0.3), (0, 0, 0), (30, -50, 70)),
              ((-1, 2, 0.5), (10, 20, 30), (200, 95, -130))]   # beyond ±180 and past 90
    clip = load_bvh(three_joint_file(tmp_path, order, frames), scale=1.0, drop_tpose=False)
    assert clip.skeleton.euler_orders == ["ZYX", order, "ZYX"]
    for f, (pos, root_zyx, ang) in enumerate(frames):
        got = clip.rotations[f, 1]
        want = Rotation.from_euler(order, ang, degrees=True)      # upper case: intrinsic
        assert_same_rotations(got, want.as_quat(), tol=1e-12)
        assert np.allclose(Rotation.from_quat(got).as_matrix(), intrinsic(order, ang), atol=1e-12)
        # the test can tell the conventions apart: the extrinsic reading is far away
        extrinsic = Rotation.from_euler(order.lower(), ang, degrees=True)
        assert angle_between(got, extrinsic.as_quat()) > 0.1
        # forward kinematics by hand: a parent's rotation applied to the child's offset
        R_root = intrinsic("ZYX", root_zyx)
        R_J = intrinsic(order, ang)
        p_root = np.array(pos)
        p_J = p_root + R_root @ [1, 2, 3]
        p_K = p_J + R_root @ R_J @ [0.5, -1, 2]
        end = p_K + R_root @ R_J @ [0, 1, 0]        # K's own rotation is zero
        P = clip.joint_positions()[f]
        assert np.allclose(P, [p_root, p_J, p_K], atol=1e-12)
        assert np.allclose(clip.end_site_positions()[f, 0], end, atol=1e-12)


def test_intrinsic_order_by_a_worked_example(tmp_path):
    """ZXY with Z=90°, X=90°: the child offset (0,1,0) goes to (0,0,1) intrinsically
    (X about the turned axis); extrinsically it would go to (-1,0,0)."""
    lines = ["HIERARCHY", "ROOT R", "{", "OFFSET 0 0 0",
             "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
             "JOINT C", "{", "OFFSET 0 1 0", "CHANNELS 3 Zrotation Xrotation Yrotation",
             "End Site", "{", "OFFSET 0 0 0", "}", "}", "}",
             "MOTION", "Frames: 1", "Frame Time: 0.1", "0 0 0 90 90 0 0 0 0"]
    clip = load_bvh(write(tmp_path, lines), scale=1.0, drop_tpose=False)
    assert np.allclose(clip.joint_positions()[0, 1], [0, 0, 1], atol=1e-12)


def test_mixed_orders_in_one_file(tmp_path):
    """A chain whose joints use all six orders (CMU conversions mix orders)."""
    rng = np.random.default_rng(7)
    chain = ["ZYX"] + ORDERS                      # root, then one joint per order
    offsets = rng.uniform(-1, 1, (len(chain), 3))
    offsets[0] = 0
    F = 3
    pos = rng.uniform(-2, 2, (F, 3))
    ang = rng.uniform(-400, 400, (F, len(chain), 3))
    lines = ["HIERARCHY"]
    for j, order in enumerate(chain):
        lines += [("ROOT" if j == 0 else "JOINT") + f" J{j}", "{",
                  "OFFSET " + " ".join(repr(float(v)) for v in offsets[j]),
                  ("CHANNELS 6 Xposition Yposition Zposition " if j == 0 else "CHANNELS 3 ")
                  + rot_channels(order)]
    lines += ["End Site", "{", "OFFSET 0 0 0", "}"] + ["}"] * len(chain)
    lines += ["MOTION", f"Frames: {F}", "Frame Time: 0.01"]
    for f in range(F):
        lines.append(" ".join(repr(float(v)) for v in np.concatenate([pos[f], ang[f].ravel()])))
    clip = load_bvh(write(tmp_path, lines), scale=1.0, drop_tpose=False)
    assert clip.skeleton.euler_orders == chain
    for f in range(F):
        R, p = np.eye(3), pos[f]
        for j, order in enumerate(chain):
            want = Rotation.from_euler(order, ang[f, j], degrees=True).as_quat()
            assert_same_rotations(clip.rotations[f, j], want, tol=1e-12)
            if j:
                p = p + R @ offsets[j]
            R = R @ intrinsic(order, ang[f, j])
            assert np.allclose(clip.joint_positions()[f, j], p, atol=1e-12)


# ============================================================ root conventions
def root_file(tmp_path, offset, frames, root_channels="Xposition Yposition Zposition "
              "Zrotation Yrotation Xrotation"):
    lines = ["HIERARCHY", "ROOT Hips", "{", "OFFSET " + " ".join(map(str, offset)),
             f"CHANNELS 6 {root_channels}", "JOINT Spine", "{", "OFFSET 0 10 0",
             "CHANNELS 3 Zrotation Yrotation Xrotation", "End Site", "{", "OFFSET 0 5 0", "}",
             "}", "}", "MOTION", f"Frames: {len(frames)}", "Frame Time: 0.0166667"]
    for row in frames:
        lines.append(" ".join(map(str, row)))
    return write(tmp_path, lines)


@pytest.mark.parametrize("offset, positions, expected, convention", [
    # MASS: OFFSET repeats frame 1, the channels are absolute
    ((65.03, 98.21, -30.33), [(65.03, 98.21, -30.33), (66.0, 99.5, -31.0)],
     [(65.03, 98.21, -30.33), (66.0, 99.5, -31.0)], "absolute"),
    # raw CMU: OFFSET 0, the channels are absolute
    ((0, 0, 0), [(10.0, 16.0, -4.0), (11.0, 17.0, -4.5)],
     [(10.0, 16.0, -4.0), (11.0, 17.0, -4.5)], "OFFSET + channels"),
    # iClone: OFFSET is the standing hip height, the channels are small deltas
    ((0, 100, 0), [(0.5, 5.0, 0.2), (0.6, 5.5, 0.1)],
     [(0.5, 105.0, 0.2), (0.6, 105.5, 0.1)], "OFFSET + channels"),
])
def test_root_translation_conventions(tmp_path, offset, positions, expected, convention):
    frames = [(*p, 0, 0, 0, 0, 0, 0) for p in positions]
    clip = load_bvh(root_file(tmp_path, offset, frames), scale=0.01, drop_tpose=False)
    assert np.allclose(clip.root_pos, np.array(expected) * 0.01, atol=1e-12)
    assert convention in clip.meta["root_convention"]
    # the child hangs off the resolved root (rotations are zero)
    assert np.allclose(clip.joint_positions()[:, 1], clip.root_pos + [0, 0.10, 0], atol=1e-12)


def test_position_channels_after_rotation_channels(tmp_path):
    """Some exporters list the root's rotations first; columns follow the CHANNELS line."""
    frames = [(0, 90, 0, 1.0, 2.0, 3.0, 0, 0, 0)]
    clip = load_bvh(root_file(tmp_path, (0, 0, 0), frames,
                              "Zrotation Xrotation Yrotation Zposition Xposition Yposition"),
                    scale=1.0, drop_tpose=False)
    assert np.allclose(clip.root_pos[0], [2.0, 3.0, 1.0])
    assert clip.skeleton.euler_orders[0] == "ZXY"
    assert_same_rotations(clip.rotations[0, 0], Rotation.from_euler("X", 90, degrees=True).as_quat())


def tpose_file(tmp_path, offset):
    """Frame 1 a T-pose (all rotations zero, position = OFFSET), then a moving clip whose
    position channels are absolute (the MASS convention)."""
    lines = ["HIERARCHY", "ROOT Hips", "{", "OFFSET " + " ".join(map(str, offset)),
             "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation"]
    for j in range(3):
        lines += [f"JOINT J{j}", "{", "OFFSET 0 10 0", "CHANNELS 3 Zrotation Yrotation Xrotation"]
    lines += ["End Site", "{", "OFFSET 0 5 0", "}"] + ["}"] * 4
    rows = [list(offset) + [0.0] * 12]
    for k in range(1, 7):
        rows.append([offset[0] + k, offset[1] + 0.5 * k, offset[2] - k]
                    + [20.0 + k, -30.0 + k, 40.0 + k] * 4)
    lines += ["MOTION", f"Frames: {len(rows)}", "Frame Time: 0.0166667"]
    lines += [" ".join(map(str, r)) for r in rows]
    return write(tmp_path, lines), np.array(rows)


@pytest.mark.parametrize("drop", ["auto", True])
def test_convention_decided_on_the_files_first_frame_when_a_tpose_is_dropped(tmp_path, drop):
    path, rows = tpose_file(tmp_path, (65.0, 98.0, -30.0))
    clip = load_bvh(path, scale=0.01, drop_tpose=drop)
    assert clip.meta["dropped_frames"] == [0]
    assert clip.num_frames == len(rows) - 1
    assert "absolute" in clip.meta["root_convention"]
    assert np.allclose(clip.root_pos, rows[1:, :3] * 0.01, atol=1e-12)


def test_first_frame_kept_when_not_a_tpose(tmp_path):
    path, rows = tpose_file(tmp_path, (65.0, 98.0, -30.0))
    clip = load_bvh(path, scale=0.01, drop_tpose=False)
    assert clip.meta["dropped_frames"] == []
    assert np.allclose(clip.root_pos, rows[:, :3] * 0.01, atol=1e-12)


# ================================================================ round trips
def test_round_trip_real_file(shared_bvh, tmp_path):
    a = load_bvh(shared_bvh, drop_tpose=False)
    # in metres (the default) and in the file's own units
    for scale in (1.0, a.meta["scale"]):
        out = save_bvh(a, tmp_path / f"rt_{scale:g}.bvh", scale=scale)
        b = load_bvh(out, drop_tpose=False)               # the unit is guessed again
        assert b.meta["scale"] == pytest.approx(scale, rel=1e-12)
        assert_same_skeleton(a.skeleton, b.skeleton)
        assert b.num_frames == a.num_frames
        assert b.fps == a.fps
        np.testing.assert_allclose(b.joint_positions(), a.joint_positions(), rtol=0, atol=1e-6)
        np.testing.assert_allclose(b.end_site_positions(), a.end_site_positions(),
                                   rtol=0, atol=1e-6)
        assert_same_rotations(a.rotations, b.rotations, tol=1e-7)


@pytest.mark.shared("mocap/88_01.bvh")
def test_root_angles_beyond_180_round_trip_as_rotations(SHARED, tmp_path):
    path = SHARED / "mocap" / "88_01.bvh"
    raw = motion_values(path)
    assert raw[:, 5].min() < -500            # root Xrotation is unwrapped (SOURCES: -537°)
    a = load_bvh(path, drop_tpose=False)
    # Hips: Xposition Yposition Zposition Zrotation Yrotation Xrotation
    want = Rotation.from_euler("ZYX", raw[:, 3:6], degrees=True).as_quat()
    assert_same_rotations(a.rotations[:, 0], want, tol=1e-12)
    b = load_bvh(save_bvh(a, tmp_path / "88_01.bvh"), scale=1.0, drop_tpose=False)
    assert_same_rotations(b.rotations[:, 0], want, tol=1e-7)
    np.testing.assert_allclose(b.joint_positions(), a.joint_positions(), rtol=0, atol=1e-6)


# ---------------------------------------------------- property: write -> read
@st.composite
def random_clips(draw):
    J = draw(st.integers(1, 6))
    parents = [-1]
    path = [0]                         # the current root-to-leaf path: depth-first order
    for j in range(1, J):
        parent = draw(st.sampled_from(path))
        path = path[:path.index(parent) + 1] + [j]
        parents.append(parent)
    root_moves = draw(st.booleans()) or J == 1
    channels = []
    for j in range(J):
        kind = draw(st.sampled_from(["rot", "rot", "rot", "pos+rot", "none"]))
        if j == 0:
            kind = "pos+rot" if root_moves else "rot"
        order = draw(st.sampled_from(ORDERS))
        rot = tuple(f"{a}rotation" for a in order) if kind != "none" else ()
        pos = ()
        if kind == "pos+rot":
            pos = tuple(f"{a}position" for a in draw(st.permutations("XYZ")))
        channels.append(rot + pos if draw(st.booleans()) else pos + rot)
    F = draw(st.integers(1, 4))
    fps = draw(st.one_of(st.sampled_from([24.0, 29.97, 30.0, 60.0, 120.0, 119.99]),
                         st.floats(1.0, 480.0)))
    special = draw(st.sampled_from(["random", "gimbal", "large"]))
    n_ends = [draw(st.integers(0, 2)) for _ in range(J)]
    seed = draw(st.integers(0, 2 ** 32 - 1))
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(-1, 1, (J, 3))           # the root's too: it must not matter
    ends = [(j, rng.uniform(-0.5, 0.5, 3)) for j in range(J) for _ in range(n_ends[j])]
    sk = Skeleton([f"j{j} {'x' * j}".strip() if j % 2 else f"joint:{j}" for j in range(J)],
                  parents, offsets, channels, ends)
    q = rng.normal(size=(F, J, 4))
    if special != "random":                        # Euler angles at gimbal lock or past ±180
        for j, order in enumerate(sk.euler_orders):
            if order:
                ang = rng.uniform(-720, 720, (F, 3)) if special == "large" else \
                    np.stack([rng.uniform(-180, 180, F), rng.choice([-90.0, 90.0], F),
                              rng.uniform(-180, 180, F)], 1)
                q[:, j] = Rotation.from_euler(order, ang, degrees=True).as_quat()
    for j, order in enumerate(sk.euler_orders):
        if not order:
            q[:, j] = [0, 0, 0, 1]
    root = rng.uniform(-5, 5, (F, 3)) if root_moves else np.tile(rng.uniform(-5, 5, 3), (F, 1))
    has = sk.has_position.copy()
    has[0] = False
    joint_pos = None
    if has.any():
        joint_pos = np.broadcast_to(offsets, (F, J, 3)).copy()
        joint_pos[:, has] = rng.uniform(-1, 1, (F, int(has.sum()), 3))
    return Clip(sk, fps, root, q, joint_pos)


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(clip=random_clips(), scale=st.sampled_from([1.0, 0.01]), via_save=st.booleans())
def test_write_then_read_gives_the_same_motion(tmp_path, clip, scale, via_save):
    path = tmp_path / "prop.bvh"
    if via_save:
        save_bvh(clip, path, scale=scale)
    else:
        path.write_text(bvh_text(clip, scale))
    back = load_bvh(path, scale=scale, drop_tpose=False)
    assert_same_skeleton(clip.skeleton, back.skeleton)
    assert back.num_frames == clip.num_frames
    assert back.fps == pytest.approx(clip.fps, rel=1e-7)
    np.testing.assert_allclose(back.joint_positions(), clip.joint_positions(), rtol=0, atol=1e-6)
    np.testing.assert_allclose(end_sites_by_parent(back), end_sites_by_parent(clip),
                               rtol=0, atol=1e-6)
    assert_same_rotations(clip.rotations, back.rotations, tol=1e-7)


def test_writer_ignores_the_skeletons_root_offset(tmp_path):
    """A clip's root_pos is the root's world position; a non-zero root OFFSET in the
    skeleton must not shift the written motion."""
    sk = Skeleton(["Hips", "Spine"], [-1, 0], [[1.0, 2.0, 3.0], [0, 0.5, 0]])
    q = np.tile([0, 0, 0, 1.0], (2, 2, 1))
    clip = Clip(sk, 30, [[0, 1, 0], [0.1, 1.1, 0]], q)
    back = load_bvh(save_bvh(clip, tmp_path / "a.bvh"), scale=1.0, drop_tpose=False)
    np.testing.assert_allclose(back.joint_positions(), clip.joint_positions(), atol=1e-9)


def test_root_without_position_channels(tmp_path):
    sk = Skeleton(["Hips", "Spine"], [-1, 0], [[0, 0, 0], [0, 0.5, 0]],
                  [("Zrotation", "Yrotation", "Xrotation")] * 2)
    q = np.tile([0, 0, 0, 1.0], (2, 2, 1))
    fixed = Clip(sk, 30, [[0, 1, 0], [0, 1, 0]], q)
    back = load_bvh(save_bvh(fixed, tmp_path / "a.bvh"), scale=1.0, drop_tpose=False)
    np.testing.assert_allclose(back.root_pos, fixed.root_pos, atol=1e-9)
    moving = Clip(sk, 30, [[0, 1, 0], [0, 1.2, 0]], q)
    with pytest.raises(ValueError, match="no position channels"):
        bvh_text(moving)


def test_joint_names_with_spaces_and_colons_round_trip(tmp_path):
    sk = Skeleton(["mixamorig:Hips", "Left Up Leg"], [-1, 0], [[0, 0, 0], [0.1, -0.1, 0]])
    clip = Clip(sk, 30, [[0, 1, 0]], np.tile([0, 0, 0, 1.0], (1, 2, 1)))
    back = load_bvh(save_bvh(clip, tmp_path / "a.bvh"), scale=1.0, drop_tpose=False)
    assert back.skeleton.joint_names == ["mixamorig:Hips", "Left Up Leg"]


@pytest.mark.parametrize("written, fps", [("0.0083333", 120.0), (".016667", 60.0),
                                          ("0.033333", 30.0), ("0.0333667", 1 / 0.0333667)])
def test_rounded_header_frame_time_snaps_to_the_rate_it_stands_for(tmp_path, written, fps):
    lines = ["HIERARCHY", "ROOT R", "{", "OFFSET 0 0 0", "CHANNELS 3 Xposition Yposition Zposition",
             "End Site", "{", "OFFSET 0 1 0", "}", "}", "MOTION", "Frames: 1",
             f"Frame Time: {written}", "0 0 0"]
    clip = load_bvh(write(tmp_path, lines), scale=1.0)
    assert clip.fps == pytest.approx(fps, rel=1e-12)
    assert clip.meta["header_fps"] == pytest.approx(fps, rel=1e-12)


def test_byte_order_mark_is_accepted(tmp_path):
    sk = Skeleton(["Hips"], [-1], [[0, 0, 0]])
    clip = Clip(sk, 30, [[0, 1, 0]], [[[0, 0, 0, 1.0]]])
    p = tmp_path / "bom.bvh"
    p.write_bytes(b"\xef\xbb\xbf" + bvh_text(clip).encode())
    assert np.allclose(load_bvh(p, scale=1.0).root_pos, [[0, 1, 0]])


# ============================================================ malformed files
GOOD = [
    "HIERARCHY",                                                                # 1
    "ROOT Hips",                                                                # 2
    "{",                                                                        # 3
    "\tOFFSET 0 0 0",                                                           # 4
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",  # 5
    "\tJOINT Spine",                                                            # 6
    "\t{",                                                                      # 7
    "\t\tOFFSET 0 10 0",                                                        # 8
    "\t\tCHANNELS 3 Zrotation Yrotation Xrotation",                             # 9
    "\t\tEnd Site",                                                             # 10
    "\t\t{",                                                                    # 11
    "\t\t\tOFFSET 0 5 0",                                                       # 12
    "\t\t}",                                                                    # 13
    "\t}",                                                                      # 14
    "}",                                                                        # 15
    "MOTION",                                                                   # 16
    "Frames: 3",                                                                # 17
    "Frame Time: 0.0333333",                                                    # 18
    "0 90 0 1 2 3 4 5 6",                                                       # 19
    "0 91 0 1 2 3 4 5 6",                                                       # 20
    "0 92 0 1 2 3 4 5 6",                                                       # 21
]


def edited(replace=None, delete=(), insert_after=None):
    """GOOD with lines (1-based) replaced, deleted or inserted."""
    lines = list(GOOD)
    for ln, text in (replace or {}).items():
        lines[ln - 1] = text
    for ln, text in sorted((insert_after or {}).items(), reverse=True):
        lines.insert(ln, text)
    return [t for k, t in enumerate(lines, 1) if k not in delete]


MALFORMED = {
    "truncated motion": (edited(delete={21}), 21, "truncated MOTION block"),
    "more frame lines than Frames:": (edited(insert_after={21: "0 93 0 1 2 3 4 5 6"}), 22,
                                      "more data than the header declares"),
    "too few values": (edited(replace={20: "0 91 0 1 2 3 4 5"}), 20, "wrong number of values"),
    "too many values": (edited(replace={19: "0 90 0 1 2 3 4 5 6 7"}), 19, "wrong number of values"),
    "non-numeric": (edited(replace={21: "0 92 0 1 2 abc 4 5 6"}), 21, "non-numeric value 'abc'"),
    "nan": (edited(replace={20: "0 91 0 1 nan 3 4 5 6"}), 20, "non-finite value"),
    "inf": (edited(replace={19: "0 90 0 1 2 3 inf 5 6"}), 19, "non-finite value"),
    "-inf": (edited(replace={21: "-inf 92 0 1 2 3 4 5 6"}), 21, "non-finite value"),
    "unknown channel": (edited(replace={9: "\t\tCHANNELS 3 Zrotation Yrotation Wrotation"}), 9,
                        "unknown channel name 'Wrotation'"),
    "duplicate joint": (edited(replace={6: "\tJOINT Hips"}), 6, "duplicate joint name 'Hips'"),
    "missing Frame Time": (edited(delete={18}), 18, "missing 'Frame Time"),
    "Frame Time 0": (edited(replace={18: "Frame Time: 0"}), 18, "must be a positive number"),
    "Frame Time negative": (edited(replace={18: "Frame Time: -0.0333"}), 18,
                            "must be a positive number"),
    "Frames: 0": (edited(replace={17: "Frames: 0"}, delete={19, 20, 21}), 17,
                  "needs at least one frame"),
    "missing root '}'": (edited(delete={15}), 15, "unbalanced braces"),
    "missing End Site '}'": (edited(delete={13}), 15, "unbalanced braces"),
    "extra '}'": (edited(insert_after={15: "}"}), 16, "unbalanced braces"),
    "empty file": ([""], 1, "empty file"),
    "blank lines only": (["", "  ", "\t"], 1, "empty file"),
    "no HIERARCHY": (edited(delete={1}), 1, "expected 'HIERARCHY'"),
    "something else first": (["", "MOTION", *GOOD], 2, "expected 'HIERARCHY'"),
}


def test_the_good_file_reads(tmp_path):
    clip = load_bvh(write(tmp_path, GOOD), scale=1.0, drop_tpose=False)
    assert clip.num_frames == 3 and clip.skeleton.joint_names == ["Hips", "Spine"]


@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["LF", "CRLF"])
@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_file_raises_bvherror_naming_the_line(tmp_path, case, newline):
    lines, line, phrase = MALFORMED[case]
    path = write(tmp_path, lines, newline=newline)
    with pytest.raises(BVHError) as info:
        load_bvh(path, scale=1.0)
    err = info.value
    assert err.line == line, str(err)
    assert f"line {line}" in str(err)
    assert phrase in str(err)
    assert path.name in str(err)


# ================================================================ real files
HEADER_FRAMES = {
    "88_01.bvh": 203, "87_03.bvh": 248, "88_05.bvh": 150, "90_11.bvh": 181,
    "88_01_mass-retarget.bvh": 199, "mass_cartwheel.bvh": 286, "mass_kick.bvh": 231,
    "02_04_iclone-retarget.bvh": 241, "01_01_iclone-retarget.bvh": 1376,
    "02_05_iclone-retarget.bvh": 927, "test_freebvh.bvh": 69, "test_mocapbank.bvh": 455,
}
RAW_CMU = ["88_01.bvh", "87_03.bvh", "88_05.bvh", "90_11.bvh"]


def test_the_shared_folder_has_every_documented_file(shared_path):
    # a folder that is absent skips with its name (shared_path); one that is there must hold them
    found = {p.name for folder in ("mocap", "peer-bvh") for p in shared_path(folder).glob("*.bvh")}
    assert set(HEADER_FRAMES) <= found


def test_a_missing_shared_folder_skips_the_documented_files_test(shared_path, tmp_path, monkeypatch):
    (tmp_path / "mocap").mkdir()                     # ../shared with mocap/ but no peer-bvh/
    for name in HEADER_FRAMES:
        (tmp_path / "mocap" / name).write_text("")
    monkeypatch.setitem(shared_path.__globals__, "SHARED_DIR", tmp_path)
    with pytest.raises(pytest.skip.Exception, match="peer-bvh not found"):
        test_the_shared_folder_has_every_documented_file(shared_path)


def test_every_real_file_loads(shared_bvh):
    clip = load_bvh(shared_bvh)
    n = HEADER_FRAMES.get(shared_bvh.name)
    if n is not None:
        assert clip.num_frames + len(clip.meta["dropped_frames"]) == n
    P = clip.joint_positions()
    assert P.shape == (clip.num_frames, clip.skeleton.num_joints, 3)
    assert np.isfinite(P).all()
    assert np.allclose(np.linalg.norm(clip.rotations, axis=-1), 1.0)


@pytest.fixture
def real(shared_path):
    def load(name, **kw):
        folder = "peer-bvh" if name.startswith("test_") else "mocap"
        return load_bvh(shared_path(f"{folder}/{name}"), **kw)
    return load


@pytest.mark.parametrize("name, scale, unit", [
    *[(n, CMU_UNIT, "CMU") for n in RAW_CMU],
    *[(n, 0.01, "cm") for n in ["88_01_mass-retarget.bvh", "mass_cartwheel.bvh", "mass_kick.bvh",
                                "02_04_iclone-retarget.bvh", "01_01_iclone-retarget.bvh",
                                "02_05_iclone-retarget.bvh", "test_freebvh.bvh",
                                "test_mocapbank.bvh"]],
])
def test_scale_guess(real, name, scale, unit):
    clip = real(name)
    assert clip.meta["scale"] == pytest.approx(scale, rel=1e-12)
    assert clip.meta["scale_source"].startswith("guess") and unit in clip.meta["scale_source"]


@pytest.mark.parametrize("name, hip", [
    ("88_01.bvh", 0.904), ("87_03.bvh", 0.928), ("88_05.bvh", 0.947), ("90_11.bvh", 0.912),
    ("88_01_mass-retarget.bvh", 0.982), ("02_04_iclone-retarget.bvh", 1.109),
])
def test_hip_height_of_the_first_frame(real, name, hip):
    clip = real(name)
    assert clip.root_pos[0, 1] == pytest.approx(hip, abs=0.02)
    assert clip.joint_positions()[0, 0, 1] == pytest.approx(hip, abs=0.02)


@pytest.mark.parametrize("name", list(HEADER_FRAMES))
def test_tpose_dropped_only_for_raw_cmu(real, name):
    clip = real(name)
    if name in RAW_CMU:
        assert clip.meta["dropped_frames"] == [0]
        assert clip.num_frames == HEADER_FRAMES[name] - 1
        assert any("T-pose" in w for w in clip.meta["warnings"])
        kept = real(name, drop_tpose=False)
        assert kept.num_frames == HEADER_FRAMES[name]
        np.testing.assert_array_equal(kept.root_pos[1:], clip.root_pos)
    else:
        assert clip.meta["dropped_frames"] == []
        assert clip.num_frames == HEADER_FRAMES[name]


@pytest.mark.parametrize("name, fps", [
    ("88_01.bvh", 120.0), ("87_03.bvh", 120.0), ("88_05.bvh", 60.0), ("90_11.bvh", 60.0),
    ("02_04_iclone-retarget.bvh", 60.0), ("01_01_iclone-retarget.bvh", 60.0),
    ("02_05_iclone-retarget.bvh", 60.0), ("88_01_mass-retarget.bvh", 120.0),
    ("test_freebvh.bvh", 30.0), ("test_mocapbank.bvh", 30.0),
])
def test_header_frame_rate(real, name, fps):
    clip = real(name)
    assert clip.fps == fps
    assert clip.meta["header_fps"] == fps
    assert clip.meta["fps_source"] == "header"


def test_fps_argument_overrides_the_header(real):
    clip = real("88_01.bvh", fps=60)
    assert clip.fps == 60.0
    assert clip.meta["header_fps"] == 120.0
    assert clip.meta["fps_source"] == "given"
    assert clip.duration == pytest.approx((clip.num_frames - 1) / 60)


@pytest.mark.parametrize("name, order", [
    *[(n, "ZYX") for n in RAW_CMU],
    ("88_01_mass-retarget.bvh", "ZXY"), ("mass_cartwheel.bvh", "ZXY"),
    ("test_mocapbank.bvh", "ZXY"), ("02_04_iclone-retarget.bvh", "ZYX"),
    ("test_freebvh.bvh", "ZYX"),
])
def test_euler_orders_of_real_files(real, name, order):
    orders = real(name).skeleton.euler_orders
    assert {o for o in orders if o} == {order}


def test_mixamo_joint_names_keep_their_colon(real):
    clip = real("test_freebvh.bvh")
    names = clip.skeleton.joint_names
    assert names[0] == "mixamorig:Hips"
    assert len(names) == 55 and all(n.startswith("mixamorig:") for n in names)
    assert len(clip.skeleton.end_sites) == 15
    assert clip.skeleton.index("mixamorig:HeadTop_End") > 0


@pytest.mark.parametrize("name", ["88_01_mass-retarget.bvh", "test_mocapbank.bvh"])
def test_crlf_file_reads_like_its_lf_copy(real, shared_path, tmp_path, name):
    folder = "peer-bvh" if name.startswith("test_") else "mocap"
    raw = shared_path(f"{folder}/{name}").read_bytes()
    assert b"\r\n" in raw
    crlf = real(name)
    copy = tmp_path / name
    copy.write_bytes(raw.replace(b"\r\n", b"\n"))
    lf = load_bvh(copy)
    assert crlf.num_frames == HEADER_FRAMES[name]
    np.testing.assert_array_equal(crlf.joint_positions(), lf.joint_positions())
    assert crlf.fps == lf.fps

"""The fast code paths give the numbers of the plain ones, on the real files.

* BVH reading: the MOTION block through ``np.loadtxt`` against the token-by-token
  reader (bit for bit), and the checked reader taking over whenever the block is not
  plain numbers; Euler angles through one N-dimensional ``Rotation.from_euler`` call
  against one flat call per joint;
* forward kinematics: the component-major level products of ``Clip._fk`` against
  stacked ``matmul``/``einsum`` products over (F, J, 3, 3) arrays.

No timings here: ``benchmarks/`` measures speed.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from flipstudy.errors import BVHError
from flipstudy.stimuli.motion import Clip, Skeleton, load_bvh
from flipstudy.stimuli.motion import _bvh_parse as parse_mod
from flipstudy.stimuli.motion import bvh as bvh_mod
from flipstudy.stimuli.motion.skeleton import ROTATION_CHANNELS

from _shared import ALL_BVH, shared_file


# ------------------------------------------------------------------ helpers
def _blocks(path):
    """(hierarchy, data lines, frames, channels, first data line) of a file."""
    text = path.read_bytes().decode("utf-8-sig")
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    h, motion_at = parse_mod.parse_hierarchy(lines, path)
    n_ch = sum(len(c) for c in h["channels"])
    n_frames, _, _, values, first = parse_mod.parse_motion(lines, motion_at, n_ch, path)
    return h, lines[first:first + n_frames], n_frames, n_ch, first, values


def plain_fk(clip):
    """Forward kinematics as stacked (3,3) products over frames, one level at a time
    (the implementation the component-major one replaced)."""
    sk = clip.skeleton
    F, J = clip.num_frames, sk.num_joints
    local_R = Rotation.from_quat(clip.rotations.reshape(-1, 4)).as_matrix().reshape(F, J, 3, 3)
    if clip.joint_pos is not None:
        trans = np.where(sk.has_position[None, :, None], clip.joint_pos, sk.offsets[None])
    else:
        trans = np.broadcast_to(sk.offsets[None], (F, J, 3))
    R = np.empty((F, J, 3, 3))
    P = np.empty((F, J, 3))
    R[:, 0] = local_R[:, 0]
    P[:, 0] = clip.root_pos
    for idx in sk.levels()[1:]:
        par = sk.parents[idx]
        pR = R[:, par]
        R[:, idx] = pR @ local_R[:, idx]
        P[:, idx] = P[:, par] + np.einsum("fjab,fjb->fja", pR, trans[:, idx])
    return R, P


# --------------------------------------------------------------- BVH reading
@pytest.mark.parametrize("name", ALL_BVH)
def test_loadtxt_reads_the_motion_block_bit_for_bit(name):
    path = shared_file(name)
    _, data_lines, n_frames, n_ch, first, values = _blocks(path)
    fast = parse_mod.fast_values(data_lines, n_frames, n_ch)
    assert fast is not None, "a plain real file must take the fast path"
    checked = parse_mod.checked_values(data_lines, n_frames, n_ch, first, path)
    assert fast.dtype == checked.dtype and fast.shape == checked.shape
    assert np.array_equal(fast, checked)
    assert np.array_equal(values, checked)


@pytest.mark.parametrize("lines, why", [
    (["1 2 3", "", "4 5 6"], "blank line inside the block"),
    (["1 2 3", "4 5"], "short line"),
    (["1 2 3 4", "5 6"], "counts that only add up over the block"),
    (["1 2\x1c3", "4 5 6"], "a separator loadtxt splits at and bytes.split does not"),
    (["1 2 3", "4 5 6\xa0"], "non-ASCII"),
    (["1 2 1_0", "4 5 6"], "a number only Python's float reads"),
    (["1 2 #3", "4 5 6"], "a comment sign"),
    (["1 2 x", "4 5 6"], "non-numeric"),
])
def test_anything_but_plain_numbers_leaves_the_fast_path(lines, why):
    assert parse_mod.fast_values(lines, len(lines), 3) is None, why


def test_numbers_only_pythons_float_reads_still_load(tmp_path):
    body = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0",
            "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
            "End Site", "{", "OFFSET 0 1 0", "}", "}", "MOTION", "Frames: 2",
            "Frame Time: 0.0333333", "0 1_0 0 0 0 0", "0 1 0 0 0 0"]
    p = tmp_path / "underscore.bvh"
    p.write_text("\n".join(body) + "\n")
    clip = load_bvh(p, scale=1.0, drop_tpose=False)
    assert clip.root_pos[0, 1] == 10.0


@pytest.mark.parametrize("body, line", [
    (["0 0 0 0 0 0", "", "0 0 0 0 0 0"], 15),
    (["0 0 0 0 0 0 0", "0 0 0 0 0"], 14),
    (["0 0 0 0 0 0", "0 0 0 oops 0 0"], 15),
])
def test_malformed_blocks_still_name_their_line(tmp_path, body, line):
    head = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0",
            "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation",
            "End Site", "{", "OFFSET 0 1 0", "}", "}", "MOTION", f"Frames: {len(body)}",
            "Frame Time: 0.0333333"]                       # frame lines start at line 14
    p = tmp_path / "bad.bvh"
    p.write_text("\n".join(head + body) + "\n")
    with pytest.raises(BVHError) as e:
        load_bvh(p)
    assert e.value.line == line


@pytest.mark.parametrize("name", ALL_BVH)
def test_nd_from_euler_equals_one_flat_call_per_joint(name):
    path = shared_file(name)
    h, _, _, _, _, values = _blocks(path)
    orders, cols, c0 = [], [], 0
    for ch in h["channels"]:
        rot = [k for k, c in enumerate(ch) if c in ROTATION_CHANNELS]
        orders.append("".join(ch[k][0] for k in rot))
        cols.append([c0 + k for k in rot])
        c0 += len(ch)
    q = bvh_mod._euler_to_quat(values, orders, cols)
    for j, (order, c) in enumerate(zip(orders, cols)):
        if not order:
            assert np.array_equal(q[:, j], np.broadcast_to([0, 0, 0, 1.0], q[:, j].shape))
            continue
        ref = Rotation.from_euler(order.upper(), values[:, c], degrees=True).as_quat()
        np.testing.assert_allclose(q[:, j], ref, rtol=0, atol=1e-15)


@pytest.mark.parametrize("orders", [["ZYX", "ZYX", "ZYX"], ["ZXY", "", "XYZ", "ZXY", "YZX"]])
def test_nd_from_euler_with_mixed_orders_and_joints_without_rotations(orders):
    rng = np.random.default_rng(5)
    cols, c0 = [], 0
    for o in orders:
        cols.append(list(range(c0, c0 + len(o))))
        c0 += len(o)
    values = rng.uniform(-400, 400, size=(23, c0))
    q = bvh_mod._euler_to_quat(values, orders, cols)
    assert q.shape == (23, len(orders), 4)
    for j, (order, c) in enumerate(zip(orders, cols)):
        ref = (Rotation.from_euler(order, values[:, c], degrees=True).as_quat() if order
               else np.broadcast_to([0, 0, 0, 1.0], (23, 4)))
        np.testing.assert_allclose(q[:, j], ref, rtol=0, atol=1e-15)


# -------------------------------------------------------- forward kinematics
@pytest.mark.parametrize("name", ALL_BVH)
def test_fk_equals_stacked_products_on_real_files(name):
    clip = load_bvh(shared_file(name), drop_tpose=False)
    R, P = clip._fk()
    R0, P0 = plain_fk(clip)
    assert R.shape == R0.shape and P.shape == P0.shape
    assert R.flags.c_contiguous and P.flags.c_contiguous
    assert not R.flags.writeable and not P.flags.writeable
    np.testing.assert_allclose(R, R0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(P, P0, rtol=0, atol=1e-12)


def test_fk_with_animated_joint_translations():
    rng = np.random.default_rng(7)
    sk = Skeleton(["a", "b", "c", "d", "e"], [-1, 0, 1, 1, 3],
                  rng.normal(size=(5, 3)),
                  [("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"),
                   ("Zrotation", "Xrotation", "Yrotation"),
                   ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"),
                   (), ("Yrotation", "Xrotation", "Zrotation")])
    F = 17
    clip = Clip(sk, 30.0, rng.normal(size=(F, 3)), Rotation.random(F * 5, random_state=3)
                .as_quat().reshape(F, 5, 4), rng.normal(size=(F, 5, 3)))
    R, P = clip._fk()
    R0, P0 = plain_fk(clip)
    np.testing.assert_allclose(R, R0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(P, P0, rtol=0, atol=1e-12)


# ------------------------------------------------------------------ multi-flip
def _assert_same_multiflip(r0, r1):
    c0, c1 = r0.clip, r1.clip
    assert (r0.flips, r0.takeoff, r0.landing) == (r1.flips, r1.takeoff, r1.landing)
    assert c0.num_frames == c1.num_frames and c0.meta == c1.meta
    np.testing.assert_allclose(c1.rotations, c0.rotations, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c1.root_pos, c0.root_pos, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c1.joint_positions(), c0.joint_positions(), rtol=0, atol=1e-12)
    rep1 = r1.report.to_dict()
    assert r0.report.keys() == rep1.keys()
    for key, v in r0.report.items():
        if isinstance(v, dict):
            assert v.keys() == rep1[key].keys()
            for k2, v2 in v.items():
                assert rep1[key][k2] == pytest.approx(v2, rel=1e-9, abs=1e-9), (key, k2)
        else:
            assert rep1[key] == pytest.approx(v, rel=1e-9, abs=1e-9), key


@pytest.fixture(scope="module")
def builtin_flips():
    from flipstudy.stimuli import analyse, builtin
    return {name: analyse(builtin(name)) for name in ("backflip", "frontflip")}


@pytest.mark.parametrize("name", ["backflip", "frontflip"])
@pytest.mark.parametrize("kw", [dict(flips=1, k_ratio=1.0), dict(flips=2, k_ratio=1.0),
                                dict(flips=3, k_ratio=1.0), dict(flips=4, k_ratio=1.0),
                                dict(flips=2), dict(flips=2, takeoff_height=0.3),
                                dict(flips=3, k=1.2, blend_s=0.05)])
def test_multiflip_on_prepared_source_equals_the_plain_implementation(builtin_flips, name, kw):
    import _multiflip_reference as ref
    from flipstudy.stimuli.edit.multiflip import flip_source, multiflip
    a = builtin_flips[name]
    r0 = ref.multiflip(a, **kw)
    _assert_same_multiflip(r0, multiflip(a, **kw))
    _assert_same_multiflip(r0, multiflip(flip_source(a), **kw))


@pytest.mark.parametrize("name", ["88_01.bvh", "87_03.bvh", "90_11.bvh"])
def test_multiflip_of_real_cmu_equals_the_plain_implementation(name):
    """Real clips also put cross-fades next to take-off or landing, where the
    sequenced clip's COM is read (and computed for them alone)."""
    import _multiflip_reference as ref
    from flipstudy.stimuli import analyse
    from flipstudy.errors import FlipEditError
    from flipstudy.stimuli.edit.multiflip import flip_source, multiflip
    a = analyse(load_bvh(shared_file(name)))
    pre = flip_source(a)
    for flips in (2, 3):
        for kw in (dict(k_ratio=1.0), dict(blend_s=0.1), dict(takeoff_height=0.2)):
            try:
                r0 = ref.multiflip(a, flips, **kw)
            except ref.FlipEditError as e:
                with pytest.raises(FlipEditError, match=str(e)[:30]):
                    multiflip(pre, flips, **kw)
                continue
            _assert_same_multiflip(r0, multiflip(pre, flips, **kw))


def test_sampling_at_whole_frames_keeps_the_source_quaternions():
    from flipstudy.stimuli import builtin
    from flipstudy.stimuli.edit.timing import sample
    clip = builtin("backflip")
    s = np.array([0.0, 3.0, 3.25, 7.0, 7.5, clip.num_frames - 1.0])
    out = sample(clip, s)
    whole = s == np.floor(s)
    assert np.array_equal(out.rotations[whole], clip.rotations[s[whole].astype(int)])
    q0 = Rotation.from_quat(clip.rotations[[3, 7]])
    q1 = Rotation.from_quat(clip.rotations[[4, 8]])
    u = np.array([0.25, 0.5])[:, None, None]
    slerp = (q0 * Rotation.from_rotvec((q0.inv() * q1).as_rotvec() * u)).as_quat()
    np.testing.assert_allclose(out.rotations[~whole], slerp, rtol=0, atol=1e-15)

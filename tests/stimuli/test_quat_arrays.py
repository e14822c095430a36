"""The quaternion arrays of the multi-flip hot path (issue 34, item 5):
:mod:`flipstudy.stimuli.motion.quat` is scipy ``Rotation``'s arithmetic on stacks
without the objects, so it must give the very same bits — checked three ways:

1. each function against scipy on the shapes the old code passed (stacks of more
   than one leading axis), random and degenerate inputs (hypothesis);
2. ``multiflip`` run twice, once with the module's functions swapped for the
   scipy calls the old code made: byte-identical outputs on built-in and CMU flips;
3. sha256 of ``multiflip``'s outputs as the old code path (main at e4afe3d,
   before this change) printed them on this project's pinned numpy 2.4.6 /
   scipy 1.17.1, for 5 clips × 4 flip counts × 3 settings (skipped with the
   reason under other versions: float bits are only promised per version).
"""
from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from _shared import shared_file
from flipstudy.stimuli.motion import quat


def _nd(x):             # the old code's (n, 1, k) stacks: scipy's array backend
    return x.reshape(-1, 1, x.shape[-1])


def _scipy(name):
    """The scipy call the old code made for each quat function, same shapes."""
    def norm(x):
        return np.linalg.norm(x, axis=-1, keepdims=True)

    def normalized(q):
        return Rotation.from_quat(_nd(q)).as_quat().reshape(q.shape)

    def mul(p, q):
        p, q = np.broadcast_arrays(p, q)
        r = Rotation(_nd(p), normalize=False) * Rotation(_nd(q), normalize=False)
        return r.as_quat().reshape(p.shape)

    def from_rotvec(v):
        return Rotation.from_rotvec(_nd(v)).as_quat().reshape(v.shape[:-1] + (4,))

    def as_rotvec(q):
        return Rotation(_nd(q), normalize=False).as_rotvec().reshape(q.shape[:-1] + (3,))

    return locals()[name]


def _same(a, b):
    assert a.shape == b.shape and a.tobytes() == b.tobytes()


finite = st.floats(-2.0, 2.0, allow_nan=False, width=64)
quats = arrays(np.float64, st.tuples(st.integers(1, 12), st.just(4)), elements=finite).filter(
    lambda q: np.all(np.linalg.norm(q, axis=-1) > 1e-3))
# rotation vectors from nothing to past π, including the series' range |v| <= 1e-3
vecs = arrays(np.float64, st.tuples(st.integers(1, 12), st.just(3)),
              elements=st.one_of(st.floats(-4.0, 4.0, width=64), st.floats(-4e-4, 4e-4, width=64),
                                 st.just(0.0)))


@settings(max_examples=150, deadline=None)
@given(quats, quats)
def test_products_norms_and_logs_equal_scipys_bits(p, q):
    n = min(len(p), len(q))
    p, q = p[:n], q[:n]
    _same(quat.norm(p), _scipy("norm")(p))
    P, Q = quat.normalized(p), quat.normalized(q)
    _same(P, _scipy("normalized")(p))
    _same(quat.mul(P, Q), _scipy("mul")(P, Q))
    _same(quat.inv(P), Rotation(_nd(P), normalize=False).inv().as_quat().reshape(P.shape))
    _same(quat.as_rotvec(P), _scipy("as_rotvec")(P))


@settings(max_examples=150, deadline=None)
@given(vecs)
def test_exp_equals_scipys_bits(v):
    _same(quat.from_rotvec(v), _scipy("from_rotvec")(v))


@settings(max_examples=150, deadline=None)
@given(quats, vecs)
def test_matrices_and_applied_vectors_equal_scipys_bits(q, v):
    """as_matrix and apply against the (n, 4) Rotation calls the old forward kinematics
    and turns made (scipy's compiled path for one leading axis), bit for bit."""
    n = min(len(q), len(v))
    q, v = q[:n], v[:n]
    _same(quat.as_matrix(quat.normalized(q)), Rotation.from_quat(q).as_matrix())
    _same(quat.apply(quat.normalized(q), v), Rotation.from_quat(q).apply(v))
    rv = np.roll(v, 1, axis=0)
    _same(quat.apply(quat.from_rotvec(rv), v), Rotation.from_rotvec(rv).apply(v))


def test_forward_kinematics_local_matrices_are_scipys():
    """Clip._fk's local matrices (built in its component-major layout) are the ones
    Rotation.from_quat(...).as_matrix() gives: the root's world rotation is its local one."""
    from flipstudy import load_bvh
    clip = load_bvh(shared_file("88_01.bvh"))
    _same(np.ascontiguousarray(clip.joint_rotations()[:, 0]),
          Rotation.from_quat(clip.rotations[:, 0]).as_matrix())


def test_logs_of_the_canonical_sign_cases():
    """w = 0 with leading zeros: scipy's canonical sign rule, case by case."""
    q = np.array([[-1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 0], [0, 0, 0, -1.0],
                  [0, 0.6, -0.8, 0], [1e-300, 0, 0, 1.0]])
    _same(quat.as_rotvec(q), _scipy("as_rotvec")(q))
    # the rotation vectors are half turns about the axes, whichever sign came in
    assert np.allclose(np.abs(quat.as_rotvec(q[:3])), np.pi * np.eye(3))


def test_slerp_of_real_joint_rotations_equals_the_scipy_expression():
    from flipstudy.stimuli.edit.timing import slerp
    from flipstudy import load_bvh
    rot = load_bvh(shared_file("88_01.bvh")).rotations
    q0, q1 = rot[100:160], rot[101:161]
    u = np.linspace(0, 1, 60)[:, None]
    a = Rotation.from_quat(q0)
    rel = (a.inv() * Rotation.from_quat(q1)).as_rotvec()
    old = (a * Rotation.from_rotvec(rel * u[..., None])).as_quat()
    _same(slerp(q0, q1, u), old)
    # and its ends are the inputs, up to sign and rounding
    np.testing.assert_allclose(np.abs(slerp(q0, q1, np.ones((60, 1)))), np.abs(q1), atol=1e-12)


def _digest(r) -> str:
    h = hashlib.sha256()
    for a in (r.clip.rotations, r.clip.root_pos):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(f"{r.takeoff} {r.landing}".encode())
    h.update(json.dumps(r.report.to_dict(), sort_keys=True).encode())
    return h.hexdigest()[:16]


def _source(name):
    from flipstudy import analyse, builtin, load_bvh
    from flipstudy.stimuli.edit.multiflip import flip_source
    return flip_source(analyse(load_bvh(shared_file(name)) if name.endswith(".bvh") else builtin(name)))


@pytest.mark.parametrize("name", ["backflip", "frontflip", "88_01.bvh", "87_03.bvh"])
def test_multiflip_is_byte_identical_to_the_scipy_object_path(name, monkeypatch):
    from flipstudy.stimuli.edit.multiflip import multiflip
    pre = _source(name)
    cases = [(2, {}), (3, dict(k_ratio=0.7, takeoff_height=0.2)), (4, dict(k=1.2, blend_s=0.05))]
    new = [_digest(multiflip(pre, n, **kw)) for n, kw in cases]
    for f in ("norm", "normalized", "mul", "from_rotvec", "as_rotvec"):
        monkeypatch.setattr(quat, f, _scipy(f))
    old = [_digest(multiflip(pre, n, **kw)) for n, kw in cases]
    assert new == old


# sha256[:16] of multiflip(flip_source(analyse(clip)), flips, **kw): clip rotations and root
# positions (bytes), flight frames and the report (JSON), printed by main at e4afe3d
OLD_CODE = [
    ('backflip', 1, '{"k_ratio": 1.0}', 'd56d8eff32998c46'),
    ('backflip', 1, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'f83e1f24097c1570'),
    ('backflip', 1, '{"blend_s": 0.05, "k": 1.2}', '21f9ddb83a5bdf2e'),
    ('backflip', 2, '{"k_ratio": 1.0}', 'ac6fe8aa6e0deda0'),
    ('backflip', 2, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'd6c3b1e6a8804f82'),
    ('backflip', 2, '{"blend_s": 0.05, "k": 1.2}', 'c7ca378ee01a8a62'),
    ('backflip', 3, '{"k_ratio": 1.0}', '07d1f67dad3c3c8b'),
    ('backflip', 3, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '36af162e24076a1c'),
    ('backflip', 3, '{"blend_s": 0.05, "k": 1.2}', 'a3b8beb2467a75c3'),
    ('backflip', 4, '{"k_ratio": 1.0}', 'dd100b96bf829311'),
    ('backflip', 4, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '1398aaae8b4e6c4e'),
    ('backflip', 4, '{"blend_s": 0.05, "k": 1.2}', '6d6d22a8f103da7a'),
    ('frontflip', 1, '{"k_ratio": 1.0}', '93c26cb4d4b4a8e2'),
    ('frontflip', 1, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'ca32b5d0212b79d4'),
    ('frontflip', 1, '{"blend_s": 0.05, "k": 1.2}', '59ff0c606c02b30d'),
    ('frontflip', 2, '{"k_ratio": 1.0}', 'cd495b10c67f14f7'),
    ('frontflip', 2, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '1ba7e1bff567d1a3'),
    ('frontflip', 2, '{"blend_s": 0.05, "k": 1.2}', '220ddf00ccb30b14'),
    ('frontflip', 3, '{"k_ratio": 1.0}', '604b802547f9da8f'),
    ('frontflip', 3, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '3d4ac97e4df0f93c'),
    ('frontflip', 3, '{"blend_s": 0.05, "k": 1.2}', '3e79aac4297515ba'),
    ('frontflip', 4, '{"k_ratio": 1.0}', 'a06a3bad8cf42dcc'),
    ('frontflip', 4, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'd0eae9f5460496f2'),
    ('frontflip', 4, '{"blend_s": 0.05, "k": 1.2}', 'dad0b3e27753138c'),
    ('88_01.bvh', 1, '{"k_ratio": 1.0}', '08553fb59037d064'),
    ('88_01.bvh', 1, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'b3510f1fda9c967f'),
    ('88_01.bvh', 1, '{"blend_s": 0.05, "k": 1.2}', 'cbdbcee2b8946868'),
    ('88_01.bvh', 2, '{"k_ratio": 1.0}', '0c7979393fc182f5'),
    ('88_01.bvh', 2, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'dd4297dd2f1fb551'),
    ('88_01.bvh', 2, '{"blend_s": 0.05, "k": 1.2}', '311660848faf3525'),
    ('88_01.bvh', 3, '{"k_ratio": 1.0}', '5f867f28661ee146'),
    ('88_01.bvh', 3, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'b2b74dc9f5c32340'),
    ('88_01.bvh', 3, '{"blend_s": 0.05, "k": 1.2}', '4294bc6b7d303558'),
    ('88_01.bvh', 4, '{"k_ratio": 1.0}', '1afda8104b156bf2'),
    ('88_01.bvh', 4, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '415f06065ba3c8d0'),
    ('88_01.bvh', 4, '{"blend_s": 0.05, "k": 1.2}', 'f8bbc780203f9445'),
    ('87_03.bvh', 1, '{"k_ratio": 1.0}', '3a2f50ea4282b222'),
    ('87_03.bvh', 1, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'b8cbb95a8d6f1a1c'),
    ('87_03.bvh', 1, '{"blend_s": 0.05, "k": 1.2}', '8fb834716fe2e144'),
    ('87_03.bvh', 2, '{"k_ratio": 1.0}', 'ce20dd48ef22a5cb'),
    ('87_03.bvh', 2, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'e631b435057cc475'),
    ('87_03.bvh', 2, '{"blend_s": 0.05, "k": 1.2}', 'ef6f55143e4030a2'),
    ('87_03.bvh', 3, '{"k_ratio": 1.0}', '38dee28cc73e00dc'),
    ('87_03.bvh', 3, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'b7e33500c7073bbc'),
    ('87_03.bvh', 3, '{"blend_s": 0.05, "k": 1.2}', 'd427dfc354f383a8'),
    ('87_03.bvh', 4, '{"k_ratio": 1.0}', '9bac5d39f47bf578'),
    ('87_03.bvh', 4, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '2c649fcdee5b9dcd'),
    ('87_03.bvh', 4, '{"blend_s": 0.05, "k": 1.2}', '9d15c8142a8a939e'),
    ('90_11.bvh', 1, '{"k_ratio": 1.0}', 'f57fd529d5256ea8'),
    ('90_11.bvh', 1, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '0d76a902b4924af0'),
    ('90_11.bvh', 1, '{"blend_s": 0.05, "k": 1.2}', '08887d2eab50effe'),
    ('90_11.bvh', 2, '{"k_ratio": 1.0}', '2fe655d70e14ac51'),
    ('90_11.bvh', 2, '{"k_ratio": 0.7, "takeoff_height": 0.2}', '07e5324e968c48de'),
    ('90_11.bvh', 2, '{"blend_s": 0.05, "k": 1.2}', 'c4d6aa04817bd45f'),
    ('90_11.bvh', 3, '{"k_ratio": 1.0}', '45304c73bce85f01'),
    ('90_11.bvh', 3, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'def51897ea6265e8'),
    ('90_11.bvh', 3, '{"blend_s": 0.05, "k": 1.2}', 'ff83e582464f6235'),
    ('90_11.bvh', 4, '{"k_ratio": 1.0}', 'FlipEditError'),
    ('90_11.bvh', 4, '{"k_ratio": 0.7, "takeoff_height": 0.2}', 'FlipEditError'),
    ('90_11.bvh', 4, '{"blend_s": 0.05, "k": 1.2}', 'FlipEditError'),]


@pytest.mark.parametrize("name", ["backflip", "frontflip", "88_01.bvh", "87_03.bvh", "90_11.bvh"])
def test_multiflip_outputs_are_the_old_codes_bytes(name):
    import scipy
    from flipstudy.stimuli.edit.multiflip import FlipEditError, multiflip
    if (np.__version__, scipy.__version__) != ("2.4.6", "1.17.1"):
        pytest.skip(f"the hashes were recorded with numpy 2.4.6 / scipy 1.17.1, not "
                    f"{np.__version__} / {scipy.__version__}")
    pre = _source(name)
    rows = [r for r in OLD_CODE if r[0] == name]
    assert len(rows) == 12
    for _, flips, kw, want in rows:
        try:
            got = _digest(multiflip(pre, flips, **json.loads(kw)))
        except FlipEditError as e:
            got = type(e).__name__
        assert got == want, (name, flips, kw)

"""The quaternion arrays of the multi-flip hot path (issue 34, item 5):
:mod:`flipstudy.stimuli.motion.quat` is scipy ``Rotation``'s arithmetic on stacks
without the objects, so it must give the very same bits — checked three ways:

1. each function against scipy on the shapes the old code passed (stacks of more
   than one leading axis), random and degenerate inputs (hypothesis);
2. ``multiflip`` run twice, once with the module's functions swapped for the
   scipy calls the old code made: byte-identical outputs on built-in and CMU flips;
3. ``multiflip`` on 5 clips × 4 flip counts × 3 settings against the old code's
   scipy calls, both computed in the same run, to a tolerance of rounding (an
   earlier version compared sha256 digests recorded on one processor, which
   another processor's SIMD kernels do not reproduce).
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


def _outputs(pre, flips, kw):
    """What a user keeps of one multiflip: the clip, its flight frames and the report
    (or the name of the error it raised)."""
    from flipstudy.stimuli.edit.multiflip import FlipEditError, multiflip
    try:
        r = multiflip(pre, flips, **kw)
    except FlipEditError as e:
        return type(e).__name__
    return r.clip.rotations.copy(), r.clip.root_pos.copy(), (r.takeoff, r.landing), r.report.to_dict()


def _close(a, b, path=""):
    """Reports equal: numbers within 1e-9 (relative), everything else exactly."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12, nan_ok=True), path
    else:
        assert a == b, path


SETTINGS = [{"k_ratio": 1.0}, {"k_ratio": 0.7, "takeoff_height": 0.2}, {"blend_s": 0.05, "k": 1.2}]


@pytest.mark.parametrize("name", ["backflip", "frontflip", "88_01.bvh", "87_03.bvh", "90_11.bvh"])
def test_multiflip_outputs_match_the_old_scipy_code_path(name, monkeypatch):
    """5 clips x 4 flip counts x 3 settings: the arrays path and the old code's scipy
    calls, both computed in this run, agree to rounding (1e-12 on rotations and root
    positions, the same flight frames, the same report); 90_11 cannot take 4 flips on
    either path.  Tolerances, not recorded digests: float bits differ per processor."""
    pre = _source(name)
    cases = [(n, kw) for n in (1, 2, 3, 4) for kw in SETTINGS]
    new = [_outputs(pre, n, kw) for n, kw in cases]
    for f in ("norm", "normalized", "mul", "from_rotvec", "as_rotvec"):
        monkeypatch.setattr(quat, f, _scipy(f))
    old = [_outputs(pre, n, kw) for n, kw in cases]
    for (n, kw), a, b in zip(cases, new, old):
        if isinstance(b, str):
            assert a == b, (name, n, kw)
            continue
        assert not isinstance(a, str), (name, n, kw, a)
        np.testing.assert_allclose(a[0], b[0], rtol=0, atol=1e-12, err_msg=f"{name} {n} {kw}")
        np.testing.assert_allclose(a[1], b[1], rtol=0, atol=1e-12, err_msg=f"{name} {n} {kw}")
        assert a[2] == b[2], (name, n, kw)
        _close(a[3], b[3], f"{name} {n} {kw}")
    errors = [(n, kw) for (n, kw), b in zip(cases, old) if isinstance(b, str)]
    assert errors == ([(4, kw) for kw in SETTINGS] if name == "90_11.bvh" else [])

"""Body model: automatic mapping on every real skeleton, table masses, inertia."""
import numpy as np
import pytest

from flipstudy.errors import BodyMappingError
from flipstudy.stimuli.body import Body, GROUPS, SEGMENT_TABLE, ellipsoid_inertia
from flipstudy.stimuli.motion import Skeleton, load_bvh

from _shared import ALL_BVH, shared_file


def test_table_fractions_sum_to_one():
    total = sum(v[0] * (1 if g in ("head", "trunk") else 2) for g, v in SEGMENT_TABLE.items())
    assert total == pytest.approx(1.0, abs=1e-3)


def test_ellipsoid_inertia_closed_form():
    # a solid ellipsoid with semi-axes (a, b, b) along x: Ixx = 2/5 m b², Iyy = Izz = m/5 (a²+b²)
    I = ellipsoid_inertia(np.array([2.0]), np.array([0.3]), np.array([0.1]), np.array([[1.0, 0, 0]]))[0]
    assert np.allclose(np.diag(I), [2 / 5 * 2 * 0.01, 2 / 5 * (0.09 + 0.01), 2 / 5 * (0.09 + 0.01)])
    assert np.allclose(I, I.T)
    # rotated axis: same eigenvalues
    u = np.array([[1.0, 1.0, 0.0]]) / np.sqrt(2)
    I2 = ellipsoid_inertia(np.array([2.0]), np.array([0.3]), np.array([0.1]), u)[0]
    assert np.allclose(np.sort(np.linalg.eigvalsh(I2)), np.sort(np.diag(I)))


@pytest.mark.parametrize("name", ALL_BVH)
def test_every_real_skeleton_maps(name):
    clip = load_bvh(shared_file(name))
    body = Body.from_skeleton(clip.skeleton, total_mass=70.0)
    masses = body.segment_masses()
    assert sum(masses.values()) == pytest.approx(70.0)
    for g in GROUPS:
        assert body.group_masses()[g] == pytest.approx(
            SEGMENT_TABLE[g][0] * 70.0 * (1 if g in ("head", "trunk") else 2), rel=1e-9)
    # limbs hang off the right joints: left and right segments on opposite sides of the
    # body's sagittal plane in the rest pose
    P = clip.skeleton.rest_positions()
    lm = body.landmarks
    hl, hr = P[clip.skeleton.index(lm["hip_l"])], P[clip.skeleton.index(lm["hip_r"])]
    sl, sr = P[clip.skeleton.index(lm["shoulder_l"])], P[clip.skeleton.index(lm["shoulder_r"])]
    assert np.linalg.norm(hl - hr) > 0.05 and np.linalg.norm(sl - sr) > 0.1
    # the thigh is longer than the foot, the trunk heavier than a thigh
    assert np.all(body.radius > 0) and np.all(np.isfinite(body.inertia))


def test_mapping_override_and_errors():
    names = ["Root", "Torso", "Skull", "A1", "A2", "A3", "B1", "B2", "B3", "C1", "C2", "C3", "D1", "D2", "D3"]
    parents = [-1, 0, 1, 1, 3, 4, 1, 6, 7, 0, 9, 10, 0, 12, 13]
    offs = np.zeros((15, 3))
    offs[1] = [0, 0.5, 0]; offs[2] = [0, 0.2, 0]
    offs[3] = [0.2, 0.0, 0]; offs[4] = [0.3, 0, 0]; offs[5] = [0.25, 0, 0]
    offs[6] = [-0.2, 0.0, 0]; offs[7] = [-0.3, 0, 0]; offs[8] = [-0.25, 0, 0]
    offs[9] = [0.1, -0.05, 0]; offs[10] = [0, -0.45, 0]; offs[11] = [0, -0.45, 0]
    offs[12] = [-0.1, -0.05, 0]; offs[13] = [0, -0.45, 0]; offs[14] = [0, -0.45, 0]
    sk = Skeleton(names, parents, offs, end_sites=[(2, [0, 0.2, 0]), (5, [0.1, 0, 0]), (8, [-0.1, 0, 0]),
                                                  (11, [0, -0.05, 0.15]), (14, [0, -0.05, 0.15])])
    with pytest.raises(BodyMappingError, match="no joint found"):
        Body.from_skeleton(sk)
    mapping = {"neck": "Torso", "head": "Skull", "shoulder_l": "A1", "elbow_l": "A2", "wrist_l": "A3",
               "shoulder_r": "B1", "elbow_r": "B2", "wrist_r": "B3", "hip_l": "C1", "knee_l": "C2",
               "ankle_l": "C3", "hip_r": "D1", "knee_r": "D2", "ankle_r": "D3"}
    body = Body.from_skeleton(sk, total_mass=60.0, mapping=mapping)
    assert sum(body.segment_masses().values()) == pytest.approx(60.0)
    with pytest.raises(BodyMappingError, match="no such joint"):
        Body.from_skeleton(sk, mapping={**mapping, "head": "Nope"})
    heavier = body.with_segment_masses({"trunk": 30.0})
    assert heavier.segment_masses()["trunk"] == pytest.approx(30.0)


def _segment_shape(body, seg):
    """(total length along the chain, short semi-axis) of one segment."""
    m = body.segment == body.segment_names.index(seg)
    return float(np.linalg.norm(body.dist[m] - body.prox[m], axis=1).sum()), float(body.radius[m].max())


@pytest.mark.parametrize("name", ALL_BVH)
def test_segments_are_body_shaped(name):
    """Trunk from mid-hip to the shoulder line, head above it, no flat discs: every
    segment but the hands (flat by nature, and CMU's are 6 cm long) is at least 1.5×
    as long as it is wide, and the trunk spans the hip-to-shoulder distance of the
    clip's first frame (iClone's rest pose folds the clavicles: measured on the clip)."""
    import warnings
    clip = load_bvh(shared_file(name))
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        body = Body.from_clip(clip, total_mass=70.0)
    for seg in body.segment_names:
        length, radius = _segment_shape(body, seg)
        ratio = 1.0 if seg.startswith("hand") else 1.5
        assert length >= ratio * radius, f"{seg}: {length:.3f} m long, {radius:.3f} m wide"
        assert length < 0.8, f"{seg}: {length:.3f} m long"
    P = clip.joint_positions()[0]
    ix = clip.skeleton.index
    lm = body.landmarks
    mid_hip = (P[ix(lm["hip_l"])] + P[ix(lm["hip_r"])]) / 2
    mid_sh = (P[ix(lm["shoulder_l"])] + P[ix(lm["shoulder_r"])]) / 2
    trunk_len, _ = _segment_shape(body, "trunk")
    assert 0.9 * np.linalg.norm(mid_sh - mid_hip) <= trunk_len <= 1.25 * np.linalg.norm(mid_sh - mid_hip)


def test_broken_hand_end_site_is_replaced_with_a_warning():
    """The MASS rig's right hand has a 1.62 m End Site: a hand that long would carry
    the hand's mass half a body away; the body uses a typical hand and says so."""
    clip = load_bvh(shared_file("mass_cartwheel.bvh"))
    with pytest.warns(UserWarning, match=r"hand_r.*1\.62 m long"):
        body = Body.from_skeleton(clip.skeleton)
    assert _segment_shape(body, "hand_r")[0] == pytest.approx(_segment_shape(body, "hand_l")[0], rel=0.05)


@pytest.mark.parametrize("name", ["builtin", "88_01.bvh", "01_01_iclone-retarget.bvh", "mass_kick.bvh"])
def test_trunk_com_at_de_levas_fraction(name):
    """De Leva (1996) Table 4: the trunk's COM is 43.10 % of MIDS → MIDH from the
    mid-shoulder point (the same place as 51.38 % of CERV → MIDH from C7): with the
    trunk ending at the shoulder joints it sits at 56.90 % from the mid-hip, not at
    the 50 % of a chain of spine bones each weighed at its midpoint.  Measured with
    the physics' own piece positions on the clip's frames, along the mid-hip →
    mid-shoulder line of each frame."""
    import warnings
    from flipstudy.stimuli import builtin
    from flipstudy.stimuli.physics import piece_positions
    clip = builtin("backflip") if name == "builtin" else load_bvh(shared_file(name))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        body = Body.from_clip(clip, total_mass=70.0)
    t = body.segment == body.segment_names.index("trunk")
    assert t.sum() > 1                                         # a chain of spine bones
    c = piece_positions(clip, body)[:, t]
    com = np.einsum("fpa,p->fa", c, body.mass[t]) / body.mass[t].sum()
    P, ix, lm = clip.joint_positions(), clip.skeleton.index, body.landmarks
    mid_hip = (P[:, ix(lm["hip_l"])] + P[:, ix(lm["hip_r"])]) / 2
    axis = (P[:, ix(lm["shoulder_l"])] + P[:, ix(lm["shoulder_r"])]) / 2 - mid_hip
    n = np.linalg.norm(axis, axis=1)
    frac = np.einsum("fa,fa->f", com - mid_hip, axis) / n ** 2
    assert SEGMENT_TABLE["trunk"][1] == pytest.approx(1 - 0.4310)
    # the spine bends during the motion: the frames' median within 1 % of the length
    assert np.median(frac) == pytest.approx(0.5690, abs=0.01)

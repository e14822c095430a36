"""The joint-position and AMASS/SMPL readers behind the one loading rule
(``load_clip``, every command's CLIP), their physics gate, ``convert``, and bad inputs.

Tolerances, measured on the CMU takes made into HumanML3D arrays (22 SMPL joints,
20 fps, resampled with the project's slerp sampler) against the BVH read at 60 fps:
the contact instants within 0.05 s (88_01's take-off; the others 17–35 ms;
asserted: one frame of the array, 0.05 s),
apparent gravity within 3.7 % (asserted 5 %; the 22-joint body has no fingers and
a stub head, so its COM is not the BVH body's).  The AMASS file is made here from
a synthetic body model of the documented format, so every joint has a closed form.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from _positions import cmu_humanml3d, synthetic_body_model
from _shared import shared_file
from flipstudy import analyse, load_bvh
from flipstudy.errors import FlipstudyError, MotionFileError
from flipstudy.stimuli import load_clip
from flipstudy.stimuli.convert import convert
from flipstudy.stimuli.motion.positions import SMPL22_NAMES, SMPL22_PARENTS as SMPL_PARENTS, positions_of
from flipstudy.study.cli import main

G = 9.81


def in_order(clip, names=SMPL22_NAMES):
    """(F, J, 3) joint positions of a clip in the order of ``names`` (a position clip's
    joints are in depth-first order, as BVH lists them)."""
    return clip.joint_positions()[:, [clip.skeleton.index(n) for n in names]]


@pytest.fixture(scope="module")
def cmu88():
    return load_bvh(shared_file("88_01.bvh"), fps=60)       # SOURCES.md: subject 88 is 60 Hz


@pytest.mark.parametrize("name", ["88_01.bvh", "87_03.bvh", "88_05.bvh", "90_11.bvh"])
def test_a_humanml3d_array_from_a_cmu_clip_measures_the_bvh_flight_and_gravity(name, tmp_path):
    bvh = load_bvh(shared_file(name), fps=60)
    path = tmp_path / "motion.npy"
    np.save(path, cmu_humanml3d(bvh))                        # (F, 22, 3) float32, 20 fps, Y up, m
    clip = load_clip(str(path))                              # layout humanml3d-22 and 20 fps by default
    assert clip.fps == 20.0 and sorted(clip.skeleton.joint_names) == sorted(SMPL22_NAMES)
    assert clip.meta["scale"] == 1.0 and clip.meta["fit_mm"] < 0.01
    a, b = analyse(clip), analyse(bvh)
    assert abs(a.takeoff_time - b.takeoff_time) <= 0.05 + 1e-9
    assert abs(a.landing_time - b.landing_time) <= 0.05 + 1e-9
    assert a.apparent_gravity == pytest.approx(b.apparent_gravity, rel=0.05)
    assert sum(a.body.segment_masses().values()) == pytest.approx(70.0)


def test_npz_layout_files_up_axis_and_units(cmu88, tmp_path):
    """The CMU clip with all its joints through a layout file (JSON, parents by name;
    TOML, by index), written Z up in centimetres: the same motion comes back."""
    X, layout = positions_of(cmu88)
    (tmp_path / "cmu.json").write_text(json.dumps({
        "joints": list(layout.joints), "fps": 60,
        "parents": [layout.joints[p] if p >= 0 else None for p in layout.parents]}))
    (tmp_path / "cmu.toml").write_text(
        "joints = [" + ", ".join(f'"{n}"' for n in layout.joints) + "]\n"
        f"parents = {list(layout.parents)}\nup = \"z\"\nscale = 0.01\nfps = 60\n")
    np.savez(tmp_path / "y.npz", joints=X, fps=60.0)
    zup_cm = np.stack([X[..., 0], -X[..., 2], X[..., 1]], axis=-1) * 100.0
    np.save(tmp_path / "z.npy", zup_cm)
    a = load_clip(str(tmp_path / "y.npz"), layout=str(tmp_path / "cmu.json"))
    b = load_clip(str(tmp_path / "z.npy"), layout=str(tmp_path / "cmu.toml"))
    c = load_clip(str(tmp_path / "z.npy"), layout=str(tmp_path / "cmu.json"), up="z", fps=60)
    assert c.meta["scale_source"] == "guess: cm"
    for clip in (a, b, c):
        assert clip.fps == 60.0
        assert np.abs(in_order(clip, layout.joints) - X).max() < 1e-6
    assert analyse(a).apparent_gravity == pytest.approx(analyse(cmu88).apparent_gravity, rel=0.01)


@pytest.mark.filterwarnings("ignore:segment foot")      # the 100x body's feet, reported before the refusal
def test_the_physics_gate_names_the_fix(cmu88, tmp_path):
    path = tmp_path / "m.npy"
    np.save(path, cmu_humanml3d(cmu88))
    with pytest.raises(MotionFileError, match=r"m\.npy: apparent gravity .* --fps 20"):
        load_clip(str(path), fps=40)
    (tmp_path / "nofps.json").write_text(json.dumps({"joints": list(SMPL22_NAMES),
                                                     "parents": list(SMPL_PARENTS)}))
    with pytest.raises(MotionFileError, match=r"m\.npy: apparent gravity .* --fps 20"):
        load_clip(str(path), fps=40, layout=str(tmp_path / "nofps.json"))      # no rate in the files
    np.save(path, cmu_humanml3d(cmu88) * 100.0)                  # centimetres read as metres
    with pytest.raises(MotionFileError, match=r"m\.npy: the body is .* tall .* --scale 0\.01"):
        load_clip(str(path))
    X = cmu_humanml3d(cmu88)
    np.save(path, np.stack([X[..., 0], -X[..., 2], X[..., 1]], axis=-1))   # Z up, read as Y up
    with pytest.raises(MotionFileError, match=r"m\.npy: .* lies down.* --up z"):
        load_clip(str(path))
    assert load_clip(str(path), up="z").num_frames == len(X)


@pytest.mark.parametrize("array,layout,expect", [
    (np.zeros((30, 22)), None, r"expected joint positions of shape \(frames >= 2, joints, 3\), got .* \(30, 22\)"),
    (np.zeros((30, 22, 4)), None, r"shape \(frames >= 2, joints, 3\), got .* \(30, 22, 4\)"),
    (np.zeros((30, 263)), None, r"HumanML3D's motion features, not joint positions"),
    (np.zeros((30, 31, 3)), None, r"31 joints per frame and no layout; pass --layout"),
    (np.zeros((30, 22, 3)), "smpl-24", r"layout 'smpl-24': neither a known layout \(humanml3d-22\)"),
    (np.zeros((30, 24, 3)), "humanml3d-22", r"24 joints per frame, but the layout names 22"),
    (np.array([["a"] * 3] * 22 * 3).reshape(3, 22, 3), None, r"expected numbers"),
])
def test_bad_position_arrays_name_the_file_and_what_was_expected(tmp_path, array, layout, expect):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    with pytest.raises(MotionFileError, match=expect) as e:
        load_clip(str(path), layout=layout)
    assert str(path) in str(e.value) or "layout" in str(e.value)


def test_nan_frames_are_listed(cmu88, tmp_path):
    X = cmu_humanml3d(cmu88)
    X[[5, 17], 3, 1] = np.nan
    np.save(tmp_path / "nan.npy", X)
    with pytest.raises(MotionFileError, match=r"nan\.npy: 2 frame\(s\) hold NaN .*frames 5, 17\)"):
        load_clip(str(tmp_path / "nan.npy"))


def test_bad_files_and_layout_files(tmp_path):
    (tmp_path / "pickled.npy").write_bytes(b"")
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    np.savez(tmp_path / "two.npz", a=np.zeros((3, 22, 3)), b=np.zeros(3))
    for name, expect in (("pickled.npy", "not a readable .npy/.npz"), ("obj.npy", "unpickling"),
                         ("two.npz", r"expected joint positions under one of")):
        with pytest.raises(MotionFileError, match=expect):
            load_clip(str(tmp_path / name))
    np.save(tmp_path / "m.npy", np.zeros((5, 3, 3)))
    for text, expect in (('{"joints": ["a", "b", "c"]}', "needs 'joints'"),
                         ('{"joints": ["a", "b", "c"], "parents": [-1, 0, 7]}', r"parents\[2\] .*'c'.* = 7"),
                         ('{"joints": ["a", "b", "c"], "parents": [-1, 2, 0]}', "every joint after its parent"),
                         ('{"joints": ["a", "b", "c"], "parents": [-1, 0, 0], "up": "x"}', "up = 'x'"),
                         ('not json', "not a readable layout file")):
        (tmp_path / "l.json").write_text(text)
        with pytest.raises(MotionFileError, match=expect) as e:
            load_clip(str(tmp_path / "m.npy"), layout=str(tmp_path / "l.json"))
        assert "l.json" in str(e.value)
    (tmp_path / "l.json").write_text('{"joints": ["a", "b", "c"], "parents": [-1, 0, 0]}')
    with pytest.raises(MotionFileError, match=r"m\.npy: neither the file nor layout 'l' gives a frame rate; pass --fps"):
        load_clip(str(tmp_path / "m.npy"), layout=str(tmp_path / "l.json"))


# ------------------------------------------------------------------ AMASS / SMPL
def amass_jump(tmp_path, betas=None, fps=60.0):
    """An AMASS file (Z up) of the synthetic body standing in a T-pose, jumping
    0.5 s ballistically (g = 9.81) and standing again, and the body-model file."""
    model, rest = synthetic_body_model()
    np.savez(tmp_path / "model.npz", **model)
    n_stand, T = int(0.5 * fps), 0.5
    t = np.arange(int(T * fps) + 1) / fps
    hop = 0.5 * G * t * (T - t)                                   # 0 at both contacts
    z = np.concatenate([np.zeros(n_stand), hop, np.zeros(n_stand)])
    F = len(z)
    trans = np.zeros((F, 3))
    trans[:, 1] = np.linspace(0.0, 0.6, F)                        # walking along AMASS's Y
    trans[:, 2] = z
    poses = np.zeros((F, 156))                                    # SMPL-H: 52 joints
    poses[:, :3] = [np.pi / 2, 0.0, 0.0]                          # the model's Y up stood on Z
    poses[n_stand:-n_stand, 18 * 3 + 2] = np.linspace(0.0, 1.2, F - 2 * n_stand)   # left elbow bends
    b = np.zeros(16) if betas is None else np.asarray(betas, float)
    np.savez(tmp_path / "jump_poses.npz", poses=poses, trans=trans, betas=b,
             mocap_framerate=np.float64(fps), gender=np.array("neutral"))
    return tmp_path / "jump_poses.npz", tmp_path / "model.npz", rest, poses, trans


def test_an_amass_file_loads_through_the_body_model(tmp_path):
    path, model, rest, poses, trans = amass_jump(tmp_path)
    clip = load_clip(str(path), body_model=str(model))
    P = in_order(clip)
    # closed form: the rest joints stood up (root at the model's pelvis) plus trans, in Y up
    Rz = Rotation.from_rotvec([np.pi / 2, 0, 0]).as_matrix()
    world_z = (rest - rest[0]) @ Rz.T + rest[0]
    expect = world_z[None] + trans[:, None]                       # AMASS world (Z up)
    expect_y = np.stack([expect[..., 0], expect[..., 2], -expect[..., 1]], axis=-1)
    still = [j for j in range(22) if j not in (20,)]              # the bending elbow moves the left wrist
    assert np.abs(P[:, still] - expect_y[:, still]).max() < 1e-9
    # the left wrist turns about the elbow by the pose's angle (a rotation about the model's z)
    k = len(P) // 2
    fore = rest[20] - rest[18]
    bent = Rotation.from_rotvec([np.pi / 2, 0, 0]).apply(Rotation.from_rotvec([0, 0, poses[k, 56]]).apply(fore))
    want = expect[k, 18] + bent
    assert np.abs(P[k, 20] - [want[0], want[2], -want[1]]).max() < 1e-9
    a = analyse(clip)
    assert a.apparent_gravity == pytest.approx(G, rel=0.02)
    assert a.flight_s == pytest.approx(0.5, abs=1.5 / clip.fps)
    assert clip.fps == 60.0 and clip.meta["up"] == "z"


def test_betas_move_the_joints_by_shapedirs(tmp_path):
    path, model, rest, _, trans = amass_jump(tmp_path, betas=[1.0] + [0.0] * 15)
    P = in_order(load_clip(str(path), body_model=str(model)))
    # beta 0 grows every joint's distance from the template's centroid by 5 %
    m = dict(np.load(model))
    centroid = m["v_template"].mean(axis=0)
    rest_b = centroid + 1.05 * (rest - centroid)
    Rz = Rotation.from_rotvec([np.pi / 2, 0, 0]).as_matrix()
    e = (rest_b - rest_b[0]) @ Rz.T + rest_b[0] + trans[0]
    assert np.abs(P[0] - np.stack([e[:, 0], e[:, 2], -e[:, 1]], axis=-1)).max() < 1e-9


def test_amass_without_or_with_a_bad_body_model_says_what_to_do(tmp_path):
    path, model, *_ = amass_jump(tmp_path)
    with pytest.raises(MotionFileError, match=r"jump_poses\.npz: an AMASS/SMPL motion .* pass --body-model PATH"):
        load_clip(str(path))
    with pytest.raises(MotionFileError, match=r"--body-model .*nope\.npz: no such file"):
        load_clip(str(path), body_model=str(tmp_path / "nope.npz"))
    m = dict(np.load(model))
    np.savez(tmp_path / "partial.npz", **{k: v for k, v in m.items() if k != "J_regressor"})
    with pytest.raises(MotionFileError, match=r"partial\.npz: not an SMPL-family body model: no array J_regressor"):
        load_clip(str(path), body_model=str(tmp_path / "partial.npz"))
    kt = m["kintree_table"].copy()
    kt[0, 4] = 2
    np.savez(tmp_path / "tree.npz", **{**m, "kintree_table": kt})
    with pytest.raises(MotionFileError, match=r"tree\.npz: the first 22 joints of kintree_table"):
        load_clip(str(path), body_model=str(tmp_path / "tree.npz"))
    d = dict(np.load(path))
    np.savez(tmp_path / "short.npz", **{**d, "poses": d["poses"][:, :30]})
    with pytest.raises(MotionFileError, match=r"short\.npz: poses has shape \(\d+, 30\)"):
        load_clip(str(tmp_path / "short.npz"), body_model=str(model))


def test_cli_inspect_and_convert(tmp_path, capsys, cmu88):
    path, model, *_ = amass_jump(tmp_path)
    assert main(["inspect", str(path)]) == 1
    assert "--body-model" in capsys.readouterr().err
    assert main(["inspect", str(path), "--body-model", str(model), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["apparent_gravity"] == pytest.approx(G, rel=0.02) and d["fps"] == 60.0
    # convert: positions → BVH → the same joints, read back by the BVH reader
    X = cmu_humanml3d(cmu88)
    np.save(tmp_path / "m.npy", X)
    out = tmp_path / "m.bvh"
    assert main(["convert", str(tmp_path / "m.npy"), "--out", str(out)]) == 0
    assert "22 joints" in capsys.readouterr().out
    back = load_bvh(out, scale=1.0)
    idx = [back.skeleton.index(n) for n in SMPL22_NAMES]
    assert back.fps == 20.0
    assert np.abs(back.joint_positions()[:, idx] - X).max() < 1e-5
    assert main(["convert", str(tmp_path / "m.npy"), "--out", str(out)]) == 1       # exists: refused
    assert "exists" in capsys.readouterr().err
    r = convert(str(path), tmp_path / "amass.bvh", body_model=str(model))
    assert r.frames == len(np.load(path)["poses"]) and r.joints == 22
    assert type(r).load_json(r.save_json(tmp_path / "convert.json")) == r


def test_every_reader_error_is_a_flipstudy_error():
    assert issubclass(MotionFileError, FlipstudyError) and issubclass(MotionFileError, ValueError)


def test_a_design_builds_stimuli_from_a_position_array(cmu88, tmp_path):
    """``flipstudy stimuli``: a [[clips]] source may be a 22-joint array; the study's
    BVH files carry its joints, and each stimulus' error is measured as for a BVH."""
    from flipstudy.stimuli.contract import StimulusSet
    from flipstudy.stimuli.design import load_design
    from flipstudy.stimuli.stimset import build_stimuli
    np.save(tmp_path / "flip.npy", cmu_humanml3d(cmu88, fps=60))
    (tmp_path / "d.toml").write_text(
        '[study]\nname = "positions"\nseed = 1\nfps = 60\ntolerance_pct = 2.0\n\n'
        '[[clips]]\nname = "flip"\nsource = "flip.npy"\nfps = 60\n\n'
        '[[groups]]\nname = "smooth-increase"\nkind = "angular-momentum"\nprofile = "smooth"\n'
        'sign = 1\nlevels = [0, 25]\n')
    build_stimuli(load_design(tmp_path / "d.toml"), tmp_path / "study", progress=False)
    rows = StimulusSet.read(tmp_path / "study", files=False, design=False).rows()
    r = next(r for r in rows if float(r["level"]) == 25)
    assert abs(float(r["measured_error_pct"]) - 25.0) <= 2.0
    back = load_bvh(tmp_path / "study" / r["bvh"], scale=1.0)
    assert sorted(back.skeleton.joint_names) == sorted(SMPL22_NAMES)


def test_a_layout_file_names_the_landmarks_of_joints_the_body_cannot_guess(cmu88, tmp_path):
    """Joints called j0 … jN: without landmarks the body cannot be built (the error
    names the file and the table to add); with them it is the named skeleton's body."""
    from flipstudy.stimuli.body import Body, BodyMappingError
    X = cmu_humanml3d(cmu88)
    np.save(tmp_path / "m.npy", X)
    anon = [f"j{i}" for i in range(22)]
    layout = {"joints": anon, "parents": list(SMPL_PARENTS), "fps": 20}
    (tmp_path / "bare.json").write_text(json.dumps(layout))
    with pytest.raises(BodyMappingError, match=r"m\.npy: cannot map the skeleton .* 'landmarks' table"):
        load_clip(str(tmp_path / "m.npy"), layout=str(tmp_path / "bare.json"))
    by_name = dict(zip(SMPL22_NAMES, anon))
    lm = {f"{part}_{s[0]}": by_name[f"{s}_{joint}"] for s in ("left", "right")
          for part, joint in (("hip", "hip"), ("knee", "knee"), ("ankle", "ankle"),
                              ("shoulder", "shoulder"), ("elbow", "elbow"), ("wrist", "wrist"))}
    lm.update(neck=by_name["neck"], head=by_name["head"])
    (tmp_path / "named.json").write_text(json.dumps({**layout, "landmarks": lm}))
    a = load_clip(str(tmp_path / "m.npy"), layout=str(tmp_path / "named.json"))
    b = load_clip(str(tmp_path / "m.npy"))
    ba, bb = Body.from_clip(a), Body.from_clip(b)
    assert sorted(ba.segment_masses().values()) == pytest.approx(sorted(bb.segment_masses().values()))
    assert analyse(a).apparent_gravity == pytest.approx(analyse(b).apparent_gravity, rel=1e-9)
    (tmp_path / "bad.json").write_text(json.dumps({**layout, "landmarks": {"elbow": "j3"}}))
    with pytest.raises(MotionFileError, match=r"bad\.json: landmarks\.elbow: unknown landmark"):
        load_clip(str(tmp_path / "m.npy"), layout=str(tmp_path / "bad.json"))


def test_amass_files_with_extra_arrays_read_only_what_they_need(tmp_path):
    """AMASS files carry more (``gender``, ``dmpls``, …; some pickled): only
    ``poses``, ``trans``, ``betas`` and the rate are read; a pickled one of those is refused."""
    path, model, *_ = amass_jump(tmp_path)
    d = dict(np.load(path))
    np.savez(tmp_path / "extra.npz", **d, dmpls=np.zeros((len(d["poses"]), 8)),
             note=np.array([{"x": 1}], dtype=object))
    assert load_clip(str(tmp_path / "extra.npz"), body_model=str(model)).num_frames == len(d["poses"])
    np.savez(tmp_path / "pickled.npz", **{**d, "betas": np.array([None] * 16, dtype=object)})
    with pytest.raises(MotionFileError, match=r"pickled\.npz: cannot read the motion's array 'betas'"):
        load_clip(str(tmp_path / "pickled.npz"), body_model=str(model))

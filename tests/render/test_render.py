"""Offscreen rendering: what the pixels show, not only that files exist.

Small images (160x120 and the like) and short clips keep this file fast.
"""
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.transform import Rotation

from flipstudy.stimuli.body import Body
from flipstudy.stimuli.motion import Clip, Skeleton, save_bvh

from flipstudy.render.camera import Camera, fit_camera
from flipstudy.render.compose import over, read_image
from flipstudy.render.figures import TRAIL_JOINTS, composite_image, ghost_image, overlay_image, strip_image, trail_image
from flipstudy.render.gizmos import support_polygon
from flipstudy.render.staging import stage
from flipstudy.render.video import iter_frames, render_video
from flipstudy.render.geometry import piece_frames, BodyMesh, body_points, resample, unit_sphere
from flipstudy.render.scene import Scene
from flipstudy.render.style import Style, rgb8
from flipstudy.render.study import RENDER_KINDS, parse_size, render_study

SHARED = Path(__file__).resolve().parents[3] / "shared"
HAVE_SYNTH = (Path(__file__).resolve().parents[2] / "stimuli" / "synth" / "__init__.py").exists()

# a plain style for pixel tests: no ground, pure white background, no AA
PLAIN = Style(ground=False, background="#ffffff", anti_aliasing="none")


def _skeleton():
    """A 16-joint figure (joints in depth-first order, so it writes to BVH)."""
    spec = [  # name, parent, offset
        ("Hips", None, [0, 0, 0]), ("Spine", "Hips", [0, 0.25, 0]), ("Neck", "Spine", [0, 0.25, 0]),
        ("Head", "Neck", [0, 0.1, 0]),
        ("LeftArm", "Neck", [0.18, 0, 0]), ("LeftForeArm", "LeftArm", [0.28, 0, 0]),
        ("LeftHand", "LeftForeArm", [0.25, 0, 0]),
        ("RightArm", "Neck", [-0.18, 0, 0]), ("RightForeArm", "RightArm", [-0.28, 0, 0]),
        ("RightHand", "RightForeArm", [-0.25, 0, 0]),
        ("LeftUpLeg", "Hips", [0.1, -0.05, 0]), ("LeftLeg", "LeftUpLeg", [0, -0.42, 0]),
        ("LeftFoot", "LeftLeg", [0, -0.42, 0]),
        ("RightUpLeg", "Hips", [-0.1, -0.05, 0]), ("RightLeg", "RightUpLeg", [0, -0.42, 0]),
        ("RightFoot", "RightLeg", [0, -0.42, 0])]
    names = [n for n, _, _ in spec]
    parents = [-1 if p is None else names.index(p) for _, p, _ in spec]
    ends = [(names.index("Head"), [0, 0.15, 0]), (names.index("LeftHand"), [0.08, 0, 0]),
            (names.index("RightHand"), [-0.08, 0, 0]), (names.index("LeftFoot"), [0, -0.05, 0.15]),
            (names.index("RightFoot"), [0, -0.05, 0.15])]
    return Skeleton(names, parents, [o for _, _, o in spec], end_sites=ends)


def walker(seconds=1.0, fps=60.0, speed=5.0):
    """A rigid figure gliding along +Z at ``speed`` m/s, feet on the ground
    (arms along ±X, i.e. towards the side camera: a compact silhouette)."""
    sk = _skeleton()
    F = int(round(seconds * fps)) + 1
    t = np.arange(F) / fps
    q = np.zeros((F, sk.num_joints, 4))
    q[..., 3] = 1
    root = np.stack([0 * t, 0.93 + 0 * t, speed * t], 1)
    return Clip(sk, fps, root, q, meta={"name": "walker"})


def jumper(fps=60.0, flip=0.0):
    """Stand 0.3 s, fly 0.5 s on a parabola (spinning by ``flip`` rad about X
    in flight), stand 0.2 s.  Take-off frame 18, landing frame 48 at 60 fps."""
    sk = _skeleton()
    F = int(round(1.0 * fps)) + 1
    t = np.arange(F) / fps
    t0, t1 = 0.3, 0.8
    s = np.clip(t - t0, 0, t1 - t0)
    y = 0.93 + 2.45 * s - 4.905 * s ** 2
    root = np.stack([0 * t, y, 1.2 * s], 1)
    q = np.zeros((F, sk.num_joints, 4))
    q[..., 3] = 1
    ang = flip * s / (t1 - t0)
    q[:, 0] = Rotation.from_rotvec(np.stack([ang, 0 * t, 0 * t], 1)).as_quat()
    clip = Clip(sk, fps, root, q, meta={"name": f"jumper{flip:g}"})
    return clip, int(round(t0 * fps)), int(round(t1 * fps))


def nonwhite(img, tol=8):
    return np.any(np.abs(img[..., :3].astype(int) - 255) > tol, axis=-1)


# ------------------------------------------------------------------ geometry
def test_unit_sphere_is_closed_and_outward():
    p, t = unit_sphere(12, 8)
    n = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    assert np.all(np.einsum("ij,ij->i", n, p[t].mean(1)) > 0)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)                          # watertight


def test_body_mesh_pose_is_the_ellipsoid_of_each_segment():
    """One-bone segments are drawn as their physics piece; a segment split over
    several bones (trunk, head) as one ellipsoid from its first to its last end,
    with the same radius: in the reference pose its ends are the chain's ends."""
    clip = walker(0.2)
    body = Body.from_clip(clip)
    bm = BodyMesh(body, (16, 10))
    assert len(bm.joint) == len(body.segment_names)
    f = 3
    R, P = clip.joint_rotations()[f], clip.joint_positions()[f]
    bm.pose(R, P)
    pts = np.asarray(bm.mesh.points).reshape(len(bm.joint), -1, 3)
    for s, name in enumerate(body.segment_names):
        k = np.flatnonzero(body.segment == s)
        j0, j1 = body.joint[k[0]], body.joint[k[-1]]
        prox = P[j0] + R[j0] @ body.prox[k[0]]
        dist = P[j1] + R[j1] @ body.dist[k[-1]]
        c = (prox + dist) / 2
        a = max(np.linalg.norm(dist - prox) / 2, 0.02)
        u = (dist - prox) / np.linalg.norm(dist - prox)
        d = pts[s] - c
        along = d @ u
        across = np.linalg.norm(d - np.outer(along, u), axis=1)
        # every vertex on the ellipsoid (x/a)² + (r/b)² = 1 (multi-bone segments:
        # to the chain's bending over the reference frames)
        tol = 1e-9 if k.size == 1 else 0.08
        np.testing.assert_allclose((along / a) ** 2 + (across / body.radius[k].max()) ** 2, 1.0,
                                   atol=tol, err_msg=name)
    # no drawn segment is a flat disc
    _, _, _, semi = piece_frames(body)
    assert np.all(semi[:, 0] >= 0.5 * semi[:, 1])


def test_resample_rates_and_exact_frames():
    clip, _, _ = jumper(fps=120.0, flip=2.0)
    v = resample(clip, 60.0)
    assert v.fps == 60.0 and v.num_frames == 61
    np.testing.assert_allclose(v.root_pos, clip.root_pos[::2], atol=1e-12)
    same = resample(clip, 120.0)
    assert np.array_equal(same.rotations, clip.rotations)
    up = resample(clip, 240.0)                     # in between: slerp, no jumps
    assert up.num_frames == 241
    ang = Rotation.from_quat(up.rotations[:, 0]).magnitude()
    assert np.all(np.abs(np.diff(ang)) < 0.02)


# -------------------------------------------------------------------- camera
def test_camera_json_roundtrip_and_projection_matches_vtk():
    cam = Camera((3, 1.5, 4), (0, 1, 0), (0, 1, 0), 30.0)
    assert Camera.from_json(json.dumps(cam.to_dict())) == cam
    pts = np.array([[0, 0, 0], [0.5, 1.7, -0.3], [-1, 0.2, 0.4]])
    with Scene(None, PLAIN, (160, 120), cam) as sc:
        sc.grab()
        ren = sc.plotter.renderer
        for p, q in zip(pts, cam.project(pts, (160, 120))):
            ren.SetWorldPoint(*p, 1.0)
            ren.WorldToDisplay()
            x, y, _ = ren.GetDisplayPoint()
            assert q == pytest.approx([x, 120 - y], abs=1e-6)


def test_fit_camera_keeps_points_inside_with_margin():
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(500, 3)) * [2, 0.5, 1] + [3, 1, -2]
    for size in ((160, 120), (120, 200)):
        cam = fit_camera(pts, (1, 0, 1), size, margin=0.1)
        px = cam.project(pts, size)
        W, H = size
        assert px[:, 0].min() >= 0.1 * W - 1 and px[:, 0].max() <= 0.9 * W + 1
        assert px[:, 1].min() >= 0.1 * H - 1 and px[:, 1].max() <= 0.9 * H + 1
        # tight in at least one direction
        assert (px[:, 0].min() < 0.1 * W + 2) or (px[:, 1].min() < 0.1 * H + 2)


def test_stage_aligns_takeoff_and_looks_across_the_jump():
    a, t0, t1 = jumper()
    b = a.replace(root_pos=a.root_pos + [2.0, 0.0, -1.0])          # same jump elsewhere
    st = stage([a, b], [t0, t0], [t1, t1], size=(160, 120))
    body = st.bodies[0]
    from flipstudy.stimuli.physics import center_of_mass
    for c in st.clips:
        com = center_of_mass(c, body)[t0 - 1]               # the last frame on the ground
        assert com[0] == pytest.approx(0, abs=1e-9) and com[2] == pytest.approx(0, abs=1e-9)
    np.testing.assert_allclose(st.clips[0].root_pos, st.clips[1].root_pos, atol=1e-12)
    # travel is +Z: the camera looks along ±X and +Z goes to the right of the image
    right, up, back = st.camera.basis()
    assert abs(back[2]) < 1e-9 and right @ [0, 0, 1] > 0.99
    # every frame of every clip inside the image
    for c in st.clips:
        px = st.camera.project(body_points(c, body, (20, 12)).reshape(-1, 3), (160, 120))
        assert px.min() > 0 and px[:, 0].max() < 160 and px[:, 1].max() < 120


def test_stage_orients_other_base_clips_but_not_edits():
    a, t0, t1 = jumper(flip=0.0)                                   # travels +Z
    from flipstudy.stimuli.edit.reposition import rotate
    turn = Rotation.from_rotvec([0, np.radians(120), 0])
    other = rotate(jumper(flip=3.0)[0], turn, np.zeros(3))         # another clip, another way
    other_edit = edited(other, t0)                                 # and an edit of it
    st = stage([a, other, other_edit], [t0] * 3, [t1] * 3, size=(160, 120), turn=0)
    assert st.yaws[0] == 0.0
    assert st.yaws[1] == pytest.approx(-120.0, abs=1e-6) and st.yaws[2] == st.yaws[1]
    from flipstudy.stimuli.physics import center_of_mass
    for c in st.clips:
        com = center_of_mass(c, st.bodies[0])
        d = com[t1] - com[t0]
        assert d[2] > 0.5 and abs(d[0]) < 1e-6                    # all travel +Z now
    np.testing.assert_allclose(st.clips[1].root_pos[:t0], st.clips[2].root_pos[:t0], atol=0)
    assert stage([a, other], [t0] * 2, [t1] * 2, orient=False).yaws == [0.0, 0.0]


# ---------------------------------------------------------- pixels: camera
def test_character_pixels_are_where_the_camera_projects_the_com():
    clip, t0, t1 = jumper(flip=1.0)
    prep = stage([clip], [t0], [t1], size=(160, 120))
    from flipstudy.stimuli.physics import center_of_mass
    com = center_of_mass(prep.clips[0], prep.bodies[0])
    frames = []
    with Scene(prep.bodies[0], PLAIN, (160, 120), prep.camera) as sc:
        for k, img in enumerate(iter_frames(prep.clips[0], sc, 60.0)):
            if k in (0, t0, (t0 + t1) // 2, t1):
                frames.append((k, img.copy()))
    for k, img in frames:
        x, y = prep.camera.project(com[k][None], (160, 120))[0]
        xi, yi = int(round(x)), int(round(y))
        win = nonwhite(img)[yi - 3:yi + 4, xi - 3:xi + 4]
        assert win.mean() > 0.8, f"frame {k}: COM at ({x:.1f}, {y:.1f}) is not on the character"
        m = nonwhite(img)
        ys, xs = np.nonzero(m)
        # the silhouette is around the COM and the whole character is in the frame
        assert abs(xs.mean() - x) < 25 and abs(ys.mean() - y) < 30
        assert not m[0].any() and not m[-1].any() and not m[:, 0].any() and not m[:, -1].any()


# ------------------------------------------------------------- ghosts, trails
def test_ghosts_are_separate_silhouettes():
    clip = walker(seconds=1.0, speed=5.0)                     # 1 m between ghosts 0.2 s apart
    # square side view (turn=0): the arms point at the camera, the silhouette stays compact
    img = ghost_image(stage([clip], [0], [clip.num_frames - 1], size=(320, 120), style=PLAIN, turn=0),
                      None,
                      interval=0.2, span="clip", legend=False)     # the legend box would join them
    mask = ndimage.binary_dilation(nonwhite(img), iterations=2)   # close 1-pixel joints
    _, n = ndimage.label(mask, structure=np.ones((3, 3)))
    assert n == 6                                              # t = 0, 0.2, ..., 1.0
    # ghosts translucent, the last one opaque (darker)
    lab, _ = ndimage.label(mask, structure=np.ones((3, 3)))
    ids = [lab[:, x][lab[:, x] > 0][0] for x in range(320) if (lab[:, x] > 0).any()]
    first, last = ids[0], ids[-1]
    core = nonwhite(img, 30)
    lum = img[..., :3].astype(float).mean(-1)
    assert lum[(lab == last) & core].mean() < lum[(lab == first) & core].mean() - 30


def test_trail_colours_of_the_legend_are_in_the_image():
    clip, t0, t1 = jumper(flip=3.0)
    st = Style(anti_aliasing="none")
    img = trail_image(stage([clip], [t0], [t1], size=(320, 240), style=st), None)
    cols = [rgb8(c) for c in st.trail_palette[:len(TRAIL_JOINTS) - 1]] + [rgb8(st.trail_com_color)]
    H, W = img.shape[:2]
    rest = img.reshape(-1, 3).astype(int)
    for c in cols:
        d = np.abs(rest - np.array(c)).max(1)
        # the legend's disc has the exact colour...
        assert (d <= 2).sum() >= 10, f"legend colour {c} missing"
    # ...and the markers in the scene (right of the legend box) are close to it
    scene_px = img[:, W // 3:].reshape(-1, 3).astype(int)
    for c in cols:
        d = np.abs(scene_px - np.array(c)).max(1)
        assert (d <= 40).sum() >= 5, f"trail colour {c} not drawn in the scene"


# ----------------------------------------------------------------- video
def test_video_decodes_with_expected_frames_and_rate(tmp_path):
    import imageio_ffmpeg
    clip, t0, t1 = jumper(fps=120.0)
    path = render_video(stage([clip], [t0 * 2], [t1 * 2], size=(160, 120), style=PLAIN), tmp_path / "j.mp4",
                        fps=30.0, frames_dir=tmp_path / "frames")
    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    frames = [np.frombuffer(f, np.uint8).reshape(120, 160, 3) for f in gen]
    assert meta["codec"] == "h264" and meta["pix_fmt"].startswith("yuv420p")
    assert meta["fps"] == 30.0 and meta["size"] == (160, 120)
    assert len(frames) == 31                               # 1 s at 30 fps, both ends
    pngs = sorted((tmp_path / "frames").glob("*.png"))
    assert len(pngs) == 31
    # the decoded video shows what the PNG frames show (lossy, so roughly)
    png = read_image(pngs[15])
    assert np.abs(png.astype(int) - frames[15].astype(int)).mean() < 6


def test_video_rejects_odd_size(tmp_path):
    clip, t0, t1 = jumper()
    with pytest.raises(ValueError, match="even"):
        render_video(stage([clip], [t0], [t1], size=(161, 120)), tmp_path / "x.mp4")


# ------------------------------------------------- same take-off, same frames
def edited(clip, t0, shift=(0.0, 0.0, 0.03)):
    """The clip with its flight moved from the first airborne frame ``t0`` on
    (as a retimed flight does: it resamples the take-off frame too)."""
    root = clip.root_pos.copy()
    root[t0:] += shift
    return clip.replace(root_pos=root)


def test_stimuli_of_one_clip_are_pixel_identical_before_takeoff():
    a, t0, t1 = jumper(flip=0.0)
    b, _, _ = jumper(flip=2.5)                 # the same clip, another flight...
    b = edited(b, t0)                          # ...that starts moving at the take-off frame
    b = b.replace(root_pos=b.root_pos + [0.7, 0, 0.4])     # and somewhere else in the capture
    st = stage([a, b], [t0, t0], [t1, t1], size=(160, 120))
    out = []
    with Scene(st.bodies[0], Style(), (160, 120), st.camera, st.ground_bounds) as sc:
        for c in st.clips:
            out.append(np.stack([f.copy() for f in iter_frames(c, sc, 60.0)]))
    A, B = out
    for k in range(t0):
        assert np.array_equal(A[k], B[k]), f"frame {k} differs before take-off"
    assert any(not np.array_equal(A[k], B[k]) for k in range(t0, t1))


@pytest.mark.skipif(not (SHARED / "mocap" / "88_01.bvh").exists(),
                    reason=f"needs ../shared/mocap/88_01.bvh (not found under {SHARED})")
def test_real_edited_flip_pixel_identical_before_takeoff():
    from flipstudy.stimuli import analyse, load_bvh
    from flipstudy.stimuli.injection import inject_angular_momentum
    a = analyse(load_bvh(SHARED / "mocap" / "88_01.bvh", fps=60))
    e = inject_angular_momentum(a, 0.25, "smooth").clip           # a real stimulus edit
    st = stage([a.clip, e], [a.takeoff] * 2, [a.landing] * 2, size=(96, 72))
    out = []
    with Scene(st.bodies[0], Style(anti_aliasing="none"), (96, 72), st.camera, st.ground_bounds) as sc:
        for c in st.clips:
            out.append(np.stack([f.copy() for f in iter_frames(c.slice(0, a.landing), sc, 60.0)]))
    A, B = out
    assert all(np.array_equal(A[k], B[k]) for k in range(a.takeoff))
    assert not np.array_equal(A[a.landing - 5], B[a.landing - 5])


def _write_study(folder: Path, clips_and_names, t0, t1):
    """A stimulus set of these clips (``.bvh``, ``.npz``, ``manifest.csv`` through the contract)."""
    from flipstudy.stimuli.contract import Stimulus, StimulusSet
    from flipstudy.stimuli.stimset import clip_arrays, npz_bytes
    rows = []
    for name, clip, level in clips_and_names:
        save_bvh(clip, folder / f"{name}.bvh", scale=1.0)
        (folder / f"{name}.npz").write_bytes(npz_bytes(clip_arrays(clip, t0, t1)))
        rows.append(Stimulus(name, "jumper", "g", "reference" if level == 0 else "angular-momentum",
                             "smooth", level, nominal_error_pct=level, measured_error_pct=level,
                             takeoff_angle_deg=60.0, takeoff=t0, landing=t1, seed=1,
                             frames=clip.num_frames, fps=clip.fps))
    StimulusSet(folder, rows).write()


def test_render_study_one_camera_identical_frames_before_takeoff(tmp_path):
    a, t0, t1 = jumper(flip=0.0)
    b, _, _ = jumper(flip=2.0)
    b = edited(b, t0)
    b = b.replace(root_pos=b.root_pos + [0.5, 0, -0.3])
    _write_study(tmp_path, [("ref", a, 0), ("edit", b, 20)], t0, t1)
    rec = render_study(tmp_path, what=["video", "ghost", "overlay"], size=(160, 120), jobs=1,
                       frames=True, progress=False)
    out = tmp_path / "render"
    assert (out / "ref.mp4").exists() and (out / "edit_ghost.png").exists()
    assert (out / "edit_overlay.png").exists() and not (out / "ref_overlay.png").exists()
    saved = json.loads((out / "render.json").read_text())
    assert Camera.from_dict(saved["camera"]) == Camera.from_dict(rec.record.camera)
    assert saved["size"] == [160, 120] and saved["fps"] == 60.0
    assert {"pyvista", "vtk", "openimageio"} <= set(saved["versions"])
    assert Style.from_dict(saved["style"]) == Style()
    fa = sorted((out / "frames" / "ref").glob("*.png"))
    fb = sorted((out / "frames" / "edit").glob("*.png"))
    assert len(fa) == len(fb) == a.num_frames
    for k in range(t0):
        assert np.array_equal(read_image(fa[k]), read_image(fb[k])), f"frame {k}"
    assert not np.array_equal(read_image(fa[t1 - 3]), read_image(fb[t1 - 3]))


def test_render_study_in_parallel_workers(tmp_path):
    a, t0, t1 = jumper(flip=0.0)
    _write_study(tmp_path, [("s0", a, 0), ("s1", a, 10), ("s2", a, 20)], t0, t1)
    rec = render_study(tmp_path, what="ghost", size=(96, 64), jobs=2, progress=False)
    assert rec.jobs == 2
    imgs = [read_image(tmp_path / "render" / f"s{k}_ghost.png") for k in range(3)]
    assert imgs[0].shape == (64, 96, 3)
    # the same clip, the same camera, another process: the same picture
    assert np.array_equal(imgs[0], imgs[1]) and np.array_equal(imgs[0], imgs[2])


# ------------------------------------------------------------ strip, composite
def test_strip_has_one_labelled_panel_per_time():
    clip, t0, t1 = jumper(flip=3.0)
    img = strip_image(stage([clip], [t0], [t1], style=PLAIN), None, dt=0.25, span="clip",
                      panel_size=(80, 120))
    assert img.shape == (120, 5 * 80 + 4 * 4, 3)              # t = 0, .25, .5, .75, 1.0
    for k in range(5):
        panel = img[:, k * 84:k * 84 + 80]
        assert nonwhite(panel[:20]).any()                    # the label at the top
        assert nonwhite(panel[30:]).sum() > 100              # the character


def test_composite_layers_use_the_alpha_matte():
    clip = walker(seconds=0.4, speed=5.0)
    st = stage([clip], [0], [clip.num_frames - 1], size=(200, 100), style=PLAIN)
    one = composite_image(st, None, times=[0.4], span="clip")
    ghost = ghost_image(st, None, times=[0.4], span="clip")
    # a single opaque layer matted onto the plate is the plain render
    assert np.abs(one.astype(int) - ghost.astype(int)).max() <= 2
    two = composite_image(st, None, times=[0.0, 0.4], span="clip")
    mask = nonwhite(two)
    lab, n = ndimage.label(ndimage.binary_dilation(mask, iterations=2), structure=np.ones((3, 3)))
    assert n == 2
    # the second layer is at 75 %: lighter than the opaque first one
    lum = two[..., :3].astype(float).mean(-1)
    xs = [np.nonzero(lab == i)[1].mean() for i in (1, 2)]
    first, second = (1, 2) if xs[0] < xs[1] else (2, 1)
    core = nonwhite(two, 30)
    assert lum[(lab == second) & core].mean() > lum[(lab == first) & core].mean() + 10
    rgba = np.zeros((2, 2, 4), np.uint8)
    rgba[0, 0] = (100, 0, 0, 255)
    top = np.zeros((2, 2, 4), np.uint8)
    top[0, 0] = (0, 200, 0, 255)
    out = over([rgba, top], [1.0, 0.75])
    assert tuple(out[0, 0]) == pytest.approx((25, 150, 0, 255), abs=1)


def test_overlay_two_colours():
    a, t0, t1 = jumper(flip=0.0)
    b, _, _ = jumper(flip=2.5)
    st = Style(anti_aliasing="none", ground=False, background="#ffffff")
    img = overlay_image(stage([a, b], [t0, t0], [t1, t1], size=(200, 150), style=st), None, interval=0.25)
    px = img.reshape(-1, 3).astype(int)
    for c in st.overlay_colors:
        assert (np.abs(px - rgb8(c)).max(1) <= 2).sum() >= 10       # legend swatch
        assert (np.abs(px - rgb8(c)).max(1) <= 60).sum() >= 100     # the figures


def test_support_polygon_is_the_hull():
    pts = np.array([[0, 0.02, 0], [1, 0.01, 0], [1, 0, 1], [0, 0, 1], [0.5, 0, 0.5]])
    poly = support_polygon(pts)
    assert len(poly) == 4 and np.allclose(poly[:, 1], 0.005)
    assert len(support_polygon(pts[:2])) == 2


def test_debug_gizmos_drawn_on_top():
    clip, t0, t1 = jumper(flip=2.0)
    st = Style(anti_aliasing="none", ground=False, background="#ffffff")
    one = stage([clip], [t0], [t1], size=(160, 120), style=st)
    plain = ghost_image(one, None, times=[0.5])
    dbg = ghost_image(one, None, debug=("com", "L", "v"), times=[0.5])
    com_c = np.array(rgb8(st.com_color))
    assert (np.abs(dbg.reshape(-1, 3).astype(int) - com_c).max(1) < 50).sum() > 5
    assert (np.abs(plain.reshape(-1, 3).astype(int) - com_c).max(1) < 50).sum() == 0


# --------------------------------------------------------------- memory
def _rss_mb() -> float:
    try:
        import psutil
        return psutil.Process().memory_info().rss / 2 ** 20
    except ImportError:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


#: documented bound: resident memory may grow by less than this many MB over
#: 300 reused-plotter frames and 8 figures after a warm-up (measured ≈ 0–2 MB)
MEMORY_GROWTH_MB = 15.0


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc for VmRSS")
def test_memory_stays_flat_over_a_long_batch():
    clip = walker(seconds=5.0, speed=0.2)                           # 301 frames
    prep = stage([clip], [0], [clip.num_frames - 1], size=(160, 120))
    with Scene(prep.bodies[0], Style(), (160, 120), prep.camera, prep.ground_bounds) as sc:
        for _ in iter_frames(prep.clips[0].slice(0, 40), sc, 60.0):      # warm-up
            pass
        def again():                                   # the clip drawn under the same camera
            return stage([prep.clips[0]], [0], [300], camera=prep.camera, size=(160, 120))
        ghost_image(again(), None, scene=sc, times=[0, 1, 2])
        base = _rss_mb()
        n = 0
        for _ in iter_frames(prep.clips[0], sc, 60.0):
            n += 1
        for k in range(8):
            ghost_image(again(), None, scene=sc, times=[0, 1, 2 + k / 8])
        grown = _rss_mb() - base
    assert n == 301
    print(f"RSS growth {grown:.2f} MB over {n} frames and 8 figures")
    assert grown < MEMORY_GROWTH_MB, f"RSS grew {grown:.1f} MB over {n} frames"


# ---------------------------------------------------------- the staging object
def test_stage_once_for_every_picture_of_its_clips():
    """One Stage: a clip of it drawn alone keeps the camera and the ground of
    all; another image size refits the camera to the same points; a camera that
    follows the action keeps a given ground and refits a fitted one."""
    from flipstudy.errors import FlipstudyValueError
    a, t0, t1 = jumper(flip=0.0)
    b = a.replace(root_pos=a.root_pos + [1.5, 0.0, 0.5])
    st = stage([a, b], [t0, t0], [t1, t1], size=(160, 120), style=PLAIN)
    one = st.only(1)
    assert one.clips[0] is st.clips[1] and one.camera == st.camera and one.style is st.style
    assert one.ground_bounds == st.ground_bounds and one.size == st.size
    with pytest.raises(FlipstudyValueError, match="only"):
        ghost_image(st, None)
    with pytest.raises(FlipstudyValueError, match="two clips"):
        overlay_image(one, None)
    tall = st.resized((40, 160))                      # the travel no longer fits: farther away
    assert tall.camera.distance > st.camera.distance and tall.size == (40, 160)
    for c in tall.clips:                              # every frame still in the (new) picture
        px = tall.camera.project(body_points(c, tall.bodies[0], (20, 12)).reshape(-1, 3), (40, 160))
        assert px.min() > 0 and px[:, 0].max() < 40 and px[:, 1].max() < 160
    moved = st.camera.translated((0.5, 0.0, 0.0))
    assert st.with_camera(moved).ground_bounds != st.ground_bounds           # fitted: refitted
    assert one.with_camera(moved).ground_bounds == st.ground_bounds          # given: kept
    img = ghost_image(one, None, times=[0.5])
    assert img.shape == (120, 160, 3) and nonwhite(img).any()


def test_a_reused_scene_must_have_the_stage_style():
    from flipstudy.errors import FlipstudyValueError
    clip, t0, t1 = jumper()
    st = stage([clip], [t0], [t1], size=(96, 64), style=PLAIN)
    with Scene(st.bodies[0], Style(), (96, 64), st.camera) as sc:
        with pytest.raises(FlipstudyValueError, match="style"):
            ghost_image(st, None, scene=sc)
    with Scene(st.bodies[0], PLAIN, (96, 64), st.camera) as sc:
        reused = ghost_image(st, None, scene=sc, times=[0.5])
    assert np.array_equal(reused, ghost_image(st, None, times=[0.5]))


# ------------------------------------------------------------- anti-aliasing
def _posed_frame(style, size, k=40):
    clip, t0, t1 = jumper(flip=3.0)
    st = stage([clip], [t0], [t1], size=(160, 120))
    with Scene(st.bodies[0], style, size, st.camera) as sc:
        for i, img in enumerate(iter_frames(st.clips[0], sc, 60.0)):
            if i == k:                                      # in the air, turned
                return img.astype(float)


@pytest.mark.parametrize("aa", ["fxaa", "vtk-fxaa", "ssaa"])
def test_anti_aliasing_smooths_the_edges_offscreen(aa):
    """Each offered anti-aliasing works on this EGL/llvmpipe setup: the
    character's edges come closer to a 4x4-supersampled reference than without
    (and the default style anti-aliases)."""
    ref = _posed_frame(PLAIN, (640, 480)).reshape(120, 4, 160, 4, 3).mean((1, 3))
    none = _posed_frame(PLAIN, (160, 120))
    smooth = _posed_frame(PLAIN.replace(anti_aliasing=aa), (160, 120))
    edge = np.abs(none - ref).max(-1) > 8                   # where aliasing shows
    assert edge.sum() > 50
    err = lambda img: np.sqrt(((img - ref)[edge] ** 2).mean())  # noqa: E731
    assert err(smooth) < 0.7 * err(none), (err(smooth), err(none))
    assert Style().anti_aliasing == "fxaa"


def test_fxaa_keeps_translucent_ghosts():
    """FXAA goes with depth peeling (MSAA does not here: translucent surfaces
    vanish): the ghosts of the default style are drawn."""
    clip = walker(seconds=1.0, speed=5.0)
    st = stage([clip], [0], [clip.num_frames - 1], size=(320, 120), turn=0,        # compact: square
               style=PLAIN.replace(anti_aliasing="fxaa"))
    img = ghost_image(st, None, interval=0.2, span="clip", legend=False)   # the legend box would join them
    mask = ndimage.binary_dilation(nonwhite(img), iterations=2)
    assert ndimage.label(mask, structure=np.ones((3, 3)))[1] == 6


# ------------------------------------------------------------- style, CLI
def test_style_roundtrip_toml_and_errors(tmp_path):
    s = Style(ghost_opacity=0.2, overlay_colors=("yellow", "turquoise"))
    assert Style.from_dict(json.loads(json.dumps(s.to_dict()))) == s
    p = tmp_path / "style.toml"
    p.write_text('[style]\nbackground = "#000000"\nground_tile = 1.0\n')
    assert Style.from_toml(p).ground_tile == 1.0
    with pytest.raises(ValueError, match="unknown field"):
        Style.from_dict({"colour": "red"})
    with pytest.raises(ValueError, match="ghost_opacity"):
        Style(ghost_opacity=2.0)
    with pytest.raises(ValueError, match="'fxaa', 'ssaa', 'none'"):
        Style(anti_aliasing="msaa")


def test_cli_render_and_figure(tmp_path, capsys):
    import argparse

    from flipstudy.study.cli.render import add_commands
    ap = argparse.ArgumentParser(prog="flipstudy")
    sub = ap.add_subparsers(dest="command")
    add_commands(sub)
    a, t0, t1 = jumper(flip=2.0)
    _write_study(tmp_path, [("ref", a, 0)], t0, t1)
    args = ap.parse_args(["render", str(tmp_path), "--what", "ghost,strip", "--size", "96x64",
                          "--jobs", "1", "--quiet"])
    assert args.func(args) == 0
    assert (tmp_path / "render" / "ref_strip.png").exists()
    from flipstudy.study.cli import main            # main() reports the user errors
    assert main(["render", str(tmp_path), "--what", "nonsense"]) == 1
    assert "choose from" in capsys.readouterr().err
    out = tmp_path / "fig.png"
    args = ap.parse_args(["figure", str(tmp_path / "ref.bvh"), "--trail", "--out", str(out),
                          "--size", "160x120", "--scale", "1"])
    assert args.func(args) == 0
    assert read_image(out).shape == (120, 160, 3)
    assert parse_size("640x480") == (640, 480)
    with pytest.raises(ValueError):
        parse_size("640")
    assert set(RENDER_KINDS) >= {"video", "ghost", "trail", "strip", "composite"}


def test_cli_fps_is_the_clips_frame_rate_and_video_fps_the_videos(tmp_path, capsys):
    """``--fps`` means one thing in every command (a clip's frame rate);
    ``render``'s video rate is ``--video-fps``, its old ``--fps`` still works
    with a warning and says so in --help."""
    import argparse

    from flipstudy.study.cli.render import add_commands
    ap = argparse.ArgumentParser(prog="flipstudy")
    sub = ap.add_subparsers(dest="command")
    add_commands(sub)
    assert ap.parse_args(["render", "S"]).video_fps == 60.0
    assert ap.parse_args(["render", "S", "--video-fps", "24"]).video_fps == 24.0
    assert "deprecated" not in capsys.readouterr().err
    assert ap.parse_args(["render", "S", "--fps", "25"]).video_fps == 25.0
    err = capsys.readouterr().err
    assert "--fps is deprecated" in err and "--video-fps" in err
    sub.choices["render"].print_help()
    helptext = " ".join(capsys.readouterr().out.split())
    assert "--video-fps FPS frame rate of the videos" in helptext
    assert "--fps FPS deprecated spelling of --video-fps" in helptext
    args = ap.parse_args(["figure", "backflip", "--fps", "30", "--out", str(tmp_path / "f.png")])
    assert args.fps == 30.0 and not hasattr(args, "video_fps")
    from flipstudy.study.cli.common import load_clip
    assert load_clip(args.clip, args.scale, args.fps).fps == 30.0


# ----------------------------------------------------- real and built-in clips
@pytest.mark.skipif(not (SHARED / "mocap" / "88_01.bvh").exists(),
                    reason=f"needs ../shared/mocap/88_01.bvh (not found under {SHARED})")
def test_real_flip_in_frame_and_rendered():
    from flipstudy.stimuli import load_bvh
    clip = load_bvh(SHARED / "mocap" / "88_01.bvh", fps=60)
    st = stage([clip], size=(160, 120))
    # the frames strictly inside the flight (take-off instant at frame 45.0)
    assert (st.takeoffs[0], st.landings[0]) == (46, 79)
    px = st.camera.project(body_points(st.clips[0], st.bodies[0], (20, 12)).reshape(-1, 3), (160, 120))
    assert px.min() >= 0 and px[:, 0].max() <= 160 and px[:, 1].max() <= 120
    img = ghost_image(stage([st.clips[0]], [46], [79], camera=st.camera, size=(160, 120), style=PLAIN),
                      None)
    assert nonwhite(img).mean() > 0.05


@pytest.mark.skipif(not HAVE_SYNTH, reason="stimuli/synth (the built-in clips) not available yet")
def test_builtin_backflip_renders():
    from flipstudy.stimuli import builtin
    clip = builtin("backflip")
    img = ghost_image(stage([clip], size=(160, 120), style=PLAIN), None)
    assert nonwhite(img).mean() > 0.03
    m = nonwhite(img)
    assert not m[0].any() and not m[-1].any()


def test_labels_and_legend_without_a_font_file(monkeypatch):
    import flipstudy.render.figures as fg
    import flipstudy.render.strips as strips
    monkeypatch.setattr(strips, "find_font", lambda: None)   # VTK's built-in font instead
    clip, t0, t1 = jumper(flip=3.0)
    st = Style(anti_aliasing="none", ground=False, background="#ffffff")
    img = fg.trail_image(stage([clip], [t0], [t1], size=(320, 240), style=st), None,
                         joints=("pelvis", "com"))
    for c in (rgb8(st.trail_palette[0]), rgb8(st.trail_com_color)):
        assert (np.abs(img.reshape(-1, 3).astype(int) - c).max(1) <= 2).sum() >= 10
    dark = img[:40, 10:120].astype(int).max(-1) < 170               # label text, top left
    assert dark.sum() > 20
    strip = fg.strip_image(stage([clip], [t0], [t1], style=PLAIN), None, dt=0.5, span="clip",
                           panel_size=(80, 120))
    assert all(nonwhite(strip[:16, k * 84:k * 84 + 80]).sum() > 10 for k in range(3))


def test_transition_camera_views():
    from flipstudy.render.camera import transition_camera
    from flipstudy.stimuli import analyse, builtin
    from flipstudy.stimuli.physics import momentum
    clip = builtin("backflip")
    a = analyse(clip)
    main = (a.takeoff, a.landing)

    def back(view):
        cam = transition_camera(clip, clip, a.body, view, main=main, at=a.takeoff, frames=(0, clip.num_frames))
        v = np.subtract(cam.position, cam.focal_point)
        v[1] = 0.0
        return v / np.linalg.norm(v)

    # across L: the camera looks along the flight's angular momentum (the flip in profile)
    L = momentum(clip, a.body).L[main[0]:main[1] + 1].mean(axis=0)
    L[1] = 0.0
    assert abs(back("across-L") @ L) / np.linalg.norm(L) == pytest.approx(1.0, abs=1e-3)
    # three-quarter: the side view turned 45° about the vertical
    assert np.degrees(np.arccos(np.clip(back("side") @ back("three-quarter"), -1, 1))) == pytest.approx(45.0, abs=0.1)
    with pytest.raises(ValueError):
        transition_camera(clip, clip, a.body, "top", main=main, at=0, frames=(0, 10))

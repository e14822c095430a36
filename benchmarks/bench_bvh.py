"""BVH reading + forward kinematics against the peer parsers installed beside us.

Run: python benchmarks/bench_bvh.py [--repeat N] [--budget SECONDS] [--quick]

A full run takes a few minutes, nearly all of it one call of the bvh package's
channel API on the 1376-frame clip (about 2-3 minutes); ``--quick`` leaves that one
measurement out.

For each clip (../shared/mocap/88_01.bvh and 87_03.bvh, CMU, 31 joints; and the
1376-frame, 100-joint 01_01_iclone-retarget.bvh) it times, best of N:

* ours:  ``load_bvh(path, drop_tpose=False)`` + ``clip.joint_positions()``: parse the
  file and compute the world position of every joint in every frame;
* bvhio: ``readAsHierarchy(path)``, then per frame ``root.loadPose(frame)`` and the
  ``PositionWorld`` of every joint (the way its README reads world positions);
* bvh (20tab bvh-python): it has no forward kinematics.  ``Bvh(text)`` parses, the
  channels of every joint come from its API (``frames_joint_channels``), and the
  minimal FK is ours to add: one numpy/scipy pass per joint, vectorised over frames
  (so the peer's time is its parsing and channel access, not a slow FK of ours).
  A second row times only its parse plus its raw ``frames`` table (no channel API),
  the most generous reading of that package.

Every peer's positions are compared with ours (every frame) after unit scaling
(file units -> metres).  bvhio reads position channels as replacing the OFFSET,
while the files here (and we) add them to it; its root is shifted back by the file's
root OFFSET before comparing.  The script exits non-zero only when positions
disagree, never because of a timing.  Target: ours >= 20x faster than each peer.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SHARED = ROOT.parent / "shared" / "mocap"
CLIPS = ["88_01.bvh", "87_03.bvh", "01_01_iclone-retarget.bvh"]
TARGET = 20.0
TOL_M = 1e-3          # agreement tolerance in metres (bvhio computes in float32)


def timed(fn, repeat: int, budget: float):
    """Best wall time of up to ``repeat`` calls (fewer once ``budget`` seconds are
    spent), and the last result."""
    best, spent, runs, out = float("inf"), 0.0, 0, None
    while runs < repeat and (runs == 0 or spent < budget):
        t = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t
        best, spent, runs = min(best, dt), spent + dt, runs + 1
    return best, runs, out


# ------------------------------------------------------------------------ ours
def ours(path):
    from flipstudy.stimuli import load_bvh
    clip = load_bvh(path, drop_tpose=False)
    return clip.skeleton.joint_names, clip.joint_positions()


# ----------------------------------------------------------------------- bvhio
def peer_bvhio(path):
    import bvhio
    root = bvhio.readAsHierarchy(str(path))
    joints = [j for j, _, _ in root.layout()]
    frames = len(root.Keyframes)
    out = np.empty((frames, len(joints), 3))
    for f in range(frames):
        root.loadPose(f)
        for k, joint in enumerate(joints):
            p = joint.PositionWorld
            out[f, k] = (p.x, p.y, p.z)
    return [j.Name for j in joints], out


# ------------------------------------------------------------- bvh (20tab) + FK
def _fk(names, parents, offsets, channels, values):
    """Minimal forward kinematics, vectorised over frames: BVH intrinsic Euler angles
    in the CHANNELS order, position channels added to the OFFSET."""
    from scipy.spatial.transform import Rotation
    F, J = values[0].shape[0], len(names)
    R = np.empty((F, J, 3, 3))
    P = np.empty((F, J, 3))
    for j in range(J):
        ch, v = channels[j], values[j]
        rot = [k for k, c in enumerate(ch) if c.endswith("rotation")]
        local = np.broadcast_to(np.eye(3), (F, 3, 3))
        if rot:
            order = "".join(ch[k][0] for k in rot)
            local = Rotation.from_euler(order, v[:, rot], degrees=True).as_matrix()
        trans = np.broadcast_to(offsets[j], (F, 3)).copy()
        for k, c in enumerate(ch):
            if c.endswith("position"):
                trans[:, "XYZ".index(c[0])] += v[:, k]
        p = parents[j]
        if p < 0:
            R[:, j], P[:, j] = local, trans
        else:
            R[:, j] = R[:, p] @ local
            P[:, j] = P[:, p] + np.einsum("fab,fb->fa", R[:, p], trans)
    return P


def _bvh_skeleton(mocap):
    names = mocap.get_joints_names()
    parents = [mocap.joint_parent_index(n) for n in names]
    offsets = np.array([mocap.joint_offset(n) for n in names])
    channels = [mocap.joint_channels(n) for n in names]
    return names, parents, offsets, channels


def peer_bvh_api(path):
    from bvh import Bvh
    with open(path) as fh:
        mocap = Bvh(fh.read())
    names, parents, offsets, channels = _bvh_skeleton(mocap)
    values = [np.array(mocap.frames_joint_channels(n, ch), dtype=np.float64).reshape(-1, len(ch))
              for n, ch in zip(names, channels)]
    return names, _fk(names, parents, offsets, channels, values)


def peer_bvh_frames(path):
    from bvh import Bvh
    with open(path) as fh:
        mocap = Bvh(fh.read())
    names, parents, offsets, channels = _bvh_skeleton(mocap)
    table = np.array(mocap.frames, dtype=np.float64)
    values, c0 = [], 0
    for ch in channels:
        values.append(table[:, c0:c0 + len(ch)])
        c0 += len(ch)
    return names, _fk(names, parents, offsets, channels, values)


# (module, label, function, how, counts for the target)
PEERS = [
    ("bvhio", "bvhio", peer_bvhio, "its API: readAsHierarchy + loadPose(f) + PositionWorld of "
     "every joint", True),
    ("bvh", "bvh (API)", peer_bvh_api, "its API (no FK of its own): Bvh(text) + "
     "frames_joint_channels per joint + a minimal numpy FK added here", True),
    ("bvh", "bvh (frames)", peer_bvh_frames, "for information: its parser only, Bvh(text).frames "
     "as a table + the same numpy FK (not its channel API; no target)", False),
]


def compare(name, ref_names, ref_P, names, P, scale, shift):
    """Max |ours - peer| in metres over every frame, joints matched by name."""
    missing = [n for n in ref_names if n not in names]
    if missing:
        return float("inf"), f"joints missing in the peer: {missing[:3]}"
    idx = [names.index(n) for n in ref_names]
    if P.shape[0] != ref_P.shape[0]:
        return float("inf"), f"{P.shape[0]} frames, ours {ref_P.shape[0]}"
    d = np.abs((P[:, idx] + shift) * scale - ref_P).max(axis=-1)      # (F, J)
    f, j = np.unravel_index(np.argmax(d), d.shape)
    return float(d[f, j]), f"worst at frame {f}, joint {ref_names[j]!r}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="best of N runs (default 5)")
    ap.add_argument("--budget", type=float, default=20.0,
                    help="stop repeating a peer once it has used this many seconds (default 20)")
    ap.add_argument("--quick", action="store_true",
                    help="skip the bvh package's channel API on clips over 500 frames (minutes)")
    args = ap.parse_args()

    from flipstudy.stimuli import load_bvh
    paths = [SHARED / c for c in CLIPS]
    absent = [p for p in paths if not p.exists()]
    if absent:
        print(f"skipped: shared data absent ({', '.join(str(p) for p in absent)} not found)")
        return 0
    available = []
    for module, label, fn, how, counts in PEERS:
        try:
            __import__(module)
        except ImportError:
            print(f"skipped peer {label}: package {module!r} is not installed "
                  f"(pip install -e '.[bench]')")
            continue
        available.append((module, label, fn, how, counts))

    rows, bad = [], []
    for path in paths:
        meta = load_bvh(path, drop_tpose=False).meta
        scale = meta["scale"]
        t_ours, n_ours, (ref_names, ref_P) = timed(lambda: ours(path), args.repeat, args.budget)
        shape = f"{ref_P.shape[0]}x{ref_P.shape[1]}"
        rows.append((path.name, shape, "ours", t_ours, n_ours, None, None, False))
        for module, label, fn, how, counts in available:
            if args.quick and fn is peer_bvh_api and ref_P.shape[0] > 500:
                print(f"--quick: {label} on {path.name} not timed")
                continue
            t, n, (names, P) = timed(lambda: fn(path), args.repeat, args.budget)
            shift = 0.0
            if module == "bvhio" and meta["root_convention"] == "OFFSET + channels":
                shift = np.array(meta["file_root_offset"])   # bvhio: channels replace OFFSET
            err, where = compare(label, ref_names, ref_P, names, P, scale, shift)
            rows.append((path.name, shape, label, t, n, t / t_ours, err, counts))
            if not err <= TOL_M:
                bad.append(f"{label} on {path.name}: positions differ by {err:.3g} m ({where})")

    print(f"{'clip':27s} {'frames x joints':>15s} {'parser':13s} {'time (ms)':>10s} "
          f"{'runs':>4s} {'peer/ours':>9s} {'target':>6s} {'max |dP| (mm)':>13s}")
    for clip, shape, label, t, n, ratio, err, counts in rows:
        r = f"{ratio:8.1f}x" if ratio is not None else f"{'':9s}"
        ok = ("" if ratio is None else "info" if not counts else
              "met" if ratio >= TARGET else "MISSED")
        e = "" if err is None else f"{err * 1e3:.4f}"
        print(f"{clip:27s} {shape:>15s} {label:13s} {t * 1e3:10.1f} {n:4d} {r} {ok:>6s} {e:>13s}")
    print()
    for module, label, fn, how, counts in available:
        print(f"  {label:13s} {how}")
    print("  ours          load_bvh(path, drop_tpose=False) + clip.joint_positions()")
    print(f"target: ours >= {TARGET:.0f}x faster than each peer (parse + world positions of all "
          f"joints, all frames); timings never fail the script")
    print(f"agreement: peers' world positions within {TOL_M * 1e3:g} mm of ours in every frame, "
          f"after unit scaling (file units -> m)")
    if bad:
        print("DISAGREEMENT:")
        for b in bad:
            print("  " + b)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

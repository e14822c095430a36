"""Whole `inspect` of a 1000-frame clip: parse, FK, body, momentum, flight phases,
mass fit — against the paper's pre-processing figure (about 3 s, Majkowska &
Faloutsos 2007, Section 6).

Run: python benchmarks/bench_inspect.py
The 1000-frame CMU clip is made in a temporary folder by repeating the motion
lines of ../shared/mocap/88_01.bvh (a real skeleton, real numbers); nothing is
written into the repository.  Target: under 0.3 s.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from _common import best_s  # noqa: E402
SHARED = ROOT.parent / "shared" / "mocap"
PAPER_S = 3.0


def main() -> int:
    from flipstudy.stimuli import analyse, load_bvh
    src = SHARED / "88_01.bvh"
    if not src.exists():
        print(f"skipped: {src} not found (../shared/ test data absent)")
        return 0
    text = src.read_text()
    head, _, rest = text.partition("MOTION")
    lines = rest.strip().splitlines()
    frames = lines[3:]                       # drop 'Frames:', 'Frame Time:', the T-pose
    body = (frames * (1000 // len(frames) + 1))[:1000]
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "cmu_1000.bvh"
        p.write_text(f"{head}MOTION\nFrames: {len(body)}\nFrame Time: 0.0166667\n" + "\n".join(body) + "\n")
        rows = []
        for label, path in (("CMU 31 joints, 1000 frames", p),
                            ("iClone 100 joints, 1376 frames", SHARED / "01_01_iclone-retarget.bvh")):
            if not path.exists():
                continue
            t = best_s(lambda: analyse(load_bvh(path)).to_dict(), 5)
            a = analyse(load_bvh(path))
            rows.append((label, t, len(a.flights)))
    print(f"{'clip':34s} {'inspect (s)':>12s} {'paper (s)':>10s} {'speed-up':>9s} {'flights':>8s}")
    for label, t, nf in rows:
        print(f"{label:34s} {t:12.3f} {PAPER_S:10.1f} {PAPER_S / t:8.1f}x {nf:8d}")
    print("target: under 0.3 s for the 1000-frame clip (10x the paper's 3 s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The H.264 preset of the stimulus videos, chosen by measurement.

Renders real stimuli once (the built-in backflip and, when ``../shared`` is
there, the CMU flip 88_01, each at ``--size`` and 60 fps in the default style),
keeps their frames, then encodes them with ``render.video.h264_writer`` (libx264,
CRF 18, yuv420p, the settings of every video) under each x264 preset and
prints per preset: the file size, the encoder's CPU milliseconds per frame
(the ffmpeg child's user + system time), PSNR of the decoded RGB frames
against the rendered ones (numpy) and SSIM (ffmpeg's ``ssim`` filter, on the
luma and chroma planes it compares).

Usage: ``python benchmarks/bench_encoder.py [--size 640x480] [--presets ...] [--repeat 2]``.
"""
from __future__ import annotations

import argparse
import re
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flipstudy.render._pv import pv  # noqa: E402,F401  (EGL offscreen before anything else)
from flipstudy.render.scene import scene_for  # noqa: E402
from flipstudy.render.staging import stage  # noqa: E402
from flipstudy.render.video import ENCODER, h264_writer, iter_frames  # noqa: E402
from flipstudy.stimuli import builtin  # noqa: E402

PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow")


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def stimuli_frames(size) -> dict:
    """The frames (list of (H, W, 3) uint8) of each real stimulus."""
    clips = {"built-in backflip": builtin("backflip")}
    p = ROOT.parent / "shared" / "mocap" / "88_01.bvh"
    if p.is_file():
        from flipstudy.stimuli import load_bvh
        clips["CMU 88_01"] = load_bvh(p, fps=60)
    out = {}
    for name, clip in clips.items():
        st = stage([clip], size=size)
        with scene_for(st) as sc:
            out[name] = [f.copy() for f in iter_frames(st.clips[0], sc, 60.0, body=st.bodies[0])]
    return out


def encode(frames, path: Path, preset: str) -> float:
    """Encode ``frames`` to ``path``; the encoder's CPU seconds."""
    H, W = frames[0].shape[:2]
    c = _children_cpu()
    w = h264_writer(path, (W, H), 60.0, preset=preset)
    for f in frames:
        w.send(f)
    w.close()
    return _children_cpu() - c


def quality(frames, path: Path) -> tuple[float, float]:
    """PSNR (dB, RGB, all frames) of the decoded video and ffmpeg's SSIM (All)."""
    import imageio_ffmpeg
    H, W = frames[0].shape[:2]
    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    next(reader)                                          # the metadata
    se, n = 0.0, 0
    for f, raw in zip(frames, reader):
        d = np.frombuffer(raw, np.uint8).reshape(H, W, 3).astype(np.float64) - f
        se += float((d * d).sum())
        n += d.size
    psnr = 10 * np.log10(255.0 ** 2 / (se / n))
    raw = path.with_suffix(".rgb")
    raw.write_bytes(b"".join(f.tobytes() for f in frames))
    ff = imageio_ffmpeg.get_ffmpeg_exe()
    r = subprocess.run([ff, "-hide_banner", "-i", str(path), "-f", "rawvideo", "-pix_fmt", "rgb24",
                        "-s", f"{W}x{H}", "-r", "60", "-i", str(raw), "-lavfi", "[0:v][1:v]ssim",
                        "-f", "null", "-"], capture_output=True, text=True)
    m = re.search(r"All:([0-9.]+)", r.stderr)
    return psnr, float(m.group(1)) if m else float("nan")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--presets", nargs="*", default=list(PRESETS))
    ap.add_argument("--repeat", type=int, default=2, help="encodes per preset (least CPU kept)")
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    import os
    print(f"x264 presets at CRF {ENCODER['crf']}, {size[0]}x{size[1]}, 60 fps; the videos' preset "
          f"is {ENCODER['preset']!r}; load average {os.getloadavg()[0]:.1f}")
    rows = {}
    for name, frames in stimuli_frames(size).items():
        print(f"{name}: {len(frames)} frames")
        print(f"{'preset':>10} {'KiB':>7} {'ms/frame':>9} {'PSNR dB':>8} {'SSIM':>7}")
        with tempfile.TemporaryDirectory() as d:
            for preset in args.presets:
                p = Path(d) / f"{preset}.mp4"
                cpu = min(encode(frames, p, preset) for _ in range(args.repeat))
                psnr, ssim = quality(frames, p)
                kib = p.stat().st_size / 1024
                rows[(name, preset)] = (kib, cpu / len(frames) * 1e3, psnr, ssim)
                print(f"{preset:>10} {kib:7.0f} {cpu / len(frames) * 1e3:9.2f} {psnr:8.2f} {ssim:7.4f}",
                      flush=True)
    return rows


if __name__ == "__main__":
    main()

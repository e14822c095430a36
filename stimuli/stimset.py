"""Building a stimulus set from a design: clips, errors, measurement, manifest.

``build_stimuli(design, out)`` writes every stimulus as ``.bvh`` (metres) and
``.npz``, a copy of the design, and ``manifest.csv`` (one row per stimulus: the
nominal error beside the error the analyser measures).  The set is built in a
temporary folder next to ``out`` and renamed into place at the end, so an
interrupted run leaves no half-written study.  The same design and seed give a
byte-identical manifest (content hashes included).
"""

from __future__ import annotations

from .exceptions import FlipstudyFileExistsError, FlipstudyFileNotFoundError

import csv
import hashlib
import io
import os
import shutil
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from .analyse import analyse
from .design import Design, DesignError
from .errors import Injected, StimulusError, check, inject_angular_momentum, inject_takeoff_angle, measure
from .motion.bvh import bvh_text, load_bvh
from .motion.clip import Clip

MANIFEST_COLUMNS = [
    "stimulus", "clip", "group", "kind", "profile", "level", "nominal_error_pct",
    "measured_error_pct", "takeoff_angle_deg", "takeoff_angle_change_deg", "takeoff", "landing",
    "seed", "sha256",
    "L_ratio_window", "L_change_pct", "flight_s", "jump_height_m", "jump_length_m",
    "dp_takeoff", "dp_landing", "frames", "fps", "bvh", "npz",
]


def load_base_clip(spec, design: Design) -> Clip:
    """A design's base clip: a built-in name or a BVH path (relative to the design)."""
    from . import BUILTIN_NAMES, builtin
    if spec.source in BUILTIN_NAMES:
        clip = builtin(spec.source, fps=spec.fps or design.fps, total_mass=design.total_mass)
    else:
        p = Path(spec.source)
        if not p.is_absolute() and design.path is not None:
            p = design.path.parent / p
        if not p.exists():
            raise DesignError(f"clips '{spec.name}': source {spec.source!r} is neither a built-in clip "
                              f"({', '.join(BUILTIN_NAMES)}) nor an existing BVH file ({p})")
        clip = load_bvh(p, scale=spec.scale, fps=spec.fps)
    if getattr(spec, "flips", None):
        from .edit.multiflip import FlipEditError, multiflip
        try:
            clip = multiflip(analyse(clip, total_mass=design.total_mass), spec.flips,
                             k_ratio=spec.k_ratio).clip
        except FlipEditError as e:
            raise DesignError(f"clips '{spec.name}': flips = {spec.flips}: {e}") from None
        clip.meta["name"] = spec.name
    return clip


def derived_seed(seed: int, name: str) -> int:
    """A per-stimulus seed derived from the design seed and the stimulus name."""
    return int.from_bytes(hashlib.sha256(f"{seed}:{name}".encode()).digest()[:4], "big")


def npz_bytes(arrays: dict) -> bytes:
    """An ``.npz`` (readable by ``numpy.load``) with fixed zip timestamps, so the
    same arrays always give the same bytes."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for k in sorted(arrays):
            info = zipfile.ZipInfo(f"{k}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            b = io.BytesIO()
            np.lib.format.write_array(b, np.asanyarray(arrays[k]), allow_pickle=False)
            z.writestr(info, b.getvalue())
    return buf.getvalue()


def clip_arrays(clip: Clip, takeoff: int, landing: int) -> dict:
    sk = clip.skeleton
    return {"root_pos": clip.root_pos, "rotations": clip.rotations, "fps": np.float64(clip.fps),
            "takeoff": np.int64(takeoff), "landing": np.int64(landing),
            "joint_names": np.array(sk.joint_names), "parents": sk.parents, "offsets": sk.offsets}


class _Progress:
    def __init__(self, total: int, label: str, enabled: bool):
        self.total, self.label, self.enabled, self.n = total, label, enabled, 0
        self.t0 = time.perf_counter()

    def step(self, what: str = ""):
        self.n += 1
        if not self.enabled:
            return
        done = self.n == self.total
        if sys.stderr.isatty():
            w = 30
            k = int(w * self.n / max(self.total, 1))
            sys.stderr.write(f"\r{self.label} [{'#' * k}{'.' * (w - k)}] {self.n}/{self.total} {what[:40]:40s}")
            if done:
                sys.stderr.write(f" {time.perf_counter() - self.t0:.1f} s\n")
        elif done:
            sys.stderr.write(f"{self.label}: {self.n}/{self.total} in {time.perf_counter() - self.t0:.1f} s\n")
        sys.stderr.flush()


def plan(design: Design) -> list[tuple]:
    """(stimulus name, clip spec, group or None, level) for every stimulus, in
    manifest order: reference clips first, then clip × group × level."""
    rows = [(f"{r}_reference", design.clip(r), None, 0.0) for r in design.reference]
    for c in design.clips:
        for g in design.groups:
            for lv in g.levels:
                rows.append((f"{c.name}_{g.name}_{lv:g}", c, g, lv))
    return rows


def build_stimuli(design: Design, out, force: bool = False, progress: bool = True) -> list[dict]:
    """Generate, measure and write the stimulus set of ``design`` into ``out``."""
    out = Path(out)
    if out.exists() and not force:
        raise FlipstudyFileExistsError(f"{out} exists; choose another --out or pass --force to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    todo = plan(design)
    bar = _Progress(len(todo), "stimuli", progress)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        base = {}
        for c in design.clips:
            clip = load_base_clip(c, design)
            a = analyse(clip, total_mass=design.total_mass)
            if a.flight is None:
                raise StimulusError(f"clips '{c.name}' ({c.source}): the analyser finds no flight "
                                    f"phase, so it cannot carry the study's errors")
            base[c.name] = a
        rows = []
        for name, spec, group, level in todo:
            a = base[spec.name]
            if group is None or level == 0:
                inj = Injected(a.clip, group.kind if group else "reference",
                               group.profile if group else None, 0.0, a.takeoff, a.landing,
                               np.arange(a.clip.num_frames, dtype=float), a.flight_s)
            elif group.kind == "angular-momentum":
                inj = inject_angular_momentum(a, group.sign * level / 100.0, group.profile,
                                              design.com_policy)
            else:
                inj = inject_takeoff_angle(a, group.sign * level / 100.0)
            if inj.kind == "reference":
                m = measure(a, Injected(a.clip, "takeoff-angle", None, 0.0, a.takeoff, a.landing,
                                        None, a.flight_s))
                m["measured_error_pct"] = 0.0
            else:
                m = measure(a, inj)
                check(m, inj, design.tolerance_pct, name)
            text = bvh_text(inj.clip, 1.0)
            data = text.encode()
            npz = npz_bytes(clip_arrays(inj.clip, inj.takeoff, inj.landing))
            (tmp / f"{name}.bvh").write_bytes(data)
            (tmp / f"{name}.npz").write_bytes(npz)
            rows.append({
                "stimulus": name, "clip": spec.name,
                "group": group.name if group else "reference",
                "kind": group.kind if group else "reference",
                "profile": (group.profile or "") if group else "",
                "level": level,
                "nominal_error_pct": (group.sign * level if level else 0.0) if group else 0.0,
                "measured_error_pct": m["measured_error_pct"],
                "takeoff_angle_deg": m["takeoff_angle_deg"],
                "takeoff_angle_change_deg": m["takeoff_angle_change_deg"],
                "takeoff": inj.takeoff, "landing": inj.landing,
                "seed": derived_seed(design.seed, name),
                "sha256": hashlib.sha256(data).hexdigest(),
                "L_ratio_window": m["L_ratio_window"], "L_change_pct": m["L_change_pct"],
                "flight_s": m["flight_s"], "jump_height_m": m["jump_height_m"],
                "jump_length_m": m["jump_length_m"], "dp_takeoff": m["dp_takeoff"],
                "dp_landing": m["dp_landing"], "frames": inj.clip.num_frames, "fps": inj.clip.fps,
                "bvh": f"{name}.bvh", "npz": f"{name}.npz",
            })
            bar.step(name)
        write_manifest(tmp / "manifest.csv", rows)
        if design.path is not None:
            shutil.copyfile(design.path, tmp / "design.toml")
        _replace_dir(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return rows


def _fmt(v) -> str:
    if isinstance(v, (float, np.floating)):
        if not np.isfinite(v):
            return "nan"
        s = f"{float(v):.6f}"
        return "0.000000" if s == "-0.000000" else s
    return str(v)


def write_manifest(path: Path, rows: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(MANIFEST_COLUMNS)
    for r in rows:
        w.writerow([_fmt(r[c]) for c in MANIFEST_COLUMNS])
    path.write_text(buf.getvalue())


def _replace_dir(tmp: Path, out: Path) -> None:
    """Rename ``tmp`` to ``out``; an existing ``out`` is moved aside first and
    removed only once the new one is in place."""
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        os.replace(out, old)
    os.replace(tmp, out)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def read_manifest(study_dir) -> list[dict]:
    """The rows of a study's ``manifest.csv`` (strings)."""
    p = Path(study_dir) / "manifest.csv"
    if not p.exists():
        raise FlipstudyFileNotFoundError(f"{p}: no manifest; make the stimuli first (flipstudy stimuli DESIGN.toml --out DIR)")
    with p.open(newline="") as f:
        return list(csv.DictReader(f))

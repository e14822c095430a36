"""The BVH reader under hostile input: mutations of real files (and of a generated
one) give either a valid clip or a :class:`BVHError` naming the file, never another
exception; non-regular files, oversized files and absurd numbers are refused by
name; a 30,000-joint file loads (benchmarks/bench_bvh_joints.py times it).
"""
from __future__ import annotations

import os
import re
import stat
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from flipstudy.errors import FlipstudyError, BVHError
from flipstudy.stimuli.motion import load_bvh
from flipstudy.stimuli.motion import bvh as bvh_mod

from _bvh_gen import many_joints_bvh
from _shared import MOCAP, PEER

# real files of each kind: raw CMU (T-pose, ZYX), MASS export (absolute root), iClone
# (OFFSET + deltas, 100 joints), a mixed-order CMU, two peer parsers' test files
SEED_FILES = ["88_01.bvh", "88_01_mass-retarget.bvh", "02_04_iclone-retarget.bvh",
              "90_11.bvh", "mass_kick.bvh", "test_freebvh.bvh", "test_mocapbank.bvh"]
FRAMES_KEPT = 20


def _truncate(text: str, n: int = FRAMES_KEPT) -> str:
    """The file with its MOTION block cut to its first ``n`` frames (fast examples)."""
    lines = text.replace("\r\n", "\n").split("\n")
    m = next(i for i, ln in enumerate(lines) if ln.strip() == "MOTION")
    data = [ln for ln in lines[m + 3:] if ln.strip()][:n]
    return "\n".join(lines[:m + 1] + [f"Frames: {len(data)}", lines[m + 2].strip()] + data) + "\n"


def _seeds() -> list[tuple[str, str]]:
    out = [("generated", many_joints_bvh(12, n_frames=FRAMES_KEPT, fan=3))]
    for name in SEED_FILES:
        for folder in (MOCAP, PEER):
            p = folder / name
            if p.is_file():
                out.append((name, _truncate(p.read_text(encoding="utf-8", errors="replace"))))
                break
    return out


SEEDS = _seeds()
NASTY = ["1e308", "-1e308", "1e309", "nan", "NaN", "inf", "-inf", "-0", "0", "1e-320",
         "9" * 400, "-" + "9" * 30, "0x10", "1_000", "", "1e6", "-1e6", "1000001", "1e-5",
         "123456789012", "Frame", "{", "}", "MOTION", "JOINT", "\x00", "\u00e9", "1,5"]
NUM = re.compile(r"-?\d+(\.\d*)?([eE][-+]?\d+)?")


@st.composite
def mutated(draw):
    """(seed name, bytes): a seed file with one to three mutations."""
    name, text = draw(st.sampled_from(SEEDS))
    lines = text.split("\n")
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["number", "number", "number", "del_line", "dup_line",
                                     "swap_lines", "swap_tokens", "del_bytes", "ins_bytes",
                                     "header"]))
        n = len(lines)
        i = draw(st.integers(0, max(n - 1, 0)))
        if kind == "number":
            spans = [m.span() for m in NUM.finditer(lines[i])] if n else []
            if spans:
                a, b = draw(st.sampled_from(spans))
                lines[i] = lines[i][:a] + draw(st.sampled_from(NASTY)) + lines[i][b:]
        elif kind == "del_line" and n:
            del lines[i]
        elif kind == "dup_line" and n:
            lines.insert(i, lines[i])
        elif kind == "swap_lines" and n:
            j = draw(st.integers(0, n - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif kind == "swap_tokens" and n:
            tok = lines[i].split()
            if len(tok) >= 2:
                a, b = draw(st.integers(0, len(tok) - 1)), draw(st.integers(0, len(tok) - 1))
                tok[a], tok[b] = tok[b], tok[a]
                lines[i] = " ".join(tok)
        elif kind in ("del_bytes", "ins_bytes"):
            s = "\n".join(lines)
            a = draw(st.integers(0, len(s)))
            if kind == "del_bytes":
                s = s[:a] + s[a + draw(st.integers(1, 64)):]
            else:
                s = s[:a] + draw(st.text(st.characters(codec="latin-1"), max_size=8)) + s[a:]
            lines = s.split("\n")
        elif kind == "header":
            # the MOTION header lines, rewritten with odd spacing or absurd values
            for k, ln in enumerate(lines):
                if ln.strip().startswith("Frame Time"):
                    lines[k] = draw(st.sampled_from([
                        "Frame  Time:\t0.0083333", "Frame\tTime : 0.01", "frame time: 0.033333",
                        "Frame Time: 1e-320", "Frame Time: 0", "Frame Time: -0.01",
                        "Frame Time: 1e300", "Frame Time: 2", "Frame Time: 0.00001",
                        "Frame Time:", "Frame Time: nan"]))
                    break
    data = "\n".join(lines).encode("latin-1", errors="replace")
    return name, data


def _check_valid_clip(clip, path):
    assert clip.num_frames >= 1
    lo, hi = bvh_mod.FPS_RANGE
    assert lo <= clip.fps <= hi
    for a in (clip.root_pos, clip.rotations, clip.joint_pos, clip.skeleton.offsets):
        if a is not None:
            assert np.all(np.isfinite(a)), path
    assert np.allclose(np.linalg.norm(clip.rotations, axis=-1), 1.0)
    assert np.abs(clip.root_pos).max() <= 2 * bvh_mod.MAX_POSITION_M
    assert np.all(np.isfinite(clip.joint_positions()))


@pytest.fixture(scope="module")
def scratch():
    with tempfile.TemporaryDirectory(prefix="bvhfuzz") as d:
        yield Path(d)


@settings(max_examples=1000, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@given(case=mutated())
def test_mutated_files_give_a_clip_or_a_bvherror(case, scratch):
    name, data = case
    path = scratch / "mutant.bvh"
    path.write_bytes(data)
    try:
        clip = load_bvh(path)
    except BVHError as e:
        msg = str(e)
        assert msg.startswith(str(path)), msg
        assert e.line is None or 1 <= e.line <= data.count(b"\n") + 2, msg
        return
    _check_valid_clip(clip, name)


def test_seeds_are_valid_clips(scratch):
    """The unmutated seeds load (so the fuzz mutates working files, not broken ones)."""
    assert len(SEEDS) >= 1
    for name, text in SEEDS:
        p = scratch / f"seed_{name}"
        p.write_text(text)
        _check_valid_clip(load_bvh(p), name)


# ------------------------------------------------------------ refusals by name
def test_non_regular_files_are_refused_before_reading(tmp_path):
    fifo = tmp_path / "pipe.bvh"
    os.mkfifo(fifo)
    with pytest.raises(BVHError, match="FIFO"):      # opening it would block forever
        load_bvh(fifo)
    with pytest.raises(BVHError, match="directory"):
        load_bvh(tmp_path)
    if os.path.exists("/dev/zero") and stat.S_ISCHR(os.stat("/dev/zero").st_mode):
        with pytest.raises(BVHError, match="device"):  # would read until memory runs out
            load_bvh("/dev/zero")
    with pytest.raises(BVHError, match="cannot read"):
        load_bvh(tmp_path / "absent.bvh")


def test_size_cap_names_itself(tmp_path, monkeypatch):
    p = tmp_path / "big.bvh"
    p.write_text(many_joints_bvh(5, n_frames=50))
    load_bvh(p)
    monkeypatch.setattr(bvh_mod, "MAX_BVH_BYTES", p.stat().st_size - 1)
    with pytest.raises(BVHError, match="MAX_BVH_BYTES"):
        load_bvh(p)


def _motion_line(text: str, k: int = 0) -> int:
    """0-based index of frame line ``k``."""
    lines = text.split("\n")
    return lines.index("MOTION") + 3 + k


@pytest.mark.parametrize("header,ok", [
    ("Frame Time: 0.0083333", True), ("Frame  Time: 0.0083333", True),
    ("Frame\tTime:\t0.0083333", True), ("Frame Time : 0.0083333", True),
    ("Frame Time: 1e-320", False), ("Frame Time: 1e-300", False), ("Frame Time: 2", False),
    ("Frame Time: 0.00009", False), ("Frame Time: 1e308", False), ("Frame Time: inf", False),
])
def test_frame_time_header(tmp_path, header, ok):
    text = many_joints_bvh(4, n_frames=5).replace("Frame Time: 0.0083333", header)
    p = tmp_path / "c.bvh"
    p.write_text(text)
    line = text.split("\n").index(header) + 1
    if ok:
        assert load_bvh(p).fps == 120.0
    else:
        with pytest.raises(BVHError, match=f"line {line}:.*1 to 10000 frames per second"):
            load_bvh(p)


@pytest.mark.parametrize("where,value,phrase", [
    ("offset", "1e308", "OFFSET"), ("offset", "1e306", "OFFSET"), ("offset", "2e5", "OFFSET"),
    ("root", "1e306", "position"), ("root", "1.1e5", "position"),
    ("angle", "1e308", "angle"), ("angle", "-1.5e6", "angle"), ("angle", "1e309", "non-finite"),
])
def test_absurd_numbers_are_refused_with_their_line(tmp_path, where, value, phrase):
    text = many_joints_bvh(4, n_frames=5)
    lines = text.split("\n")
    if where == "offset":
        k = next(i for i, ln in enumerate(lines) if ln.strip().startswith("OFFSET") and i > 5)
        lines[k] = f"\tOFFSET {value} 0.5 0"
    else:
        k = _motion_line(text, 2)
        tok = lines[k].split()
        tok[0 if where == "root" else 4] = value
        lines[k] = " ".join(tok)
    p = tmp_path / "c.bvh"
    p.write_text("\n".join(lines))
    with pytest.raises(BVHError, match=f"line {k + 1}: .*{phrase}") as info:
        load_bvh(p, scale=0.01)
    assert isinstance(info.value, FlipstudyError)


def test_bounds_hold_in_metres_not_file_units(tmp_path):
    """A root 900 units from the origin is 9 m in centimetres and 900 m in metres (both
    accepted) but 9 km at 10 m per unit (refused at its frame line; the 90-unit root OFFSET
    is then 900 m, still accepted)."""
    text = many_joints_bvh(4, n_frames=5)
    lines = text.split("\n")
    k = _motion_line(text, 1)
    tok = lines[k].split()
    tok[0] = "900"
    lines[k] = " ".join(tok)
    p = tmp_path / "c.bvh"
    p.write_text("\n".join(lines))
    assert np.isclose(load_bvh(p, scale=0.01).root_pos[1, 0], 9.0)
    assert np.isclose(load_bvh(p, scale=1.0).root_pos[1, 0], 900.0)
    with pytest.raises(BVHError, match=f"line {k + 1}"):
        load_bvh(p, scale=10.0)


@pytest.mark.parametrize("kw", [{"fps": 0}, {"fps": 1e-300}, {"fps": 2e4}, {"fps": float("nan")},
                                {"scale": 0}, {"scale": -1}, {"scale": float("inf")}])
def test_bad_arguments_name_the_field(tmp_path, kw):
    p = tmp_path / "c.bvh"
    p.write_text(many_joints_bvh(4, n_frames=5))
    field = next(iter(kw))
    with pytest.raises(FlipstudyError, match=f"^{field}: expected"):
        load_bvh(p, **kw)


def test_thirty_thousand_joints_load(tmp_path):
    """Joint names are checked in a dict, so a 30,000-joint file loads (it took 18 s with a
    list; benchmarks/bench_bvh_joints.py compares its time with np.loadtxt's)."""
    p = tmp_path / "many.bvh"
    p.write_text(many_joints_bvh(30_000, n_frames=3))
    clip = load_bvh(p)
    assert clip.skeleton.num_joints == 30_000
    assert clip.rotations.shape == (3, 30_000, 4)
    dup = p.read_text().replace("JOINT J29999\n", "JOINT J7\n")
    p.write_text(dup)
    with pytest.raises(BVHError, match="duplicate joint name 'J7' \\(first at joint 7\\)"):
        load_bvh(p)

"""Issue 28 case 8: a BVH joint (or End Site) with two OFFSET lines or two CHANNELS
lines is refused with the file and the line of the second one, naming the first;
before, the last OFFSET silently won and two CHANNELS lines misread the motion."""
from __future__ import annotations

import re

import pytest
from hypothesis import given, settings, strategies as st

from flipstudy.stimuli.motion import BVHError, load_bvh

from _bvh_gen import many_joints_bvh
from _shared import shared_file


def _duplicate(text: str, key: str, k: int) -> tuple[str, int, int]:
    """``text`` with its ``k``-th line starting with ``key`` written twice; returns the
    new text, the 1-based line of the original and of the copy."""
    lines = text.split("\n")
    at = [i for i, ln in enumerate(lines) if ln.strip().startswith(key + " ")]
    i = at[k % len(at)]
    return "\n".join(lines[:i + 1] + [lines[i]] + lines[i + 1:]), i + 1, i + 2


@pytest.mark.parametrize("key", ["OFFSET", "CHANNELS"])
def test_a_real_cmu_file_with_a_line_twice_is_refused_at_that_line(tmp_path, key):
    text = shared_file("88_01.bvh").read_text()
    load_bvh(shared_file("88_01.bvh"))                       # the file as it is loads
    for k in (0, 7):                                         # the root's and a limb joint's
        bad, first, second = _duplicate(text, key, k)
        p = tmp_path / f"dup_{key}_{k}.bvh"
        p.write_text(bad)
        with pytest.raises(BVHError) as e:
            load_bvh(p)
        assert e.value.line == second
        msg = str(e.value)
        assert msg.startswith(f"{p}, line {second}: a second {key}") and f"line {first}" in msg


def test_an_end_site_with_two_offsets_is_refused(tmp_path):
    text = many_joints_bvh(5, n_frames=3)
    lines = text.split("\n")
    i = next(k for k, ln in enumerate(lines) if ln.strip() == "End Site") + 2   # its OFFSET
    assert lines[i].strip().startswith("OFFSET")
    p = tmp_path / "end.bvh"
    p.write_text("\n".join(lines[:i + 1] + ["OFFSET 1 2 3"] + lines[i + 1:]))
    with pytest.raises(BVHError, match=rf"line {i + 2}: a second OFFSET in one End Site \(the first at line {i + 1}\)"):
        load_bvh(p)


@settings(max_examples=25, deadline=None)
@given(n=st.integers(2, 30), key=st.sampled_from(["OFFSET", "CHANNELS"]), k=st.integers(0, 200))
def test_any_doubled_line_of_a_generated_file_is_refused(tmp_path_factory, n, key, k):
    text = many_joints_bvh(n, n_frames=2)
    assert len(re.findall(rf"^\s*{key} ", text, re.M)) >= n
    bad, first, second = _duplicate(text, key, k)
    p = tmp_path_factory.mktemp("g") / "g.bvh"
    p.write_text(bad)
    with pytest.raises(BVHError) as e:
        load_bvh(p)
    assert e.value.line == second and f"(the first at line {first})" in str(e.value)

"""flipstudy.stimuli.measure on the files a study build writes: the default
design (the paper's, ``flipstudy init``'s default) and a design using every
ballistic kind at ±20 % are built with ``build_stimuli``; every stimulus' BVH
is read back as any user's clip would be and measured from the motion alone.
Its kind's item must read the manifest's nominal error within 1 percentage
point; the originals (level 0) read ≈ 0 on every kind in % (within 1 point)."""
from __future__ import annotations

import pytest

from flipstudy import load_bvh
from flipstudy.stimuli.design import PAPER_DESIGN, parse_design
from flipstudy.stimuli.measure import measure
from flipstudy.stimuli.stimset import build_stimuli

#: the item each kind is read from (kind, variant, phase); None: the group's profile
ITEM = {"angular-momentum": ("angular-momentum", None, "flight 1"),
        "takeoff-angle": ("takeoff-angle", "", "takeoff 1"),
        "horizontal-velocity": ("horizontal-velocity", "", "takeoff 1"),
        "vertical-velocity": ("vertical-velocity", "", "takeoff 1"),
        "gravity": ("gravity", "", "flight 1"),
        "time-scale": ("time-scale", "", "flight 1")}


def ballistic_design() -> str:
    head = ('[study]\nname = "every-ballistic-kind"\nseed = 7\nfps = 120\nrepetitions = 1\n'
            'tolerance_pct = 1.0\n\n[[clips]]\nname = "backflip"\nsource = "backflip"\n\n'
            '[[clips]]\nname = "frontflip"\nsource = "frontflip"\n\n')
    groups = [("gravity", "policy", p) for p in ("takeoff-velocity", "apex-height", "flight-time")]
    groups += [("horizontal-velocity", None, None), ("vertical-velocity", None, None)]
    groups += [("acceleration", "axis", x) for x in ("horizontal", "vertical")]
    groups += [("time-scale", "span", s) for s in ("flight", "whole")]
    out = head
    for kind, key, val in groups:
        for sign in (1, -1):
            name = f"{kind}-{val or ''}-{'up' if sign > 0 else 'down'}".replace("--", "-")
            opt = f'{key} = "{val}"\n' if key else ""
            out += (f'[[groups]]\nname = "{name}"\nkind = "{kind}"\n{opt}sign = {sign}\n'
                    f"levels = [0, 20]\n\n")
    return out


@pytest.fixture(scope="module", params=["paper", "ballistic"])
def study(request, tmp_path_factory):
    text = PAPER_DESIGN if request.param == "paper" else ballistic_design()
    out = tmp_path_factory.mktemp(request.param) / "s"
    rows = build_stimuli(parse_design(text), out, progress=False).rows
    return out, rows


def _read(out, row):
    return measure(load_bvh(out / row["bvh"], fps=float(row["fps"]), scale=1.0))


def test_every_stimulus_measures_its_nominal_error(study):
    out, rows = study
    misses, n = [], 0
    for r in rows:
        if float(r["level"]) == 0:
            continue
        m = _read(out, r)
        kind, variant, phase = ITEM.get(r["kind"], ("acceleration", None, "flight 1"))
        if variant is None:
            variant = r["profile"] if r["kind"] == "angular-momentum" else r["axis"]
        items = m.get(kind, variant, phase)
        assert len(items) == 1, (r["stimulus"], m.warnings)
        nominal = float(r["nominal_error_pct"])
        n += 1
        if abs(items[0].size - nominal) > 1.0:
            misses.append((r["stimulus"], nominal, round(items[0].size, 2)))
    assert n >= 36 and not misses


def test_every_original_measures_zero(study):
    out, rows = study
    for r in rows:
        if float(r["level"]) != 0:
            continue
        m = _read(out, r)
        for i in m.items:
            if i.unit.startswith("%"):
                assert abs(i.size) <= 1.0, (r["stimulus"], i)
            elif i.unit == "mm":
                assert i.size <= 0.5, (r["stimulus"], i)

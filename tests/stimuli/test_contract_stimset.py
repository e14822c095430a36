"""The study contract (issue 29 item 1): ``StimulusSet.write`` then ``read`` gives
equal objects for any stimuli (hypothesis); ``read`` then ``write`` gives the same
bytes for real built studies (the paper's design, the ballistic kinds with their
columns, a style column, quest+ grids and 2AFC); every defect of a manifest is a
``ManifestError`` naming the file, the line and the column."""
from __future__ import annotations

import csv
import hashlib
import io
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from flipstudy.errors import FlipstudyError, FlipstudyFileNotFoundError, ManifestError
from flipstudy.stimuli.contract import (EXTRA_COLUMNS, MANIFEST_COLUMNS, Ballistic, Stimulus,
                                        StimulusSet)
from flipstudy.stimuli.design import parse_design
from flipstudy.stimuli.stimset import build_stimuli

# --- write → read: equal objects --------------------------------------------------------

NAME = st.from_regex(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,20}", fullmatch=True)
TEXT = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\r\n\x00"), max_size=12)
# what a manifest holds: six decimals (what the writer keeps), or a missing value (nan)
NUM = st.one_of(st.integers(-10**9, 10**9).map(lambda k: k / 1e6), st.just(math.nan),
                st.floats(-1e6, 1e6).map(lambda v: round(v, 6)))
INT = st.integers(-2**62, 2**62)


@st.composite
def ballistic(draw):
    kw = {c: draw(TEXT) for c in ("policy", "axis", "span", "quantity", "unit")}
    kw.update({c: draw(NUM) for c in Ballistic.columns() if c not in kw})
    return Ballistic(**kw)


@st.composite
def stimulus_sets(draw):
    styled, extra = draw(st.booleans()), draw(st.booleans())
    names = draw(st.lists(NAME, min_size=0, max_size=6, unique=True))
    out = []
    for n in names:
        kw = {c: draw(NUM) for c, t in Stimulus._types.items() if t is float}
        kw.update({c: draw(INT) for c, t in Stimulus._types.items() if t is int})
        kw.update({c: draw(TEXT) for c in ("clip", "group", "kind", "profile", "sha256", "original")})
        out.append(Stimulus(n, **kw, bvh=draw(st.sampled_from([f"{n}.bvh", f"sub/{n}.b"])),
                            accept_unphysical=draw(st.booleans()),
                            style=draw(TEXT) if styled else None,
                            ballistic=draw(ballistic()) if extra else None))
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stimuli=stimulus_sets())
def test_write_then_read_gives_equal_stimuli(tmp_path_factory, stimuli):
    d = tmp_path_factory.mktemp("s")
    s = StimulusSet(d, stimuli)
    text = s.write().read_text()
    back = StimulusSet.read(d, files=False, design=False)
    assert back == s and back.stimuli == tuple(stimuli)
    assert [type(getattr(b, "level")) for b in back] == [float] * len(stimuli)
    assert back.manifest_text() == text                                   # and the bytes again
    assert back.manifest_sha256 == hashlib.sha256(text.encode()).hexdigest()
    # an independent reader (the csv module) sees the same cells
    rows = list(csv.reader(io.StringIO(text, newline="")))
    assert rows[0] == s.columns and len(rows) == len(stimuli) + 1
    for r, x in zip(rows[1:], stimuli):
        assert r[0] == x.stimulus and r[rows[0].index("takeoff")] == str(x.takeoff)
        lv = r[rows[0].index("level")]
        assert (lv == "nan") if math.isnan(x.level) else float(lv) == x.level


def test_floats_are_kept_to_six_decimals_and_minus_zero_written_as_zero(tmp_path):
    s = Stimulus("a", "c", "g", "k", level=-1e-9, measured_error_pct=1.23456789, fps=np.float64(120))
    StimulusSet(tmp_path, [s]).write()
    line = (tmp_path / "manifest.csv").read_text().splitlines()[1].split(",")
    assert line[MANIFEST_COLUMNS.index("level")] == "0.000000"
    assert line[MANIFEST_COLUMNS.index("measured_error_pct")] == "1.234568"
    back = StimulusSet.read(tmp_path, files=False)["a"]
    assert back.measured_error_pct == 1.234568 and back.level == 0.0 and back.fps == 120.0


def test_a_stimulus_is_typed_when_made():
    s = Stimulus("a", "c", "g", "k", takeoff=np.int64(3), level=np.float32(2.5))
    assert type(s.takeoff) is int and type(s.level) is float and str(s.bvh) == "a.bvh"
    for bad in ({"takeoff": 2.5}, {"level": "10"}, {"accept_unphysical": "false"},
                {"bvh": "../x.bvh"}, {"bvh": "/abs.bvh"}):
        with pytest.raises(TypeError):
            Stimulus("a", "c", "g", "k", **bad)
    with pytest.raises(TypeError, match="plain file name"):
        Stimulus("../a", "c", "g", "k")
    for bad in ("two\nlines", "cr\r", "nul\x00"):             # a manifest cell is one line
        with pytest.raises(TypeError, match="one line of text"):
            Stimulus("a", "c", bad, "k")
        with pytest.raises(TypeError, match="one line of text"):
            Stimulus("a", "c", "g", "k", style=bad)
    with pytest.raises(AttributeError):
        s.level = 3.0                                       # frozen


# --- real built studies: read → write is byte-identical -----------------------------------

BASE = ('[study]\nname = "k"\nseed = 3\nrepetitions = 2\n{study}\n[[clips]]\nname = "backflip"\n'
        'source = "backflip"\n\n[reference]\nclips = ["backflip"]\n\n')
DESIGNS = {
    "paper": BASE.format(study="") + (
        '[[groups]]\nname = "smooth-increase"\nkind = "angular-momentum"\nprofile = "smooth"\n'
        'levels = [0, 25]\noriginal = "shared"\n\n'
        '[[groups]]\nname = "takeoff-increase"\nkind = "takeoff-angle"\nlevels = [0, 10]\n'),
    "ballistic-styled": BASE.format(study='style = "mannequin"\n') + (
        '[[groups]]\nname = "g"\nkind = "gravity"\npolicy = "flight-time"\nsign = -1\nlevels = [0, 20]\n\n'
        '[[groups]]\nname = "p"\nkind = "pose-rate"\nlevels = [0, 15]\n'),
    "quest-2afc-styled-group": BASE.format(study="") + (
        '[[groups]]\nname = "q"\nkind = "angular-momentum"\nprofile = "smooth"\n'
        'levels = {from = 0, to = 30, step = 10}\nmethod = "quest+"\ntrials = 6\n\n'
        '[[groups]]\nname = "f"\nkind = "takeoff-angle"\nlevels = [0, 20]\ntask = "2afc"\nstyle = "stick"\n'),
}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("built")
    out = {}
    for name, text in DESIGNS.items():
        (root / f"{name}.toml").write_text(text)
        rows = build_stimuli(parse_design(text, root / f"{name}.toml"), root / name, progress=False).rows
        out[name] = (root / name, rows)
    return out


@pytest.mark.parametrize("name", list(DESIGNS))
def test_read_then_write_is_byte_identical_for_built_studies(built, name, tmp_path):
    folder, rows = built[name]
    data = (folder / "manifest.csv").read_bytes()
    s = StimulusSet.read(folder)                      # every file there, every hash right
    assert s.design is not None and s.design.name == "k" and len(s) == len(rows)
    assert s.write(tmp_path).read_bytes() == data
    assert s.manifest_sha256 == hashlib.sha256(data).hexdigest()
    # the typed values are the build's numbers to six decimals, the files its files
    for r, x in zip(rows, s):
        assert x.stimulus == r["stimulus"] and x.takeoff == r["takeoff"] and x.frames == r["frames"]
        assert x.measured_error_pct == pytest.approx(r["measured_error_pct"], abs=5e-7)
        assert hashlib.sha256(s.path(x).read_bytes()).hexdigest() == x.sha256
        assert np.load(s.path(x, "npz"))["takeoff"] == x.takeoff
    header = data.decode().split("\n", 1)[0].split(",")
    assert header[:len(MANIFEST_COLUMNS)] == MANIFEST_COLUMNS
    assert (s.stimuli[0].ballistic is not None) == (header[-len(EXTRA_COLUMNS):] == EXTRA_COLUMNS)
    assert s.styled == ("style" in header)


def test_the_kinds_carry_their_typed_parts(built):
    s = StimulusSet.read(built["ballistic-styled"][0])
    assert {x.style for x in s} == {"mannequin"}
    g = s["backflip_g_20"].ballistic
    assert (g.policy, g.unit) == ("flight-time", "m/s²")
    assert g.nominal_value == pytest.approx(0.8 * 9.81, abs=1e-3)        # known: 80 % of g
    assert s["backflip_p_15"].ballistic.measured_value == pytest.approx(15.0, rel=1e-4)
    q = StimulusSet.read(built["quest-2afc-styled-group"][0])
    assert {x.style for x in q if x.group == "f"} == {"stick"}
    assert [x.level for x in q if x.group == "q"] == [10.0, 20.0, 30.0]          # the grid
    assert {x.original for x in q if x.group == "q"} == {"backflip_original"}     # level 0, shared
    assert q["backflip_f_20"].original == "backflip_f_0"


# --- a bad manifest: one error naming file, line and column -------------------------------

def _copy(built, tmp_path) -> Path:
    d = tmp_path / "s"
    shutil.copytree(built["paper"][0], d)
    return d


def _edit(d: Path, line: int, col: str, value: str) -> None:
    rows = list(csv.reader(io.StringIO((d / "manifest.csv").read_text(), newline="")))
    rows[line - 1][rows[0].index(col)] = value
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    (d / "manifest.csv").write_text(buf.getvalue())


@pytest.mark.parametrize("col,value,what", [
    ("level", "ten", "is not a number"), ("takeoff", "12.5", "is not an integer"),
    ("accept_unphysical", "yes", "is not true or false"), ("fps", "inf", "is not a number"),
    ("bvh", "../../etc/passwd", "inside the study folder"), ("stimulus", "a b", "plain file name")])
def test_a_bad_cell_names_file_line_and_column(built, tmp_path, col, value, what):
    d = _copy(built, tmp_path)
    _edit(d, 3, col, value)
    with pytest.raises(ManifestError) as e:
        StimulusSet.read(d)
    assert str(e.value).startswith(f"{d / 'manifest.csv'} line 3, column ") and col in str(e.value)
    assert what in str(e.value)


def test_missing_files_changed_files_and_columns_are_refused(built, tmp_path):
    d = _copy(built, tmp_path)
    first = StimulusSet.read(d).stimuli[1]
    (d / first.npz).unlink()
    with pytest.raises(ManifestError, match=rf"line 3: stimulus '{first.stimulus}': no file .*{first.npz}"):
        StimulusSet.read(d)
    assert len(StimulusSet.read(d, files=False)) == len(built["paper"][1])   # a session needs no motion
    d = _copy(built, tmp_path / "b")
    (d / first.bvh).write_text((d / first.bvh).read_text() + "\n")
    with pytest.raises(ManifestError, match=r"line 3: .* has sha256 .* the manifest says"):
        StimulusSet.read(d)
    text = (d / "manifest.csv").read_text()
    (d / "manifest.csv").write_text(text.replace(",sha256,", ",sha,", 1))
    with pytest.raises(ManifestError, match=r"line 1: no column 'sha256'"):
        StimulusSet.read(d)
    (d / "manifest.csv").write_text(text.replace(",dp_landing,", ",dp_landed,", 1))
    with pytest.raises(ManifestError, match=r"line 1: unknown column 'dp_landed'"):
        StimulusSet.read(d)
    (d / "manifest.csv").write_text(text.replace("\n", ",x\n", 2))
    with pytest.raises(ManifestError, match=r"line 1: unknown column 'x'"):
        StimulusSet.read(d)
    lines = text.splitlines()
    (d / "manifest.csv").write_text(text + "\n")         # a blank line: skipped, but the hash changes
    blank = StimulusSet.read(d, files=False)
    assert blank.stimuli == StimulusSet(d, blank.stimuli).stimuli and len(blank) == len(lines) - 1
    assert blank.manifest_sha256 != hashlib.sha256(text.encode()).hexdigest()
    (d / "manifest.csv").write_text("\n".join(lines + [lines[-1]]) + "\n")
    with pytest.raises(ManifestError, match="listed more than once"):
        StimulusSet.read(d, files=False)
    (d / "manifest.csv").write_text("\n".join(lines[:3] + [lines[3].rsplit(",", 1)[0]]) + "\n")
    with pytest.raises(ManifestError, match=r"line 4: 34 cells, the header has 35"):
        StimulusSet.read(d, files=False)
    (d / "manifest.csv").unlink()
    with pytest.raises(FlipstudyFileNotFoundError, match="no manifest"):
        StimulusSet.read(d)


def test_an_older_builds_manifest_still_opens_its_sessions(built, tmp_path):
    """A study built before the last measured columns were added (below_floor_mm,
    takeoff_time, ...) keeps its answers usable: those columns read as NaN (not
    measured), the session's order is the same, and write() gives today's columns."""
    from flipstudy.study.order import trial_order
    from flipstudy.study.session import load_study
    d = _copy(built, tmp_path)
    (d / "design.toml").write_text(DESIGNS["paper"])
    full = StimulusSet.read(d)
    rows = list(csv.reader(io.StringIO((d / "manifest.csv").read_text(), newline="")))
    keep = [k for k, c in enumerate(rows[0]) if c not in ("below_floor_mm", "takeoff_time", "fps", "frames")]
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows([[r[k] for k in keep] for r in rows])
    (d / "manifest.csv").write_text(buf.getvalue())
    old = StimulusSet.read(d)
    assert old.names == full.names and all(math.isnan(x.below_floor_mm) and math.isnan(x.fps) for x in old)
    assert [x.landing_time for x in old] == [x.landing_time for x in full] and old.stimuli[0].frames == 0
    study = load_study(d)
    assert trial_order(study.design, study.stimuli, "P01") == trial_order(full.design, full, "P01")
    assert old.manifest_text().split("\n", 1)[0] == ",".join(MANIFEST_COLUMNS)


def test_every_stage_takes_the_set_it_was_handed(built, tmp_path):
    """Sessions, export and the render check take a StimulusSet read once; a
    StimulusSet made in memory (not on disk) is what they use."""
    from flipstudy.study.order import trial_order
    from flipstudy.study.session import load_study
    folder, _ = built["paper"]
    s = StimulusSet.read(folder)
    study = load_study(s)
    assert study.stimuli is s and study.manifest_sha256 == s.manifest_sha256
    trials = trial_order(s.design, s, "P01")
    assert {t.stimulus for t in trials} == {x.stimulus for x in s.tests}
    assert all(isinstance(t.level, float) for t in trials)
    assert isinstance(ManifestError("x"), FlipstudyError)

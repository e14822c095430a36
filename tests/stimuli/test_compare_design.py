"""A comparison design ([[sources]]) is a Design like any other: valid when it
exists, and ``from_dict(to_dict(d)) == d`` / ``from_toml(to_toml(d)) == d`` over
drawn sources (names, folders with any characters, scale, fps) and error groups."""
import os
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pytest

from flipstudy.errors import DesignError
from flipstudy.stimuli.design import Design, SourceGroup, parse_design

NAMES = st.from_regex(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,8}", fullmatch=True)
FOLDERS = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), min_size=1,
                  max_size=20)


@st.composite
def comparison_tables(draw):
    names = draw(st.lists(NAMES, min_size=2, max_size=4, unique=True))
    folders = draw(st.lists(FOLDERS, min_size=len(names), max_size=len(names),
                            unique_by=os.path.normpath))       # one folder written twice is refused
    task = draw(st.sampled_from(["yes-no", "2afc"]))
    sources = []
    for n, f in zip(names, folders):
        s = {"name": n, "folder": f}
        if draw(st.booleans()):
            s["scale"] = draw(st.floats(1e-3, 10, allow_nan=False))
        if draw(st.booleans()):
            s["fps"] = float(draw(st.integers(10, 240)))
        if draw(st.booleans()):
            s["accept_unphysical"] = draw(st.booleans())
        sources.append(s)
    tables = {"study": {"name": draw(NAMES), "seed": draw(st.integers(0, 2 ** 63 - 1)), "task": task,
                        "repetitions": draw(st.integers(1, 5))},
              "sources": sources}
    if draw(st.booleans()):
        tables["study"]["fps"] = float(draw(st.integers(10, 240)))
    if task == "2afc" and draw(st.booleans()):
        tables["study"]["compare"] = draw(st.sampled_from(["first", "all"]))
    gnames = draw(st.lists(NAMES.filter(lambda x: x not in names and x not in ("reference", "original")),
                           max_size=2, unique=True))
    tables["groups"] = [{"name": g, "kind": "takeoff-angle",
                         "levels": sorted({0.0, *draw(st.lists(st.sampled_from([5.0, 10.0, 20.0, 40.0]),
                                                               min_size=1, max_size=3))})}
                        for g in gnames]
    if not tables["groups"]:
        del tables["groups"]
    return tables


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(t=comparison_tables())
def test_a_comparison_design_round_trips_through_dict_and_toml(t):
    d = Design.from_dict(t, "drawn.toml")
    assert d.compares and [s.name for s in d.sources] == [s["name"] for s in t["sources"]]
    names = [s["name"] for s in t["sources"]]
    pairs = [f"{b}-vs-{a}" for i, a in enumerate(names[1:], 1) for b in names[i + 1:]] \
        if t["study"].get("compare") == "all" else []
    assert [g.name for g in d.groups if isinstance(g, SourceGroup)] == names + pairs
    assert [g.name for g in d.error_groups] == [g["name"] for g in t.get("groups", [])]
    assert Design.from_dict(d.to_dict(), d.path) == d
    back = parse_design(d.to_toml(), "again.toml")
    assert back == d and back.to_dict() == d.to_dict()
    assert [s.folder for s in back.sources] == [s["folder"] for s in t["sources"]]


def _sources_design(n: int, compare: str = "first", folders=None, extra: str = "") -> str:
    folders = folders or [f"f{i}" for i in range(n)]
    text = f'[study]\nname = "c"\nseed = 1\ntask = "2afc"\ncompare = "{compare}"\n{extra}'
    return text + "".join(f'\n[[sources]]\nname = "s{i}"\nfolder = "{f}"\n' for i, f in enumerate(folders))


def test_a_thousand_sources_compared_in_all_pairs_are_refused_with_the_number_they_would_build():
    """Issue 45 item 13: 1,000 sources with compare = "all" built 499,501 stimuli a run then refused."""
    with pytest.raises(DesignError, match=r"c\.toml: \[\[sources\]\]: 1,000 sources, at most 64 "
                                          r"\(they would build 499,501 stimuli per item: 1000 sources \+ "
                                          r"498,501 pairs") as e:
        parse_design(_sources_design(1000, "all"), "c.toml")
    assert "\n" not in str(e.value)
    with pytest.raises(DesignError, match=r"c\.toml: \[\[sources\]\]: 60 sources \+ 1,711 pairs .* = 1,771 "
                                          r"stimuli per item, × repetitions 2 = 3,542 trials per participant"):
        parse_design(_sources_design(60, "all", extra="repetitions = 2\n"), "c.toml")
    assert len(parse_design(_sources_design(60, "all", extra="repetitions = 1\n"), "c.toml").sources) == 60


@pytest.mark.parametrize("folders", [["gt", "gt/"], ["gt", "gt/./"], ["gt/", "./gt"], ["a/../gt", "gt"]])
def test_one_folder_written_twice_is_a_duplicate_source(folders, tmp_path):
    """Issue 45 item 16: ``gt``, ``gt/`` and ``gt/./`` passed the duplicate check."""
    p = tmp_path / "c.toml"
    p.write_text(_sources_design(2, folders=folders))
    with pytest.raises(DesignError, match=r"c\.toml: \[\[sources\]\]: duplicate source folders .* "
                                          r"\(one folder, written differently\)"):
        Design.from_toml(p)
    with pytest.raises(DesignError, match="duplicate source folders"):
        parse_design(_sources_design(2, folders=folders), "c.toml")


def _folders_with(tmp_path, stems, sources=("gt", "b")) -> Path:
    """Source folders holding (empty) clip files of ``stems``: the checks run before any is read."""
    for s in sources:
        (tmp_path / s).mkdir()
        for stem in stems:
            (tmp_path / s / f"{stem}.bvh").write_bytes(b"")
    p = tmp_path / "c.toml"
    p.write_text(_sources_design(len(sources), folders=list(sources), extra="repetitions = 20\n")
                 + '\n[[groups]]\nname = "g"\nkind = "takeoff-angle"\nlevels = [0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50]\n')
    return p


def test_a_build_beyond_the_trials_of_a_session_is_refused_before_it_starts(tmp_path):
    """Issue 45 item 13 at build time: the items the folders hold × the stimuli per item
    are counted before anything is read, and the message names the number."""
    from flipstudy.stimuli.stimset import build_stimuli
    p = _folders_with(tmp_path, [f"i{k}" for k in range(8)])
    with pytest.raises(DesignError, match=r"c\.toml: \[\[sources\]\]: 8 items × 22 stimuli per item .* would build "
                                          r"176 stimuli, × repetitions 20 = 3,520 trials per participant; at most 3000"):
        build_stimuli(Design.from_toml(p), tmp_path / "study", progress=False)
    assert not (tmp_path / "study").exists()


@pytest.mark.parametrize("stem", ["my clip", "sprüng", "x" * 200])
def test_an_item_name_that_cannot_name_a_stimulus_file_names_the_file(stem, tmp_path):
    """Issue 45: item names with spaces, non-ASCII or 200 characters ended in a TypeError."""
    from flipstudy.stimuli.stimset import build_stimuli
    p = _folders_with(tmp_path, [stem])
    with pytest.raises(DesignError, match=r"gt/.*\.bvh: the item name .* \(the file's name without its suffix\) "
                                          r"must be 1-64 letters") as e:
        build_stimuli(Design.from_toml(p), tmp_path / "study", progress=False)
    assert "\n" not in str(e.value)

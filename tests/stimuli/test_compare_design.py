"""A comparison design ([[sources]]) is a Design like any other: valid when it
exists, and ``from_dict(to_dict(d)) == d`` / ``from_toml(to_toml(d)) == d`` over
drawn sources (names, folders with any characters, scale, fps) and error groups."""
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flipstudy.stimuli.design import Design, SourceGroup, parse_design

NAMES = st.from_regex(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,8}", fullmatch=True)
FOLDERS = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), min_size=1,
                  max_size=20)


@st.composite
def comparison_tables(draw):
    names = draw(st.lists(NAMES, min_size=2, max_size=4, unique=True))
    folders = draw(st.lists(FOLDERS, min_size=len(names), max_size=len(names), unique=True))
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

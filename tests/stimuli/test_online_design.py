"""Issue 32: the design's [online] and [exclusions] tables: validated on construction,
round-tripped through dict and TOML (hypothesis), written only when given."""
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from flipstudy.stimuli.design import PAPER_DESIGN, Design, DesignError, parse_design
from flipstudy.stimuli.online import PROLIFIC_COMPLETE, Exclusions, OnlineSettings

PARAM = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,10}", fullmatch=True)


def catch_design(extra: dict):
    t = tomllib.loads(PAPER_DESIGN)
    t["groups"].append({"name": "catch", "kind": "takeoff-angle", "levels": [90]})
    t.update(extra)
    return t


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(online=st.fixed_dictionaries({}, optional={
           "recruit_params": st.lists(PARAM, unique=True, max_size=4),
           "completion_code": st.from_regex(r"[A-Za-z0-9_-]{0,12}", fullmatch=True),
           "completion_url": st.sampled_from(["", "https://example.org/done?c={code}"]),
           "consent": st.sampled_from(["", "consent.md", "c_1.txt"]),
           "debrief": st.sampled_from(["", "debrief.md"]),
           "demographics": st.booleans(),
           "min_refresh_hz": st.floats(0, 1000), "min_width": st.integers(0, 10000),
           "min_height": st.integers(0, 10000), "preload": st.booleans()}),
       excl=st.fixed_dictionaries({}, optional={
           "catch_groups": st.sampled_from([[], ["catch"]]), "min_catch_accuracy_pct": st.floats(0, 100),
           "max_flagged_pct": st.floats(0, 100), "require_complete": st.booleans(),
           "min_median_rt_ms": st.floats(0, 60000)}))
def test_online_and_exclusions_round_trip(online, excl):
    d = Design.from_dict(catch_design({"online": online, "exclusions": excl}), "drawn.toml")
    assert Design.from_dict(d.to_dict(), d.path) == d
    back = parse_design(d.to_toml(), "again.toml")
    assert back == d and back.to_dict() == d.to_dict()
    for k, v in online.items():
        assert getattr(d.online, k) == (tuple(v) if isinstance(v, list) else v)


def test_defaults_are_not_written_and_older_designs_keep_their_text():
    d = parse_design(PAPER_DESIGN)
    assert d.online == OnlineSettings() and d.exclusions == Exclusions()
    assert "[online]" not in d.to_toml() and "[exclusions]" not in d.to_toml()
    assert d.online.recruit_params == ("PROLIFIC_PID", "STUDY_ID", "SESSION_ID") and d.online.redirect_url() == ""


def test_redirect_url():
    assert OnlineSettings(completion_code="AB1").redirect_url() == PROLIFIC_COMPLETE.format(code="AB1")
    assert OnlineSettings(completion_code="AB1", completion_url="https://x.org/end?code={code}").redirect_url() \
        == "https://x.org/end?code=AB1"


@pytest.mark.parametrize("extra, message", [
    ({"online": {"completion_url": "http://insecure.org"}}, "[online].completion_url: an https:// URL"),
    ({"online": {"consent": "../secret.txt"}}, "[online].consent: a file name beside the design"),
    ({"online": {"recruit_params": ["PROLIFIC_PID", "PROLIFIC_PID"]}}, "[online].recruit_params: listed twice"),
    ({"online": {"recruit_params": ["a b"]}}, "URL parameter names are letters"),
    ({"online": {"min_width": -1}}, "[online].min_width: expected 0 to 10000 pixels"),
    ({"online": {"completion": "x"}}, "unknown key 'completion'; did you mean 'completion_url'?"),
    ({"exclusions": {"catch_groups": ["nope"]}}, "'nope' is not one of the groups"),
    ({"exclusions": {"catch_groups": ["smooth-increase"]}}, "a catch group's level 0 is its own original"),
    ({"exclusions": {"min_catch_accuracy_pct": 120}}, "[exclusions].min_catch_accuracy_pct: expected 0 to 100"),
    ({"exclusion": {}}, "unknown section [exclusion]; did you mean [exclusions]?"),
])
def test_bad_tables_are_refused_naming_file_and_key(extra, message):
    with pytest.raises(DesignError, match=None) as e:
        Design.from_dict(catch_design(extra), "d.toml")
    assert message in str(e.value) and str(e.value).startswith("d.toml")


@pytest.mark.parametrize("group, message", [
    ({"levels": [0, 100], "original": "own"}, None),                    # its own original (the guide's)
    ({"levels": [100]}, None),                                          # none
    ({"levels": [0, 100]}, "a catch group's level 0 is its own original"),    # the shared one: refused
    ({"levels": [0], "original": "own"}, "at least one level above 0"),
])
def test_a_catch_group_may_show_its_own_original_never_the_shared_one(group, message):
    t = tomllib.loads(PAPER_DESIGN)
    t["groups"].append({"name": "catch", "kind": "angular-momentum", "profile": "abrupt", **group})
    t["exclusions"] = {"catch_groups": ["catch"], "min_catch_accuracy_pct": 75}
    if message is None:
        d = Design.from_dict(t, "d.toml")
        assert d.groups[-1].trial_levels() == list(group["levels"])
    else:
        with pytest.raises(DesignError) as e:
            Design.from_dict(t, "d.toml")
        assert message in str(e.value) and str(e.value).startswith("d.toml")

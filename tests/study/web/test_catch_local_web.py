"""Issue 42, item 1: catch trials by construction in every path.  The sessions guide's
Prolific tables (its catch group, [online], [exclusions]) on a study whose groups share
the clip's original: the same three participants (attentive, "incorrect" to everything,
at random) answered locally (the session path `run` stores) and on the web (the records
the site writes, through `import-web`) give the same groups, the same catch trials and
the same exclusions; `simulate` pilots the design."""
import hashlib

import pandas as pd
import pytest

from _prolific import guide_prolific_tables, web_records, write_jsonl

from flipstudy.study.demo import make_demo_study
from flipstudy.study.export import export_responses
from flipstudy.study.pipeline import analyze
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.simulate import simulate
from flipstudy.study.web.importer import import_web


def _random(t):
    """A coin per motion and showing (the same in both paths): right on at most one of the
    catch group's two trials here (its original)."""
    return "incorrect" if hashlib.sha256(f"r2:{t.stimulus}:{t.repetition}".encode()).digest()[0] % 2 else "correct"


#: role → answer(trial): right everywhere, "incorrect" to everything, at random
ROLES = {"att": lambda t: "incorrect" if t.level else "correct", "inc": lambda t: "incorrect", "rnd": _random}


def guide_tables(catch):
    """The guide's tables; ``catch`` "own": as written (the catch group's own original
    and its gross error), "none": the catch group without an original of its own."""
    text = guide_prolific_tables()
    if catch == "none":
        text = text.replace("levels = [0, 100]", "levels = [100]").replace('original = "own"', "")
        assert "levels = [100]" in text
    return text


@pytest.fixture(params=["own", "none"])
def study(tmp_path, request):
    d = make_demo_study(tmp_path / "study", original="shared", repetitions=1, videos=False,
                        extra=guide_tables(request.param))
    (d / "consent.md").write_text("# Taking part\n\nYou may stop at any time.\n")
    (d / "debrief.md").write_text("Thank you!\n")
    return d


def _local(study):
    st = load_study(study)
    for role, answer in ROLES.items():
        s = open_session(st, f"L{role}")
        for t in s.trials:
            submit_answer(s, {"participant": s.participant, "session": s.session, "trial": t.trial,
                              "stimulus": t.stimulus, "response": answer(t), "rt_ms": 700.0, "shown_ms": 400.0,
                              "late_frames": 0, "replays": 0, "input": "key"})
        s.close()
    export_responses(study)
    return study / "responses.csv"


def _web(study, tmp_path):
    files = [write_jsonl(tmp_path / f"W{role}.jsonl", web_records(study, f"W{role}", run=f"r{role}", response=answer))
             for role, answer in ROLES.items()]
    import_web(study, files)
    return study / "web" / "responses.csv"


def _outcome(csv, out):
    analyze([csv], out, psychometric="none", gee=False, n_boot=20, figures=False)
    rows = pd.read_csv(out / "responses_exclusions.csv", keep_default_na=False)
    rows["role"] = rows["participant"].str[1:]
    part = pd.read_csv(out / "exclusions_participants.csv", keep_default_na=False)
    part["role"] = part["participant"].str[1:]
    return rows, part.set_index("role"), pd.read_csv(out / "table.csv")


def test_local_and_web_give_the_same_groups_catch_trials_and_exclusions(study, tmp_path):
    local = _outcome(_local(study), tmp_path / "local")
    web = _outcome(_web(study, tmp_path), tmp_path / "web")
    own = (study / "manifest.csv").read_text().count("backflip_catch_0") > 0
    catch = {"backflip_catch_0", "backflip_catch_100"} if own else {"backflip_catch_100"}
    for rows, part, table in (local, web):
        # every row in its manifest group: the shared original in 'original', never a catch trial
        assert set(rows.loc[rows["stimulus"] == "backflip_original", "group"]) == {"original"}
        assert set(rows.loc[rows["catch"], "stimulus"]) == catch
        # the catch trials counted are those each participant saw (one showing of each)
        assert part["catch_trials"].to_dict() == {r: len(catch) for r in ROLES}
        if own:
            assert part["catch_accuracy_pct"].to_dict() == {"att": 100.0, "inc": 50.0, "rnd": 50.0}
            assert part["exclusion_rule"].to_dict() == {"att": "", "inc": "catch accuracy", "rnd": "catch accuracy"}
        else:       # a gross error alone: "incorrect" to everything passes (the guide says so)
            assert part["catch_accuracy_pct"].to_dict() == {"att": 100.0, "inc": 100.0, "rnd": 100.0}
            assert not part["excluded"].any()
        # the tables keep the original's answers (one per participant kept) as both groups' level 0
        cells = table.set_index(["group", "level"])["n"]
        assert cells[("smooth-increase", 0.0)] == cells[("abrupt-decrease", 0.0)] == (~part["excluded"]).sum()
        assert "catch" not in set(table["group"])
    key = ["role", "stimulus", "group", "level", "catch", "response", "excluded", "exclusion_rule"]
    same = [r[key].sort_values(["role", "stimulus"]).reset_index(drop=True) for r, _, _ in (local, web)]
    pd.testing.assert_frame_equal(*same)
    pd.testing.assert_frame_equal(local[2], web[2])


def test_simulate_pilots_a_design_with_a_catch_group(study, tmp_path):
    simulate(study, 3, seed=2)
    export_responses(study, include_simulated=True)
    rows = pd.read_csv(study / "responses.csv", keep_default_na=False)
    catch = {r.stimulus for r in load_study(study).manifest if r.group == "catch"}
    assert len(rows) == 3 * (3 + len(catch)) and set(rows.loc[rows["group"] == "catch", "stimulus"]) == catch
    assert set(rows.loc[rows["stimulus"] == "backflip_original", "group"]) == {"original"}
    from flipstudy.study.simulate import DEFAULT_MODEL, with_catch_groups
    from flipstudy.stimuli.design import load_design
    m = with_catch_groups(DEFAULT_MODEL, load_design(study / "design.toml"))
    # the catch group (abrupt, sign +1) answered with the model of its kind, abrupt-increase,
    # its largest level (50) held for the gross 100
    assert m.p_correct("catch", 100) == DEFAULT_MODEL.p_correct("abrupt-increase", 50)
    assert m.p_correct("catch", 0) == DEFAULT_MODEL.p_correct("abrupt-increase", 0)

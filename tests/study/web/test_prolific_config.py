"""Issue 32, fast (no browser): the site's [online] settings in config.js, the consent
and debrief files, and import-web keeping the recruiter's ids on every row (checked
as participant IDs are)."""
import json

import pandas as pd
import pytest

from flipstudy.errors import SiteError, WebImportError
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT, site_config

ONLINE = """
[online]
completion_code = "C7XK2P"
consent = "consent.md"
min_refresh_hz = 50
preload = false
demographics = false
"""


@pytest.fixture
def study(tmp_path):
    d = make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=1, extra=ONLINE)
    (d / "consent.md").write_text("# Consent\n\nI agree to **take part**.\n")
    return d


def test_the_site_carries_the_online_settings(study):
    cfg = site_config(load_study(study), host="jatos")["online"]
    assert cfg["redirect_url"] == "https://app.prolific.com/submissions/complete?cc=C7XK2P"
    assert cfg["consent_html"] == "<h2>Consent</h2><p>I agree to <strong>take part</strong>.</p>"
    assert cfg["recruit_params"] == ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]
    assert (cfg["min_refresh_hz"], cfg["preload"], cfg["demographics"], cfg["debrief_html"]) == (50.0, False, False, "")


def test_a_missing_consent_file_is_named(study):
    (study / "consent.md").unlink()
    with pytest.raises(SiteError, match=r"\[online\].consent = 'consent.md': cannot read .*consent.md"):
        site_config(load_study(study), host="jatos")


def _records(study, pid, **extra):
    st = load_study(study)
    trials = web_trial_order(order_groups(st.design, st.manifest), 1, st.design.seed, pid)
    base = {"format": FORMAT, "site_id": "s", "study": st.design.name, "manifest_sha256": st.manifest_sha256,
            "host": "jatos", "participant": pid, "run_id": "r1", "run_started": "2026-01-05T10:00:00.000Z",
            "timestamp": "2026-01-05T10:00:01.000Z", **extra}
    recs = [dict(base, record="start", n_trials=len(trials), order=" ".join(t.stimulus for t in trials),
                 refresh_hz=60.0, consent="2026-01-05T10:00:00.500Z", window="900x760", screen_ok=True)]
    recs += [dict(base, record="answer", trial=t.trial, stimulus=t.stimulus, group=t.group, level=t.level,
                  repetition=1, clip=t.clip, kind=t.kind, response="correct", rt_ms=500.0, shown_ms=400.0,
                  input="key", replays=0, frames_expected=12, frames_presented=12, frames_dropped=0,
                  dropped_pct=0.0, playback_ms=400.0, video_ms=400.0, timing="rvfc", playback_flagged=False,
                  max_dropped_pct=10.0) for t in trials]
    return recs


def test_import_keeps_the_recruiter_ids_on_every_row(study, tmp_path):
    f = tmp_path / "a.jsonl"
    recs = _records(study, "P1", PROLIFIC_PID="P1", STUDY_ID="st9", SESSION_ID="se3")
    f.write_text("".join(json.dumps(r) + "\n" for r in recs))
    import_web(study, [f])
    rows = pd.read_csv(study / "web" / "responses.csv", dtype=str)
    assert len(rows) == 4 and set(rows["STUDY_ID"]) == {"st9"} and set(rows["SESSION_ID"]) == {"se3"}
    parts = pd.read_csv(study / "web" / "participants.csv", dtype=str)
    assert parts.loc[0, "STUDY_ID"] == "st9" and parts.loc[0, "window"] == "900x760" and parts.loc[0, "screen_ok"] == "true"


def test_a_bad_recruiter_id_is_refused_with_its_line(study, tmp_path):
    f = tmp_path / "bad.jsonl"
    recs = _records(study, "P1", STUDY_ID="x<script>")
    f.write_text("".join(json.dumps(r) + "\n" for r in recs))
    with pytest.raises(WebImportError, match=r"bad.jsonl: line 1: STUDY_ID 'x<script>' is not a valid"):
        import_web(study, [f])
    assert not (study / "web" / "responses.csv").exists()

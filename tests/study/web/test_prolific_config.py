"""Issue 32, fast (no browser): the site's [online] settings in config.js, the consent
and debrief files, and import-web keeping the recruiter's ids on every row (checked
as participant IDs are)."""
import pandas as pd
import pytest

from _prolific import web_records, write_jsonl

from flipstudy.errors import SiteError, WebImportError
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.site import site_config

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


def test_import_keeps_the_recruiter_ids_on_every_row(study, tmp_path):
    import_web(study, [write_jsonl(tmp_path / "a.jsonl", web_records(
        study, "P1", end=False, PROLIFIC_PID="P1", STUDY_ID="st9", SESSION_ID="se3"))])
    rows = pd.read_csv(study / "web" / "responses.csv", dtype=str)
    assert len(rows) == 4 and set(rows["STUDY_ID"]) == {"st9"} and set(rows["SESSION_ID"]) == {"se3"}
    parts = pd.read_csv(study / "web" / "participants.csv", dtype=str)
    assert parts.loc[0, "STUDY_ID"] == "st9" and parts.loc[0, "window"] == "900x760" and parts.loc[0, "screen_ok"] == "true"


def test_a_bad_recruiter_id_is_refused_with_its_line(study, tmp_path):
    f = write_jsonl(tmp_path / "bad.jsonl", web_records(study, "P1", STUDY_ID="x<script>"))
    with pytest.raises(WebImportError, match=r"bad.jsonl: line 1: STUDY_ID 'x<script>' is not a valid"):
        import_web(study, [f])
    assert not (study / "web" / "responses.csv").exists()

"""Issue 45, item 7 in headless Chromium: saved records without the agreement to the
consent text (``{"records":[{"record":"start"}]}`` seeded into localStorage, or a start
record whose ``consent`` is null) do not skip the consent screen; the run that follows
is recorded with its agreement and imported."""
import json
import os

import pytest

from test_session_browser import CHROMIUM, jspsych_dir, page, pw  # noqa: F401 (fixtures)
from test_web_browser import _Host
from test_prolific_browser import PID, _records, _route, _through, study  # noqa: F401 (fixture)
from _prolific import write_jsonl

from flipstudy.study.web.importer import import_web
from flipstudy.study.web.site import FORMAT, export_site

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason=f"needs Debian's chromium at {CHROMIUM}")]


def _forged_start(site_id):
    return {"records": [{"format": FORMAT, "record": "start", "site_id": site_id, "participant": PID,
                         "run_id": "rforged0001", "consent": None}], "sent": 0, "run_id": "rforged0001",
            "run_started": "2026-01-05T10:00:00.000Z"}


@pytest.mark.parametrize("seed", [lambda site_id: {"records": [{"record": "start"}]}, _forged_start],
                         ids=["bare start", "start without consent"])
def test_saved_records_without_consent_do_not_skip_the_consent_screen(page, study, tmp_path, jspsych_dir,  # noqa: F811
                                                                       seed):
    site = tmp_path / "site"
    res = export_site(study, site, host="jatos", iti_ms=20, jspsych_dir=jspsych_dir)
    blocked = []
    with _Host(site) as host:
        origin = f"127.0.0.1:{host.port}"
        _route(page, origin, blocked)
        page.goto(f"http://{origin}/config.js")              # the site's origin, before the site runs
        key = f"flipstudy:{res['site_id']}:{PID}"
        page.evaluate("([k, v]) => localStorage.setItem(k, v)", [key, json.dumps(seed(res["site_id"]))])
        page.goto(f"http://{origin}/index.html?PROLIFIC_PID={PID}")
        page.wait_for_selector('#jspsych-target[data-screen-id="consent"]')
        assert host.bodies == []                                       # nothing sent before it
        _through(page, 5, lambda stim: "correct")
        page.wait_for_selector('#jspsych-target[data-saved="1"]', timeout=40_000)
    recs = _records(host.bodies)
    starts = [r for r in recs if r["record"] == "start"]
    assert len(starts) == 1 and starts[0]["consent"] and starts[0]["run_id"] != "rforged0001"
    assert all(r.get("format") == FORMAT for r in recs)              # the seeded record is gone
    out = import_web(study, [write_jsonl(tmp_path / "jatos.txt", recs)])
    assert out.participants == 1 and out.answers == 5 and out.quarantined == ()

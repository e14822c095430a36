"""The participant server refuses what it must: traversal, foreign names, bad IDs,
malformed posts — each with a clean 4xx JSON error and nothing stored.

Requests go over a real socket with http.client, so paths reach the server
verbatim (no client-side normalisation of ``..``)."""
import http.client
import json
import os
import sqlite3

import pytest

from _site_names import site_name
from flipstudy.study.demo import make_demo_study
from flipstudy.study.server import ServerThread, create_app
from flipstudy.study.session import load_study, open_session


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    d = make_demo_study(tmp_path_factory.mktemp("sec") / "study", video_frames=6)
    (d / "secret.txt").write_text("experimenter only")
    (d.parent / "outside.mp4").write_bytes((d / "render" / "backflip_reference.mp4").read_bytes())
    session = open_session(load_study(d), "P01")
    with ServerThread(create_app(session)) as srv:
        yield d, session, srv
    session.close()


def request(srv, method, path, body=None, headers=None):
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=10)
    h = {"Host": f"127.0.0.1:{srv.port}"}
    if body is not None and not isinstance(body, bytes):
        body = json.dumps(body).encode()
        h["Content-Type"] = "application/json"
    h.update(headers or {})
    conn.request(method, path, body=body, headers=h)
    r = conn.getresponse()
    data = r.read()
    conn.close()
    return r.status, dict((k.lower(), v) for k, v in r.getheaders()), data


def counts(d):
    conn = sqlite3.connect(d / "sessions.sqlite")
    try:
        return tuple(conn.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0]
                     for t in ("responses", "demographics", "sessions", "trials"))
    finally:
        conn.close()


def video_url(d, stimulus):
    """The URL the page is given for ``stimulus``'s video (its opaque name)."""
    return f"/stimuli/{site_name(d, stimulus)}.mp4"


def good_answer(session, trial=1, **kw):
    """An answer as the page sends it (the trial's video by the page's name of it)."""
    body = {"participant": "P01", "session": 1, "trial": trial,
            "stimulus": site_name(session.study.dir, session.trials[trial - 1].stimulus), "response": "correct",
            "rt_ms": 500.0, "shown_ms": 200.0, "late_frames": 0}
    body.update(kw)
    return body


def assert_json_4xx(status, headers, data, expect=None):
    assert 400 <= status < 500, (status, data)
    if expect is not None:
        assert status == expect, (status, data)
    assert headers["content-type"].startswith("application/json")
    assert "error" in json.loads(data)


def test_serves_the_page_assets_and_manifest_videos(served):
    d, session, srv = served
    st, h, data = request(srv, "GET", "/")
    csp = h["content-security-policy"]
    assert st == 200 and b'src="flipstudy-web.js"' in data and "script-src 'self'" in csp
    assert "connect-src 'self';" in csp and "frame-ancestors 'none'" in csp and "https:" not in csp
    assert h["x-content-type-options"] == "nosniff"
    # the site export-web builds, in its local host mode: jsPsych from lib/, flipstudy's own files
    for asset, ctype in (("flipstudy-web.js", "text/javascript"), ("flipstudy-2afc.js", "text/javascript"),
                         ("flipstudy-web.css", "text/css"), ("config.js", "text/javascript")):
        st, h, data = request(srv, "GET", f"/{asset}")
        assert st == 200 and h["content-type"].startswith(ctype), asset
    assert b'"host": "local"' in request(srv, "GET", "/config.js")[2]


def test_serves_jspsych_from_lib(served):
    """jsPsych's bundles, read from npm's packages when first asked for (never a CDN)."""
    from flipstudy.study.web import jspsych as jsp
    try:
        folder, _ = jsp.fetch()
    except jsp.JsPsychFetchError as e:
        pytest.skip(f"npm could not fetch jsPsych: {e}")
    d, session, srv = served
    for asset, ctype in (("lib/jspsych.js", "text/javascript"), ("lib/jspsych.css", "text/css")):
        st, h, data = request(srv, "GET", f"/{asset}")
        assert st == 200 and h["content-type"].startswith(ctype), asset
    pkg, (src, _) = "jspsych", jsp.BUNDLES["jspsych"]
    assert data == (folder / "node_modules" / pkg / "css" / "jspsych.css").read_bytes()
    assert request(srv, "GET", "/lib/jspsych.js")[2] == (folder / "node_modules" / pkg / src).read_bytes()
    st, h, data = request(srv, "GET", video_url(d, "backflip_reference"))
    assert st == 200 and h["content-type"] == "video/mp4"
    assert data == (d / "render" / "backflip_reference.mp4").read_bytes()
    st, _, data = request(srv, "GET", "/api/session")
    tl = json.loads(data)
    assert tl["participant"] == "P01" and tl["n_trials"] == 8


TRAVERSAL = [
    "/stimuli/../manifest.csv",
    "/stimuli/../secret.txt",
    "/stimuli/%2e%2e/secret.txt",
    "/stimuli/%2E%2E%2Fsecret.txt",
    "/stimuli/..%2fsecret.txt",
    "/stimuli/..%2Fmanifest.csv",
    "/stimuli/....//secret.txt",
    "/stimuli/%2e%2e%2f%2e%2e%2fetc%2fpasswd",
    "/stimuli//etc/passwd",
    "/stimuli/%2Fetc%2Fpasswd",
    "/stimuli/render/backflip_reference.mp4",
    "/stimuli/backflip_reference.mp4",             # a stimulus's own name (the page's is opaque)
    "/stimuli/backflip_reference",                 # a manifest name without the video suffix
    "/stimuli/backflip_reference.bvh",
    "/stimuli/backflip_reference.mp4/",
    "/stimuli/backflip_reference.mp4%00.txt",
    "/stimuli/not_in_manifest.mp4",
    "/stimuli/BACKFLIP_REFERENCE.mp4",
    "/stimuli/",
    "/stimuli",
    "/static/",
    "/static/../server.py",
    "/static/%2e%2e/session.py",
    "/static/index.html/../../store.py",
    "/static/session.js/",
    "/static/flipstudy-web.js",
    "/index.html",
    "/config.js/",
    "/lib/",
    "/lib",
    "/lib/../config.js",
    "/lib/%2e%2e/config.js",
    "/lib/../../server.py",
    "/flipstudy-web.js/../../session.py",
    "/node_modules/jspsych/package.json",
    "/render/backflip_reference.mp4",
    "/manifest.csv",
    "/sessions.sqlite",
    "/design.toml",
    "/../secret.txt",
    "/%2e%2e/secret.txt",
    "/api/export",
    "/api/status",
    "/api/sessions",
    "/api/",
]


@pytest.mark.parametrize("path", TRAVERSAL)
def test_no_traversal_no_listing_no_experimenter_routes(served, path):
    d, session, srv = served
    st, h, data = request(srv, "GET", path)
    assert_json_4xx(st, h, data)
    assert b"experimenter only" not in data and b"stimulus,clip" not in data


def test_symlink_out_of_render_is_refused(served, tmp_path):
    d, session, srv = served
    video = d / "render" / "backflip_smooth-increase_0.mp4"
    saved = video.read_bytes()
    video.unlink()
    os.symlink(d.parent / "outside.mp4", video)
    try:
        assert_json_4xx(*request(srv, "GET", video_url(d, "backflip_smooth-increase_0")), expect=404)
    finally:
        video.unlink()
        video.write_bytes(saved)
    assert request(srv, "GET", video_url(d, "backflip_smooth-increase_0"))[0] == 200


def test_foreign_host_header_and_cross_origin_posts(served):
    d, session, srv = served
    before = counts(d)
    assert_json_4xx(*request(srv, "GET", "/api/session", headers={"Host": "evil.example"}), expect=400)
    assert_json_4xx(*request(srv, "POST", "/api/answer", good_answer(session),
                             headers={"Origin": "http://evil.example"}), expect=403)
    assert_json_4xx(*request(srv, "POST", "/api/answer", json.dumps(good_answer(session)).encode(),
                             headers={"Content-Type": "text/plain"}), expect=415)
    assert_json_4xx(*request(srv, "POST", "/api/answer", json.dumps(good_answer(session)).encode(),
                             headers={"Content-Type": "application/x-www-form-urlencoded"}), expect=415)
    assert_json_4xx(*request(srv, "GET", "/api/answer"), expect=405)
    assert_json_4xx(*request(srv, "PUT", "/api/answer", good_answer(session)), expect=405)
    assert counts(d) == before


def _malformed(session):
    good = good_answer(session)
    drop = lambda k: {x: v for x, v in good.items() if x != k}  # noqa: E731
    with_ = lambda **kw: {**good, **kw}                           # noqa: E731
    return {
        "not json": b"{trial: 1",
        "a list": b"[1, 2]",
        "a string": b'"correct"',
        "empty": b"",
        "NaN rt": json.dumps(good).replace('"rt_ms": 500.0', '"rt_ms": NaN').encode(),
        "Infinity shown": json.dumps(good).replace('"shown_ms": 200.0', '"shown_ms": Infinity').encode(),
        "1e999 rt": json.dumps(good).replace('"rt_ms": 500.0', '"rt_ms": 1e999').encode(),
        "huge int rt": json.dumps(good).replace('"rt_ms": 500.0', '"rt_ms": ' + "9" * 5000).encode(),
        "too large body": json.dumps(with_(pad="x" * 20000)).encode(),
        **{f"missing {k}": drop(k) for k in good},
        "unknown field": with_(admin=True),
        "response maybe": with_(response="maybe"),
        "response empty": with_(response=""),
        "response bool": with_(response=True),
        "response list": with_(response=["correct"]),
        "trial string": with_(trial="1"),
        "trial float": with_(trial=1.0),
        "trial bool": with_(trial=True),
        "trial 0": with_(trial=0),
        "trial negative": with_(trial=-1),
        "trial past the end": with_(trial=9),
        "trial huge": with_(trial=10 ** 30),
        "rt negative": with_(rt_ms=-1),
        "rt huge": with_(rt_ms=1e12),
        "rt string": with_(rt_ms="500"),
        "rt null": with_(rt_ms=None),
        "shown huge": with_(shown_ms=1e9),
        "shown negative": with_(shown_ms=-0.5),
        "late float": with_(late_frames=1.5),
        "late negative": with_(late_frames=-2),
        "late huge": with_(late_frames=10 ** 9),
        "replays not allowed": with_(replays=1),
        "input other": with_(input="telepathy"),
        "input simulated": with_(input="simulated"),
        "participant other": with_(participant="P02"),
        "participant bad": with_(participant="../P01"),
        "participant number": with_(participant=1),
        "session other": with_(session=2),
        "session string": with_(session="1"),
        "stimulus of another trial": with_(stimulus="backflip_reference"),
        "stimulus object": with_(stimulus={"a": 1}),
        "not the current trial": good_answer(session, trial=2),
    }


def test_malformed_answers_are_refused_and_nothing_is_stored(served):
    d, session, srv = served
    before = counts(d)
    for name, body in _malformed(session).items():
        headers = {"Content-Type": "application/json"} if isinstance(body, bytes) else None
        st, h, data = request(srv, "POST", "/api/answer", body, headers)
        assert 400 <= st < 500, (name, st, data)
        assert h["content-type"].startswith("application/json") and json.loads(data)["error"], name
        assert counts(d) == before, name


def test_malformed_demographics_are_refused(served):
    d, session, srv = served
    before = counts(d)
    good = {"participant": "P01", "session": 1, "age": 30, "gender": "woman",
            "animation_experience": "none", "gymnastics_experience": "none"}
    for bad in [{**good, "age": 5}, {**good, "age": "30"}, {**good, "age": 30.5}, {**good, "age": True},
                {**good, "gender": "x"}, {k: v for k, v in good.items() if k != "gender"},
                {**good, "animation_experience": None}, {**good, "participant": "P02"},
                {**good, "extra": 1}]:
        assert_json_4xx(*request(srv, "POST", "/api/demographics", bad))
    assert counts(d) == before


def test_a_good_answer_then_a_double_submit_then_a_conflict(served):
    d, session, srv = served
    r0 = counts(d)[0]
    n = r0 + 1
    body = good_answer(session, trial=n)
    st, _, data = request(srv, "POST", "/api/answer", body)
    assert st == 200 and json.loads(data)["status"] == "stored"
    st, _, data = request(srv, "POST", "/api/answer", body)
    assert st == 200 and json.loads(data)["status"] == "duplicate"
    st, h, data = request(srv, "POST", "/api/answer", {**body, "response": "incorrect"})
    assert_json_4xx(st, h, data, expect=409)
    assert counts(d)[0] == r0 + 1
    conn = sqlite3.connect(d / "sessions.sqlite")
    assert conn.execute("SELECT response FROM responses WHERE trial=?", (n,)).fetchone()[0] == "correct"
    conn.close()

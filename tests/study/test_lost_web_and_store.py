"""Issue 28, cases 4, 6 (corrupt database, deep JSON, folders, FIFOs) and 9.

Each test failed on the code before this change (checked): a web ID was taken
again by ``run``/``simulate`` and every later import failed; ``status`` and
``run`` on a damaged ``sessions.sqlite`` ended in an internal DatabaseError;
``import-web`` took a result file of another study name or site, kept a file of
duplicate records, said "no such file" for a folder, blocked on a FIFO and
raised RecursionError on deeply nested JSON.
"""
import hashlib
import json
import os
import shutil
import threading

import pytest

from flipstudy.errors import FlipstudyError
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import SessionError, load_study, open_session
from flipstudy.study.simulate import simulate
from flipstudy.study.web._fields import WebImportError
from flipstudy.study.web.importer import import_web
from flipstudy.study.web.sites import remember_site
from test_web_import import jsonl, run_records


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=2)


# --- 4: one participant-ID namespace -----------------------------------------------------------

def test_a_web_id_cannot_be_used_by_run_or_simulate_and_imports_go_on(study, tmp_path, capsys):
    import_web(study, [jsonl(tmp_path / "w.jsonl", run_records(study, "W01"))])
    with pytest.raises(SessionError, match="W01 has answers imported from the web"):
        open_session(load_study(study), "W01")                     # what `run` opens
    assert cli(["run", str(study), "--participant", "W01", "--no-browser"]) == 1
    assert "one participant-ID namespace" in capsys.readouterr().err
    # simulate's IDs too
    import_web(study, [jsonl(tmp_path / "s.jsonl", run_records(study, "sim002", run="r2"))])
    with pytest.raises(SessionError, match="sim002 has answers imported from the web"):
        simulate(study, 2, seed=1)
    from flipstudy.study.export import status
    assert "sim002" not in {r["participant"] for r in status(study)}
    # and the study still takes web results, and local IDs stay out of the web
    out = import_web(study, [jsonl(tmp_path / "w2.jsonl", run_records(study, "W02", run="r3"))])
    assert out.participants == 3
    open_session(load_study(study), "L01")
    with pytest.raises(WebImportError, match="L01 also has local sessions"):
        import_web(study, [jsonl(tmp_path / "l.jsonl", run_records(study, "L01", run="r4"))])


# --- 6: a damaged database ---------------------------------------------------------------------

def _damaged(good: bytes):
    yield "truncated", good[: len(good) // 2]
    yield "header only", good[:100]
    yield "garbage", bytes(range(256)) * 20
    yield "zeros", b"\0" * 8192
    yield "a page overwritten", good[:8192] + b"\xff" * 4096 + good[12288:]


def test_a_damaged_database_is_a_clear_error_and_is_never_touched(study, capsys):
    simulate(study, 2, seed=1)
    db = study / "sessions.sqlite"
    good = db.read_bytes()
    for what, data in _damaged(good):
        db.write_bytes(data)
        digest = hashlib.sha256(data).hexdigest()
        for argv in (["status", str(study)], ["run", str(study), "--participant", "P09", "--no-browser"],
                     ["export", str(study)], ["simulate", str(study), "--participants", "1"]):
            assert cli(argv) == 1, (what, argv)
            err = capsys.readouterr().err
            assert str(db) in err and "not a readable SQLite database" in err, (what, argv, err)
            assert "restore it from a backup" in err and "Traceback" not in err
            assert len(err.strip().splitlines()) == 1
        assert hashlib.sha256(db.read_bytes()).hexdigest() == digest, what
        assert sorted(p.name for p in study.glob("sessions.sqlite*")) == ["sessions.sqlite"], what
    db.write_bytes(good)
    assert cli(["status", str(study)]) == 0


# --- 9 and 6: import-web's inputs ---------------------------------------------------------------

def test_import_web_checks_the_study_name_and_the_site(study, tmp_path):
    recs = run_records(study, "W01")
    with pytest.raises(WebImportError, match="study 'another', but this is the study 'demo'"):
        import_web(study, [jsonl(tmp_path / "a.jsonl", [dict(r, study="another") for r in recs])])
    remember_site(study, "abc123", "jatos", tmp_path / "site", names="opaque")   # what export-web records
    with pytest.raises(WebImportError, match="site 's' was not exported from this study"):
        import_web(study, [jsonl(tmp_path / "b.jsonl", recs)])
    assert not (study / "web" / "responses.csv").exists()
    good = jsonl(tmp_path / "c.jsonl", [dict(r, site_id="abc123") for r in recs])
    design = study / "design.toml"
    text = design.read_text()
    design.write_text(text.replace("repetitions = 2", "repetitions = 2  # edited"))
    with pytest.raises(WebImportError, match="site abc123 was exported when .*design.toml was another"):
        import_web(study, [good])                      # a design edited after the export
    design.write_text(text)
    out = import_web(study, [good])
    assert out.answers == 8


def test_a_file_of_duplicate_records_is_not_kept(study, tmp_path):
    recs = run_records(study, "W01")
    import_web(study, [jsonl(tmp_path / "a.jsonl", recs)])
    kept = sorted((study / "web" / "imports").iterdir())
    table = (study / "web" / "responses.csv").read_bytes()
    big = jsonl(tmp_path / "dups.jsonl", recs * 300)                 # every record already kept
    out = import_web(study, [big])
    assert out.files[0].status == "nothing new" and out.files[0].new_answers == 0
    assert sorted((study / "web" / "imports").iterdir()) == kept    # not kept, so never re-read
    assert (study / "web" / "responses.csv").read_bytes() == table
    ledger = json.loads((study / "web" / "imports.json").read_text())
    assert [(e["file"], e.get("kept", True)) for e in ledger] == [(str(tmp_path / "a.jsonl"), True),
                                                                 (str(big), False)]
    # imported again: known by its hash, not read again
    again = import_web(study, [big])
    assert again.files[0].status == "already imported" and again.files[0].records == 0


def test_import_web_of_a_folder_a_fifo_or_deep_json(study, tmp_path, capsys):
    folder = tmp_path / "results"
    folder.mkdir()
    with pytest.raises(WebImportError, match="results: a folder; import-web takes the results files"):
        import_web(study, [folder])
    fifo = tmp_path / "pipe.jsonl"
    os.mkfifo(fifo)
    done = []
    t = threading.Thread(target=lambda: done.append(cli(["import-web", str(study), str(fifo)])),
                         daemon=True)
    t.start()
    t.join(30)
    assert done == [1], "import-web blocked on a FIFO"
    assert "not a regular file" in capsys.readouterr().err
    for name, text in (("deep.json", "[" * 100_000 + "]" * 100_000),
                       ("deep.jsonl", '{"a":' * 100_000 + "1" + "}" * 100_000)):
        p = tmp_path / name
        p.write_text(text)
        with pytest.raises(WebImportError, match="nested too deeply"):
            import_web(study, [p])
        assert cli(["import-web", str(study), str(p)]) == 1
        assert "nested too deeply" in capsys.readouterr().err
    assert not (study / "web").exists()

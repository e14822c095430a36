"""Issue 45, items 2, 5 and 10: one writer of a study at a time.

Every command that writes into a study holds ``STUDY/.locks/study.lock``
(:class:`flipstudy.study.lock.StudyLock`): while another process holds it, each
writer waits ``FLIPSTUDY_LOCK_WAIT`` seconds (here 0) and is refused in one line
naming the holder, having written nothing.  Two ``import-web`` or ``simulate``
commands started at once (processes) lose no participant and report what each
did; 30 between-subject sessions started at once fill the conditions evenly."""
import csv
import json
import re
import shutil
import threading

import pytest

from _prolific import web_records, write_jsonl
from _study_lock import held_elsewhere, run_together
from _site_names import nothing_imported

from flipstudy.errors import StudyInUseError
from flipstudy.study import pipeline, store
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study, open_session
from flipstudy.study.web.sites import remember_site

GROUPS = (("smooth-increase", "angular-momentum", "smooth", 1), ("abrupt-decrease", "angular-momentum", "abrupt", -1),
          ("takeoff-increase", "takeoff-angle", None, 1))
BETWEEN = [g[0] for g in GROUPS]


@pytest.fixture
def study(tmp_path):
    return make_demo_study(tmp_path / "study", videos=False)


@pytest.fixture
def wait0(monkeypatch):
    monkeypatch.setenv("FLIPSTUDY_LOCK_WAIT", "0")


def refused(capsys, argv, pid, holder="simulate"):
    """``flipstudy ARGV`` exits 1 with one line naming the holder."""
    status = cli([str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    assert status == 1 and len(err.splitlines()) == 1, err
    assert f"`flipstudy {holder}` (pid {pid}, since " in err and "is writing this study" in err, err
    assert f"`flipstudy {argv[0]}` waited 0 s for it (FLIPSTUDY_LOCK_WAIT)" in err, err
    return err


def tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


# ---- each writer holds the lock (fast) ---------------------------------------------------------

def test_import_web_waits_for_the_writer_of_the_study(study, tmp_path, capsys, wait0):
    f = write_jsonl(tmp_path / "w.jsonl", web_records(study, "W01"))
    with held_elsewhere(study) as pid:
        refused(capsys, ["import-web", study, f], pid)
    assert nothing_imported(study) and not (study / ".locks").exists()
    assert cli(["import-web", str(study), str(f)]) == 0                  # free again


def test_simulate_and_export_wait_for_the_writer_of_the_study(study, capsys, wait0):
    with held_elsewhere(study, "import-web") as pid:
        refused(capsys, ["simulate", study, "--participants", "1"], pid, "import-web")
    assert not (study / "sessions.sqlite").exists()
    pipeline.simulate(study, 1)
    with held_elsewhere(study, "import-web") as pid:
        refused(capsys, ["export", study, "--include-simulated"], pid, "import-web")
    assert not (study / "responses.csv").exists()


def test_run_creates_a_session_only_holding_the_lock(study, wait0):
    st = load_study(study)
    with held_elsewhere(study, "import-web") as pid:
        open_session(st, "P01", dry_run=True)                            # checks only: no lock
        with pytest.raises(StudyInUseError, match=rf"`flipstudy import-web` \(pid {pid}, since .*`flipstudy run` waited 0 s"):
            open_session(st, "P01")
    conn = store.connect(study)
    try:
        assert store.status_rows(conn) == []
    finally:
        conn.close()
    assert open_session(st, "P01").session == 1


def test_stimuli_render_init_archive_and_the_site_record_wait(study, tmp_path, capsys, wait0):
    design = tmp_path / "design.toml"
    shutil.copyfile(study / "design.toml", design)
    before = tree(study)
    with held_elsewhere(study) as pid:
        refused(capsys, ["stimuli", design, "--out", study, "--force", "--quiet"], pid)
        refused(capsys, ["render", study], pid)
        refused(capsys, ["init", study / "design.toml", "--force"], pid)
        refused(capsys, ["archive", study], pid)
        with pytest.raises(StudyInUseError, match=rf"\(pid {pid}, since .*`flipstudy export-web` waited 0 s"):
            remember_site(study, "site1", "static", tmp_path / "site")
        assert tree(study) == sorted(before + [".locks", ".locks/study.lock"])
    assert tree(study) == before                                        # the holder left no trace


def test_a_writer_waits_for_the_holder_then_runs(study, monkeypatch):
    from flipstudy.study.lock import StudyLock
    monkeypatch.setenv("FLIPSTUDY_LOCK_WAIT", "60")
    blocked, out = threading.Event(), []
    attempt = StudyLock._try_once

    def noting(self):
        got = attempt(self)
        if got is False:
            blocked.set()
        return got
    monkeypatch.setattr(StudyLock, "_try_once", noting)
    with held_elsewhere(study, "import-web"):
        t = threading.Thread(target=lambda: out.append(pipeline.simulate(study, 2)))
        t.start()
        assert blocked.wait(60)                   # it is waiting for the holder ...
        assert not (study / "sessions.sqlite").exists() and not out
    t.join(60)                                    # ... and runs once the holder has finished
    assert out and out[0].participants == ("sim001", "sim002")


def test_lock_wait_must_be_a_number_of_seconds(study, capsys, monkeypatch):
    monkeypatch.setenv("FLIPSTUDY_LOCK_WAIT", "-1")
    assert cli(["simulate", str(study), "--participants", "1"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "FLIPSTUDY_LOCK_WAIT='-1': expected the seconds" in err


# ---- item 5: simulate reports what it did ------------------------------------------------------

def test_simulate_reports_only_the_participants_it_simulated(study):
    assert pipeline.simulate(study, 2).participants == ("sim001", "sim002")
    res = pipeline.simulate(study, 3)
    assert res.participants == ("sim003",) and res.finished_before == ("sim001", "sim002")
    again = pipeline.simulate(study, 3)
    assert again.participants == () and again.finished_before == ("sim001", "sim002", "sim003")
    assert again.summary().startswith("simulated no participant in ") and "3 had finished already" in again.summary()


# ---- item 10: the condition counted where the session is created --------------------------------

def between_study(folder):
    return make_demo_study(folder, videos=False, levels=(0, 25), repetitions=1, groups=GROUPS,
                           extra=f"[online]\nbetween = {json.dumps(BETWEEN)}\n")


def counts_of(study_dir):
    conn = store.connect(study_dir)
    try:
        return store.condition_counts(conn, BETWEEN, "browser")
    finally:
        conn.close()


def test_between_condition_counted_inside_the_creating_transaction(tmp_path, monkeypatch):
    st = load_study(between_study(tmp_path / "b"))
    seen, count = [], store.condition_counts

    def counting(conn, conditions, source):
        seen.append(conn.in_transaction)
        return count(conn, conditions, source)
    monkeypatch.setattr(store, "condition_counts", counting)
    for i in range(3):
        open_session(st, f"P{i}")
    assert seen == [True, True, True]
    assert set(counts_of(st.dir).values()) == {1}


# ---- concurrency, as processes and threads (slow) ----------------------------------------------

def table_ids(path, column="participant"):
    with open(path, newline="") as f:
        return {r[column] for r in csv.DictReader(f)}


@pytest.mark.slow
def test_two_imports_at_once_lose_no_participant(tmp_path):
    study = make_demo_study(tmp_path / "study", videos=False)
    base = []
    for i in range(300):
        base += web_records(study, f"W{i:03d}", run=f"w{i}")
    assert cli(["import-web", str(study), str(write_jsonl(tmp_path / "base.jsonl", base))]) == 0
    n_trials = len(web_records(study, "X")) - 2                          # start, answers, end
    expected = {f"W{i:03d}" for i in range(300)}
    web = study / "web"
    for rnd in range(10):
        a, b = f"A{rnd:02d}", f"B{rnd:02d}"
        files = [write_jsonl(tmp_path / f"{p}.jsonl", web_records(study, p, run=f"r{p}")) for p in (a, b)]
        res = run_together(["import-web", study, files[0]], ["import-web", study, files[1]])
        assert [r[0] for r in res] == [0, 0], [r[2] for r in res]
        expected |= {a, b}
        new = [int(m) for _, so, _ in res for m in re.findall(r"(\d+) new answers", so)]
        assert sum(new) == 2 * n_trials, (rnd, [r[1] for r in res])      # each counted once
        assert table_ids(web / "responses.csv") == expected, rnd
        assert table_ids(web / "participants.csv") == expected, rnd
        data = sorted((web / "data").glob("*_data.csv"))
        assert len(data) == 2 and all(table_ids(p) == expected for p in data), rnd
        last = [int(m) for m in re.findall(r"(\d+) answers of", res[0][1] + res[1][1])]
        assert max(last) == len(expected) * n_trials, rnd


@pytest.mark.slow
def test_two_simulates_at_once_both_succeed_and_report_their_own(tmp_path):
    for rnd in range(10):
        study = make_demo_study(tmp_path / f"s{rnd}", videos=False, repetitions=2)
        res = run_together(["simulate", study, "--participants", "9"],
                           ["simulate", study, "--participants", "9"])
        assert [r[0] for r in res] == [0, 0], (rnd, [r[2] for r in res])
        counts = [int(m.group(1)) if m else 0 for m in
                  (re.match(r"simulated (\d+) participant", so) for _, so, _ in res)]
        assert sum(counts) == 9, (rnd, [r[1] for r in res])
        conn = store.connect(study)
        try:
            rows = store.status_rows(conn)
        finally:
            conn.close()
        assert len(rows) == 9 and all(r["complete"] and r["finished"] for r in rows), rnd


@pytest.mark.slow
def test_thirty_between_subject_starts_at_once_fill_the_conditions_evenly(tmp_path):
    for rnd in range(10):
        st = load_study(between_study(tmp_path / f"b{rnd}"))
        go, errors = threading.Barrier(30), []

        def start(i):
            try:
                go.wait()
                open_session(st, f"P{i:02d}")
            except Exception as e:                # noqa: BLE001 (reported below)
                errors.append(e)
        threads = [threading.Thread(target=start, args=(i,)) for i in range(30)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        assert not errors, errors
        counts = counts_of(st.dir)
        assert sum(counts.values()) == 30 and max(counts.values()) - min(counts.values()) <= 1, (rnd, counts)

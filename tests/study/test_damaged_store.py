"""Issue 45, item 4: a damaged ``sessions.sqlite`` is never taken for "no answers".

Before this change (checked by checking out the code before it): after ``DROP TABLE
sessions`` the store counted as holding no answers, so ``stimuli --force`` deleted 30
readable real answers, and ``status`` ended in a traceback; across damage kinds ×
commands there were tracebacks (a folder, a symbolic link to ``/dev/zero``, a dangling
link, a missing table).  Now every command names the file (and the table or column)
in one line and leaves the file as it was.
"""
import hashlib
import os
import shutil
import sqlite3

import pytest

from flipstudy.errors import FlipstudyError
from flipstudy.study.cli import main as cli
from flipstudy.study.demo import make_demo_study
from flipstudy.study.session import load_study, open_session, submit_answer
from flipstudy.study.simulate import simulate
from test_web_import import jsonl, run_records


def answer(study, pid, n):
    s = open_session(load_study(study), pid)
    for t in s.trials[:n]:
        submit_answer(s, {"participant": pid, "session": s.session, "trial": t.trial,
                          "stimulus": t.stimulus, "response": "correct", "rt_ms": 500.0,
                          "shown_ms": 900.0, "late_frames": 0})
    s.close()
    return min(n, len(s.trials))


def drop(db, table):
    conn = sqlite3.connect(db)
    conn.execute(f"DROP TABLE {table}")
    conn.commit()
    conn.close()


def tree(folder):
    """Every entry below ``folder`` → its bytes' SHA-256 (links: their target)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        out[rel] = (f"-> {os.readlink(p)}" if p.is_symlink() else "dir" if p.is_dir()
                    else hashlib.sha256(p.read_bytes()).hexdigest())
    return out


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture
def study(tmp_path):
    st = make_demo_study(tmp_path / "st", videos=False, levels=(0, 25), repetitions=3)   # 12 trials
    assert sum(answer(st, pid, 10) for pid in ("P01", "P02", "P03")) == 30
    return st


@pytest.mark.parametrize("table", ["sessions", "responses"])
def test_a_store_missing_a_table_is_never_no_answers(study, table, capsys):
    db = study / "sessions.sqlite"
    drop(db, table)
    before = tree(study)
    capsys.readouterr()
    assert cli(["stimuli", str(study / "design.toml"), "--out", str(study), "--force", "--quiet"]) == 1
    line = one_line(capsys.readouterr().err)
    assert "sessions.sqlite" in line and f"table {table} is missing" in line
    assert tree(study) == before                    # the 30 answers are still there
    assert cli(["status", str(study)]) == 1
    line = one_line(capsys.readouterr().err)
    assert str(db) in line and f"table {table} is missing" in line
    assert tree(study) == before


@pytest.mark.parametrize("kind", ["a folder", "a link to /dev/zero", "a dangling link"])
def test_status_names_a_store_that_is_not_a_file(study, kind, capsys):
    db = study / "sessions.sqlite"
    db.unlink()
    for side in study.glob("sessions.sqlite-*"):
        side.unlink()
    if kind == "a folder":
        db.mkdir()
    else:
        db.symlink_to("/dev/zero" if "zero" in kind else study / "gone.sqlite")
    capsys.readouterr()
    assert cli(["status", str(study)]) == 1
    assert str(db) in one_line(capsys.readouterr().err)
    assert not (study / "gone.sqlite").exists()


# --- the table: damage kinds × commands (slow) -------------------------------------------------

def _sql(*stmts):
    def f(db):
        conn = sqlite3.connect(db)
        for s in stmts:
            conn.execute(s)
        conn.commit()
        conn.close()
    return f


def _replace(make):
    def f(db):
        db.unlink()
        make(db)
    return f


DAMAGE = {
    "no sessions table": _sql("DROP TABLE sessions"),
    "no responses table": _sql("DROP TABLE responses"),
    "no trials table": _sql("DROP TABLE trials"),
    "no meta table": _sql("DROP TABLE meta"),
    "a renamed column": _sql("ALTER TABLE responses RENAME COLUMN response TO answer"),
    "another program's database": _replace(lambda db: _sql("CREATE TABLE notes (x)")(db)),
    "a newer schema": _sql("PRAGMA user_version = 99"),
    "truncated": lambda db: db.write_bytes(db.read_bytes()[: db.stat().st_size // 3]),
    "the header only": lambda db: db.write_bytes(db.read_bytes()[:100]),
    "garbage": lambda db: db.write_bytes(bytes(range(256)) * 40),
    "a folder": _replace(lambda db: db.mkdir()),
    "a link to /dev/zero": _replace(lambda db: db.symlink_to("/dev/zero")),
    "a dangling link": _replace(lambda db: db.symlink_to(db.parent / "elsewhere" / "gone.sqlite")),
    "no permission": lambda db: db.chmod(0),
}

#: the commands that read or write the store: each must refuse, naming it
COMMANDS = {
    "status": ["status", "{st}"],
    "stimuli --force": ["stimuli", "{st}/design.toml", "--out", "{st}", "--force", "--quiet"],
    "render": ["render", "{st}", "--quiet"],
    "simulate": ["simulate", "{st}", "--participants", "1"],
    "export": ["export", "{st}"],
    "import-web": ["import-web", "{st}", "{results}"],
    "init --force": ["init", "{st}/design.toml", "--force"],
    "analyze": ["analyze", "{st}"],
}
#: the commands that never open the store (analyze reads the exported tables): one line
READS_NO_STORE = {"analyze"}


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A built study (stimuli with .bvh files, stale placeholder videos so that `render`
    would replace them) with real and simulated answers, and a web result file."""
    root = tmp_path_factory.mktemp("damaged")
    demo = make_demo_study(root / "demo", levels=(0, 25), repetitions=2)
    st = root / "base"
    assert cli(["stimuli", str(demo / "design.toml"), "--out", str(st), "--quiet"]) == 0
    shutil.copytree(demo / "render", st / "render")
    answer(st, "P01", 3)
    simulate(st, 1, seed=1)
    results = jsonl(root / "w.jsonl", run_records(st, "W01"))
    for side in st.glob("sessions.sqlite-*"):
        side.unlink()
    return st, results


def _case(base, tmp_path, kind):
    st = tmp_path / "st"
    shutil.copytree(base, st, symlinks=True)
    DAMAGE[kind](st / "sessions.sqlite")
    return st


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file without permission")
def test_no_permission_is_named(base, tmp_path, capsys):
    st = _case(base[0], tmp_path, "no permission")
    assert cli(["status", str(st)]) == 1
    assert "sessions.sqlite" in one_line(capsys.readouterr().err)


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("kind", sorted(k for k in DAMAGE if k != "no permission"))
def test_every_command_on_every_damage_is_one_line(base, tmp_path, kind, command, capsys):
    st = _case(base[0], tmp_path, kind)
    before = tree(st)
    capsys.readouterr()
    argv = [a.format(st=st, results=base[1]) for a in COMMANDS[command]]
    code = cli(argv)
    captured = capsys.readouterr()
    line = one_line(captured.err)
    assert code == 1, (kind, command, captured.out)
    if command in READS_NO_STORE:
        assert str(st) in line, line
    elif "table" in kind or "column" in kind:
        assert "sessions.sqlite" in line and ("table" in line or "column" in line), line
    else:
        assert "sessions.sqlite" in line, line
    after = tree(st)
    assert {k: v for k, v in after.items() if not k.startswith("sessions.sqlite-")} == \
        {k: v for k, v in before.items()}, (kind, command)    # nothing replaced, nothing deleted


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(k for k in DAMAGE if k != "no permission"))
def test_run_session_creation_and_archive_on_every_damage(base, tmp_path, kind):
    st = _case(base[0], tmp_path, kind)
    before = tree(st)
    with pytest.raises(FlipstudyError) as e:             # what `run` does for a new participant
        open_session(load_study(st), "P09")
    assert "sessions.sqlite" in str(e.value) and "\n" not in str(e.value)
    assert tree(st) == before
    assert cli(["archive", str(st)]) == 0                 # archive moves everything, as it was
    moved = [p for p in tmp_path.iterdir() if p.name.startswith("st-archived-")]
    assert len(moved) == 1 and tree(moved[0]) == before

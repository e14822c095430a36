"""`flipstudy status` lists the participants import-web imported beside the local
sessions (issue 42)."""
import json

from flipstudy.study.cli import main
from flipstudy.study.demo import make_demo_study
from flipstudy.study.web.importer import import_web

from test_web_import import jsonl, run_records


def test_status_lists_imported_web_participants(tmp_path, capsys):
    study = make_demo_study(tmp_path / "study", videos=False, levels=(0, 25), repetitions=2)
    import_web(study, [jsonl(tmp_path / "w1.jsonl", run_records(study, "W01")),
                       jsonl(tmp_path / "w2.jsonl", run_records(study, "W02", run="r2", n=3))])
    assert main(["simulate", str(study), "--participants", "1"]) == 0
    capsys.readouterr()
    assert main(["status", str(study)]) == 0
    out = capsys.readouterr().out
    lines = {ln.split()[0]: ln for ln in out.splitlines() if ln.startswith(("W0", "sim"))}
    assert set(lines) == {"W01", "W02", "sim001"}
    assert "web-jatos" in lines["W01"] and "8/8" in lines["W01"]
    assert "3/8" in lines["W02"] and "INCOMPLETE" in lines["W02"]
    assert "2 real participant(s) (2 imported from the web" in out
    assert main(["status", str(study), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    w01 = next(r for r in rows if r["participant"] == "W01")
    assert w01["complete"] and not w01["simulated"] and w01["answered"] == w01["total"] == 8

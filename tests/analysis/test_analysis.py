"""analysis: ratings, d′, corrections, bootstrap, GEE, psychometric fits, tables, figures, CLI."""
from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from flipstudy import FlipstudyError
from flipstudy import analysis
from flipstudy.analysis import analyze, corrected_rate, criterion, dprime, load_responses, summarize
from flipstudy.study.cli import main
from flipstudy.analysis.simulate import PAPER_TABLE2, paper_panel, sdt_observers
from flipstudy.analysis.stats import detection_threshold, fit_psychometric, gee_levels, psychometric_curve
from flipstudy.analysis.tables import fmt_cell, fmt_dprime, paper_layout, to_latex, to_markdown

ROOT = Path(__file__).resolve().parents[2]


def make_responses(cells: dict, n_participants: int = 4, groups_extra: dict | None = None) -> pd.DataFrame:
    """Trials with exact counts: cells maps (group, level) -> (n_incorrect, n_trials); trials
    are dealt round-robin to participants."""
    rows = []
    t = 0
    for (g, lv), (k, n) in cells.items():
        for i in range(n):
            t += 1
            rows.append({"participant": f"P{i % n_participants + 1}", "session": "S1", "trial": t,
                         "stimulus": f"{g}_{lv}", "group": g, "level": lv, "repetition": 1 + i // 50,
                         "response": "incorrect" if i < k else "correct", "rt_ms": 1000,
                         "shown_ms": 2400, "timestamp": "2026-01-01T10:00:00"})
    return pd.DataFrame(rows)


def row(table, group, level):
    r = table[(table["group"] == group) & (table["level"] == level)]
    assert len(r) == 1
    return r.iloc[0]


# ------------------------------------------------------------------ d′ by hand

def test_pooled_dprime_matches_hand_computation():
    # original 72 % correct (28 of 100 incorrect), level 50: 41 % correct (59 of 100 incorrect)
    df = make_responses({("smooth-increase", 0): (28, 100), ("smooth-increase", 50): (59, 100),
                         ("smooth-increase", 25): (28, 100)})
    table, _, _ = summarize(load_responses(df), n_boot=200)
    H, F = 59 / 100, 28 / 100
    r = row(table, "smooth-increase", 50)
    assert r["rating_pct"] == pytest.approx(41.0, abs=1e-12)
    assert r["n"] == 100 and r["n_incorrect"] == 59
    assert abs(r["dprime"] - (norm.ppf(H) - norm.ppf(F))) < 1e-9
    assert abs(r["criterion"] - (-(norm.ppf(H) + norm.ppf(F)) / 2)) < 1e-9
    assert not r["corrected"] and r["correction"] == "loglinear"
    assert abs(r["dprime"] - 0.81) < 0.005                     # the paper's (.81)
    o = row(table, "smooth-increase", 0)
    assert o["dprime"] == 0.0 and o["rating_pct"] == pytest.approx(72.0)
    assert abs(o["criterion"] + norm.ppf(F)) < 1e-9
    assert row(table, "smooth-increase", 25)["dprime"] == 0.0


def test_dprime_function_and_vectorised():
    assert abs(dprime(59, 100, 28, 100) - (norm.ppf(.59) - norm.ppf(.28))) < 1e-12
    assert abs(criterion(59, 100, 28, 100) + (norm.ppf(.59) + norm.ppf(.28)) / 2) < 1e-12
    d = dprime(np.array([59, 28, 10]), 100, 28, 100)
    assert d.shape == (3,) and d[1] == 0 and d[2] < 0          # negative sensitivity is kept
    with pytest.raises(ValueError, match="correction"):
        dprime(1, 2, 1, 2, correction="bogus")
    with pytest.raises(ValueError, match="counts"):
        dprime(3, 2, 1, 2)


@pytest.mark.parametrize("k,expected_ll,expected_half", [(0, 0.5 / 21, 1 / 40), (20, 20.5 / 21, 39 / 40)])
def test_corrections_textbook_values(k, expected_ll, expected_half):
    assert corrected_rate(k, 20, "loglinear") == pytest.approx(expected_ll, abs=1e-15)
    assert corrected_rate(k, 20, "1/(2N)") == pytest.approx(expected_half, abs=1e-15)
    assert corrected_rate(k, 20, "1/2N") == pytest.approx(expected_half, abs=1e-15)   # alias
    assert corrected_rate(7, 20, "1/(2N)") == 7 / 20                                   # not extreme: unchanged


def test_corrections_in_the_table():
    # original 5/20 incorrect; level 40 all 20 judged incorrect (H = 1); level 10 none (H = 0)
    cells = {("g", 0): (5, 20), ("g", 40): (20, 20), ("g", 10): (0, 20)}
    df = load_responses(make_responses(cells))
    t_ll, _, notes = summarize(df, correction="loglinear", n_boot=100)
    t_h, _, _ = summarize(df, correction="1/(2N)", n_boot=100)
    r = row(t_ll, "g", 40)
    assert r["corrected"] and r["correction"] == "loglinear"
    assert abs(r["dprime"] - (norm.ppf(20.5 / 21) - norm.ppf(5.5 / 21))) < 1e-9
    assert abs(row(t_ll, "g", 10)["dprime"] - (norm.ppf(0.5 / 21) - norm.ppf(5.5 / 21))) < 1e-9
    r = row(t_h, "g", 40)
    assert r["corrected"] and r["correction"] == "1/(2N)"
    assert abs(r["dprime"] - (norm.ppf(39 / 40) - norm.ppf(5 / 20))) < 1e-9
    assert abs(row(t_h, "g", 10)["dprime"] - (norm.ppf(1 / 40) - norm.ppf(5 / 20))) < 1e-9
    assert any("log-linear" in n and "Hautus" in n for n in notes)
    assert np.isfinite(t_ll[["dprime", "criterion", "dprime_mean_participants"]].to_numpy(float)).all()


def test_reproduces_paper_table2_from_its_ratings():
    """Feeding the paper's ratings as exact counts (100 trials a cell) gives back its d′ column."""
    cells = {}
    for g, t in PAPER_TABLE2.items():
        for lv, r in zip(t["levels"], t["rating"]):
            if r is not None:
                cells[(g, lv)] = (100 - r, 100)
    table, _, _ = summarize(load_responses(make_responses(cells, n_participants=10)), n_boot=100)
    for g, t in PAPER_TABLE2.items():
        for lv, r, d in zip(t["levels"], t["rating"], t["dprime"]):
            if r is None:
                continue
            got = row(table, g, lv)
            assert got["rating_pct"] == pytest.approx(r)
            assert got["dprime"] == pytest.approx(d, abs=0.055), (g, lv)   # paper: rounded ratings, 1-2 decimals
    lay = paper_layout(table).set_index("group")
    assert lay.loc["smooth-decrease", "17 %"] == "79 (-.22)"
    assert lay.loc["smooth-increase", "50 %"] == "41 (.81)"
    assert lay.loc["abrupt-decrease", "0 %"] == "72 (.00)"
    assert lay.loc["takeoff-increase", "10 %"] == "81 (-.55)"      # paper: (−.53) from unrounded ratings
    assert lay.loc["takeoff-increase", "17 %"] == ""                # level not tested by that group


# ------------------------------------------------------------- parameter recovery

TRUE_D = {10: 0.3, 20: 0.6, 30: 1.0, 40: 1.5}


def test_parameter_recovery_bootstrap_coverage():
    """Equal-variance Gaussian observers (fixed criterion location 0.6) with known d′: the true
    value lies inside the reported 95 % bootstrap interval in at least 90 % of 20 fixed seeds,
    for each level and for both intervals (mean of the participants' d′, pooled d′).
    (Over 400 seeds the measured coverage is 0.935–0.96 for both.)"""
    hits = {lv: [0, 0] for lv in TRUE_D}
    for seed in range(20):
        df = sdt_observers(TRUE_D, n_participants=40, trials_per_level=100, criterion_location=0.6,
                           seed=1000 + seed)
        table, _, _ = summarize(load_responses(df), n_boot=1000, seed=seed)
        for lv, d in TRUE_D.items():
            r = row(table, "simulated", lv)
            hits[lv][0] += r["dprime_ci_low"] <= d <= r["dprime_ci_high"]
            hits[lv][1] += r["dprime_pooled_ci_low"] <= d <= r["dprime_pooled_ci_high"]
            assert abs(r["dprime"] - d) < 0.2 and abs(r["dprime_mean_participants"] - d) < 0.2
    for lv, (a, b) in hits.items():
        assert a >= 18 and b >= 18, (lv, a, b)


def test_bootstrap_is_seeded():
    df = load_responses(paper_panel(12, seed=3))
    a, _, _ = summarize(df, n_boot=300, seed=5)
    b, _, _ = summarize(df, n_boot=300, seed=5)
    c, _, _ = summarize(df, n_boot=300, seed=6)
    pd.testing.assert_frame_equal(a, b)
    assert not np.allclose(a["dprime_ci_low"].to_numpy(), c["dprime_ci_low"].to_numpy(), equal_nan=True)


def test_negative_dprime_kept_and_per_participant_table():
    cells = {("g", 0): (40, 80), ("g", 20): (20, 80)}
    table, part, _ = summarize(load_responses(make_responses(cells)), n_boot=100)
    assert row(table, "g", 20)["dprime"] < 0
    assert row(table, "g", 20)["dprime_mean_participants"] < 0
    assert set(part.columns) >= {"participant", "group", "level", "dprime", "n", "n_incorrect"}
    assert len(part) == 4 * 2


# --------------------------------------------------------------------- input

def test_reference_rows_ignored_and_any_group_names(tmp_path):
    df = make_responses({("wobble", 0): (3, 12), ("wobble", 5): (9, 12), ("reference", 0): (0, 12)})
    df["clip"] = "x"
    df["late_frames"] = 0
    table, _, _ = summarize(load_responses(df), n_boot=100)
    assert list(table["group"].unique()) == ["wobble"]


def test_input_errors_name_file_line_and_expectation(tmp_path):
    df = make_responses({("g", 0): (1, 4), ("g", 10): (2, 4)})
    df.loc[2, "response"] = "maybe"
    p = tmp_path / "r.csv"
    df.to_csv(p, index=False)
    with pytest.raises(analysis.ResponsesError, match=r"r\.csv: line 4: response 'maybe'"):
        load_responses(p)
    with pytest.raises(analysis.ResponsesError, match="missing column.*response"):
        load_responses(df.drop(columns="response"))
    with pytest.raises(analysis.NeedsExportError, match="flipstudy export"):
        load_responses(tmp_path)


def test_group_without_original_gives_a_note_not_a_crash():
    df = make_responses({("g", 0): (3, 12), ("g", 10): (6, 12), ("h", 10): (6, 12), ("h", 20): (8, 12)})
    table, _, notes = summarize(load_responses(df), n_boot=100)
    assert np.isnan(row(table, "h", 10)["dprime"])
    assert any("No original" in n and "h" in n for n in notes)
    g = gee_levels(load_responses(df))
    assert g[g["group"] == "h"]["gee_note"].str.contains("no original").all()


# ---------------------------------------------------------------------- GEE

def test_gee_on_paper_panel():
    df = load_responses(paper_panel(19, seed=11))
    g = gee_levels(df)
    assert len(g) == 20 and set(g["group"]) == set(PAPER_TABLE2)
    strong = g[(g["group"] == "abrupt-decrease") & (g["level"] == 50)].iloc[0]
    assert strong["gee_or"] > 2 and strong["gee_ci_low"] > 1 and strong["gee_p"] < 0.001
    assert (g["gee_p_holm"] >= g["gee_p"] - 1e-15).all()
    assert ((g["gee_ci_low"] <= g["gee_or"]) & (g["gee_or"] <= g["gee_ci_high"])).all()


def test_gee_degenerate_data_does_not_crash():
    df = make_responses({("g", 0): (0, 20), ("g", 10): (0, 20), ("g", 20): (20, 20)})
    g = gee_levels(load_responses(df))
    assert len(g) == 2
    assert g["gee_note"].str.len().gt(0).all()


# ------------------------------------------------------------ psychometric fits

def test_detection_threshold_definition_matches_psignifit_sigmoid():
    Gaussian = pytest.importorskip("psignifit.sigmoids").Gaussian
    m, w, gam, lam = 30.0, 20.0, 0.25, 0.05
    x = detection_threshold(m, w, gam, lam)
    assert psychometric_curve(x, m, w, gam, lam) == pytest.approx((1 + gam) / 2, abs=1e-12)
    assert x == pytest.approx(Gaussian().inverse((1 + gam) / 2, m, w, gam, lam), abs=1e-9)
    assert detection_threshold(m, w, 0.3, 0.4) == np.inf             # never climbs to (1 + γ)/2


def _curve_counts(m, w, gam, lam, x, n):
    p = psychometric_curve(x, m, w, gam, lam)
    return np.round(p * n)


def test_psignifit_fit_and_flat_group():
    pytest.importorskip("psignifit")
    x = np.array([0, 17, 25, 37, 50.0])
    n = np.full(5, 76.0)
    truth = detection_threshold(32, 15, 0.25, 0.0)
    from flipstudy.analysis.stats import fit_psignifit
    f = fit_psignifit("steep", x, _curve_counts(32, 15, 0.25, 0.0, x, n), n, seed=0)
    assert f.method == "psignifit" and f.reached
    assert f.ci_low <= truth <= f.ci_high and abs(f.threshold - truth) < 6
    flat = fit_psignifit("flat", x, np.array([21.0, 16, 17, 16, 20]), n, seed=0)
    assert not flat.reached and np.isnan(flat.threshold)


def test_fit_psychometric_skips_single_level_group():
    df = load_responses(make_responses({("one", 0): (3, 12), ("two", 0): (3, 40), ("two", 30): (30, 40)}))
    fits, notes = fit_psychometric(df, "psignifit", seed=0)
    assert [f.group for f in fits] == ["two"]
    assert any("one" in n for n in notes)


def test_fit_psychometric_refuses_an_unknown_method_naming_the_valid_ones():
    df = load_responses(make_responses({("two", 0): (3, 40), ("two", 30): (30, 40)}))
    assert fit_psychometric(df, "none") == ([], [])
    with pytest.raises(FlipstudyError, match="expected psignifit or none.*one fit"):
        fit_psychometric(df, "mle")                  # the own maximum-likelihood fit is gone


# -------------------------------------------------------------------- tables

def test_paper_formatting():
    assert fmt_dprime(0.0) == ".00" and fmt_dprime(-0.001) == ".00"
    assert fmt_dprime(0.05) == ".05" and fmt_dprime(-0.22) == "-.22"
    assert fmt_dprime(1.4) == "1.40" and fmt_dprime(-1.026) == "-1.03"
    assert fmt_cell(72, 0.0) == "72 (.00)" and fmt_cell(41.4, 0.8114) == "41 (.81)"
    assert fmt_cell(62.5, 0.27) == "63 (.27)"
    assert fmt_cell(float("nan"), 0.1) == "—"


def test_markdown_and_latex_layout():
    cells = {("smooth-increase", 0): (28, 100), ("smooth-increase", 17): (21, 100),
             ("takeoff-increase", 0): (37, 100), ("takeoff-increase", 10): (19, 100)}
    table, _, _ = summarize(load_responses(make_responses(cells)), n_boot=50)
    md = to_markdown(table)
    assert "| smooth-increase | 72 (.00) | 79 (−.22) |" in md
    assert md.count("| group |") == 2                           # one block per level set
    tex = to_latex(table, caption="Ratings & d′")
    for s in (r"\toprule", r"\midrule", r"\bottomrule", r"\cmidrule", "79 ($-$.22)", r"Ratings \& $d'$",
              r"17 \%"):
        assert s in tex
    assert tex.isascii()                         # pdflatex without packages (was U+2032)


# ------------------------------------------------------------------ pipeline

@pytest.fixture(scope="module")
def paper_csv(tmp_path_factory):
    csv = tmp_path_factory.mktemp("analysis") / "responses.csv"
    paper_panel(19, seed=7).to_csv(csv, index=False)
    return csv


@pytest.fixture(scope="module")
def paper_run(paper_csv):
    csv = paper_csv
    out = csv.parent
    img = out / "ghost.png"
    from matplotlib.figure import Figure
    fig = Figure(figsize=(2, 1.5))
    fig.add_subplot().plot([0, 1], [0, 1])
    fig.savefig(img, dpi=60)
    res = analyze(csv, out / "run1", psychometric="psignifit", n_boot=500, seed=3,
                  images={"ghost original": img, "trail original": out / "missing.png"})
    return out, csv, res


@pytest.mark.slow
def test_analyze_writes_everything(paper_run):
    out, csv, res = paper_run
    names = {"table.csv", "table_paper.csv", "table_paper.md", "table_paper.tex", "participants.csv",
             "levels_vs_original.csv", "thresholds.csv", "notes.md", "summary.json"}
    for fig in ("ratings", "dprime", "psychometric", "sheet"):
        names |= {f"{fig}.pdf", f"{fig}.png"}
    assert names <= set(res.files)
    for p in res.files.values():
        assert Path(p).is_file() and Path(p).stat().st_size > 0
    t = pd.read_csv(res.files["table.csv"])
    need = {"group", "level", "n", "rating_pct", "dprime", "criterion", "dprime_mean_participants",
            "dprime_ci_low", "dprime_ci_high", "correction", "gee_or", "gee_p"}
    assert need <= set(t.columns) and len(t) == 25
    assert (t["correction"] == "loglinear").all()
    s = json.loads(res.files["summary.json"].read_text())
    assert s["settings"]["correction"] == "loglinear" and len(s["table"]) == 25
    assert any("missing.png" in n for n in res.notes)
    assert "Correction for rates of 0 or 1" in res.files["notes.md"].read_text()
    assert len(res.thresholds) == 5 and {"threshold", "threshold_ci_low", "threshold_ci_high",
                                         "reached", "note"} <= set(res.thresholds.columns)


@pytest.mark.slow
def test_analyze_is_byte_identical_for_a_seed(paper_run, tmp_path):
    out, csv, res = paper_run
    again = analyze(csv, tmp_path, psychometric="psignifit", n_boot=500, seed=3, figures=False)
    for name in ("table.csv", "thresholds.csv", "table_paper.tex", "participants.csv"):
        assert Path(again.files[name]).read_bytes() == Path(res.files[name]).read_bytes(), name
    from flipstudy.analysis.figures import ratings_figure, save
    from flipstudy.analysis.pipeline import _labelled                 # figures say which participants
    for p in save(_labelled(ratings_figure(again.table), again.settings["participants_label"]),
                  tmp_path / "ratings"):
        assert p.read_bytes() == Path(res.files[p.name]).read_bytes(), p.name


def test_analyze_is_byte_identical_for_a_seed_on_a_small_panel(tmp_path):
    """The default run's twin of the slow test above: the bootstrap intervals and
    tables of two runs with one seed are the same bytes, another seed moves them."""
    df = paper_panel(8, seed=2)
    runs = [analyze(df, tmp_path / f"s{seed}-{i}", psychometric="none", gee=False, n_boot=200,
                    seed=seed, figures=False) for seed, i in ((3, 0), (3, 1), (4, 0))]
    for name in ("table.csv", "table_paper.tex", "participants.csv"):
        assert Path(runs[0].files[name]).read_bytes() == Path(runs[1].files[name]).read_bytes(), name
    assert Path(runs[0].files["table.csv"]).read_bytes() != Path(runs[2].files["table.csv"]).read_bytes()


def test_analyze_without_images_and_without_figures(tmp_path):
    df = paper_panel(8, seed=2)
    res = analyze(df, tmp_path / "a", psychometric="none", gee=False, n_boot=100)
    assert "sheet.png" in res.files and any("no images" in n for n in res.notes)
    res = analyze(df, tmp_path / "b", psychometric="none", gee=False, n_boot=100, figures=False)
    assert not any(str(k).endswith(".png") for k in res.files)


# ----------------------------------------------------------------------- CLI

def run_cli(argv):
    """``flipstudy analyze ...`` as the command line runs it: ``main()`` reports the errors."""
    return main(argv)


def test_cli_csv_json(paper_csv, tmp_path, capsys):
    csv = paper_csv
    code = run_cli(["analyze", str(csv), "--out", str(tmp_path), "--psychometric", "none", "--no-figures",
                    "--n-boot", "200", "--correction", "1/2N", "--json"])
    assert code == 0
    d = json.loads(capsys.readouterr().out)
    assert d["settings"]["correction"] == "1/(2N)"
    assert {r["correction"] for r in d["table"]} == {"1/(2N)"}
    assert (tmp_path / "table.csv").is_file()


def test_cli_study_folder(paper_csv, tmp_path, capsys):
    csv = paper_csv
    study = tmp_path / "study"
    study.mkdir()
    assert run_cli(["analyze", str(study)]) == 1          # an error naming the export (issue 33)
    err = capsys.readouterr().err
    assert f"flipstudy export {study} --out {study}/responses.csv" in err
    (study / "responses.csv").write_bytes(csv.read_bytes())
    assert run_cli(["analyze", str(study), "--psychometric", "none", "--no-gee", "--no-figures",
                    "--n-boot", "100"]) == 0
    out = capsys.readouterr().out
    assert "| smooth-increase |" in out
    assert (study / "analysis" / "table.csv").is_file()


def test_cli_bad_input_exit_code(tmp_path, capsys):
    p = tmp_path / "bad.csv"
    p.write_text("participant,group,level,response\nP1,g,0,correct\nP1,g,x,incorrect\n")
    assert run_cli(["analyze", str(p), "--out", str(tmp_path / "o")]) == 1
    assert "line 3" in capsys.readouterr().err


# --------------------------------------------------------------- architecture

def test_analysis_imports_nothing_of_the_other_packages():
    for f in (ROOT / "analysis").glob("*.py"):
        tree = ast.parse(f.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                mods = [node.module or ""]
            else:
                continue
            for m in mods:
                parts = m.split(".")
                part = parts[1] if parts[0] == "flipstudy" and len(parts) > 1 else parts[0]
                assert part not in {"study", "render", "stimuli"}, (f.name, m)


@pytest.mark.slow
def test_degenerate_groups_never_crash():
    """Every answer alike (all correct, all incorrect): no threshold, a note, sane parameters."""
    x = np.array([0, 17, 25, 37, 50.0])
    n = np.full(5, 20.0)
    from flipstudy.analysis.stats import fit_psignifit
    for k in (np.zeros(5), n.copy()):
        f = fit_psignifit("g", x, k, n, seed=0)
        assert np.isnan(f.threshold) and f.note
        assert 0 <= f.params["gamma"] <= 0.9 and 0 <= f.params["lambda"] <= 0.5


# ------------------------------------------------------------------ pose-rate groups

def _pose_rate_answers(rng, hold_thr=50.0, width=30.0, gamma=0.15, lam=0.02, reps=60, n_part=6):
    """A percent group (take-off) and a pose-rate group whose P(incorrect) rises as the
    poses per second N fall: the true curve is in the hold time 1000/N ms, with the
    detection threshold x* = ``hold_thr`` ms (N* = 1000/x*)."""
    from flipstudy.analysis.stats import psychometric_curve as pc
    # m such that P(hold_thr) = (1 + γ)/2 on the curve with this width, γ, λ
    F = (1 - gamma) / (2 * (1 - gamma - lam))
    m = hold_thr - width / (norm.ppf(0.95) - norm.ppf(0.05)) * norm.ppf(F)
    rows = []
    for g, kind, levels in (("poses", "pose-rate", [0, 10, 15, 20, 30]),
                            ("takeoff", "takeoff-angle", [0, 10, 20, 30, 40])):
        for lv in levels:
            x = (1000.0 / lv if lv else 0.0) if kind == "pose-rate" else lv
            p = pc(x, m, width, gamma, lam)
            for i in range(reps * n_part):
                rows.append({"participant": f"P{i % n_part + 1}", "group": g, "level": lv, "kind": kind,
                             "response": "incorrect" if rng.random() < p else "correct"})
    return pd.DataFrame(rows)


@pytest.mark.slow
def test_pose_rate_group_threshold_in_ms_recovers_the_pose_rate(tmp_path):
    from flipstudy.analysis.units import magnitudes
    df = _pose_rate_answers(np.random.default_rng(7))
    # the magnitude is the hold time: the fewest poses per second give the largest magnitude
    assert magnitudes([30, 20, 15, 10], "pose-rate").tolist() == pytest.approx([1000 / 30, 50, 1000 / 15, 100])
    r = analyze(df, tmp_path, n_boot=100, gee=False, figures=True)
    by = {f.group: f for f in r.fits}
    f = by["poses"]
    assert f.unit == "ms" and by["takeoff"].unit == "%"
    assert sorted(f.x.tolist()) == pytest.approx([0, 1000 / 30, 50, 1000 / 15, 100])
    assert f.reached, f.note
    assert f.ci_low <= 50 <= f.ci_high                       # the true hold threshold
    assert abs(1000 / f.threshold - 20) < 2.5                # maps back to N* = 20 poses/s
    assert 1000 / f.ci_high <= 20 <= 1000 / f.ci_low
    # read as a percent (|level|), the same answers would fall with the magnitude
    k = df[df["group"] == "poses"].groupby("level")["response"].apply(lambda s: (s == "incorrect").mean())
    assert k[10] > k[30]
    # tables: pose-rate levels as written, in poses/s; the percent group's columns unchanged
    cols = list(r.paper.columns)
    assert "10 poses/s" in cols and "30 poses/s" in cols and "40 %" in cols and "15 %" not in cols
    assert r.paper.set_index("group").loc["takeoff", "10 poses/s"] == ""
    md = (tmp_path / "table_paper.md").read_text()
    assert "| group | 0 poses/s | 10 poses/s | 15 poses/s | 20 poses/s | 30 poses/s |" in md
    assert "0 poses/s" in (tmp_path / "table_paper.tex").read_text()
    assert "poses/s" in (tmp_path / "notes.md").read_text()


def test_psychometric_figure_labels_each_groups_unit():
    from flipstudy.analysis.figures import psychometric_figure
    df = _pose_rate_answers(np.random.default_rng(3), reps=20)
    fits, _ = fit_psychometric(load_responses(df), seed=0)
    fig = psychometric_figure(fits)
    labels = {ax.get_title(): ax.get_xlabel() for ax in fig.axes if ax.get_visible() and ax.get_title()}
    assert "ms" in labels["poses"] and "1000/N" in labels["poses"]
    assert labels["takeoff"] == "error magnitude |level| (%)"


def test_per_participant_pose_rate_thresholds_in_ms():
    from flipstudy.analysis.thresholds import participant_thresholds
    df = _pose_rate_answers(np.random.default_rng(11), reps=40, n_part=3)
    df = df[df["group"] == "poses"].assign(detected=lambda d: d["response"] == "incorrect",
                                           task="yes-no", method="constant")
    t, notes = participant_thresholds(df)
    assert len(t) == 3 and (t["source"] == "replayed").all(), notes
    # the true hold threshold is 50 ms = 20 poses/s: each x* near it, in most 95 % intervals
    assert (abs(t["threshold"] - 50) < 6).all() and (abs(1000 / t["threshold"] - 20) < 2.5).all(), t
    assert ((t["ci_low"] <= 50) & (50 <= t["ci_high"])).sum() >= 2, t
    assert (t["ci_high"] - t["ci_low"] < 20).all(), t

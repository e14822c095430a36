"""`analyze` never crashes on a valid long-format response table (hypothesis): 1 to 50
participants, missing cells, all-correct and all-incorrect cells, groups of a single
level, unbalanced repetitions; the whole pipeline with figures and the LaTeX table.
"""
from __future__ import annotations

import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

from flipstudy.analysis.io import DESIGN_COLUMNS
from flipstudy.analysis.pipeline import analyze
from flipstudy.analysis.simulate import PAPER_FILL, PAPER_TABLE2

GROUPS = ["smooth-increase", "abrupt-decrease", "takeoff-increase", "my_group & 50%", "Größe #2"]
LEVELS = [0.0, 10.0, 17.0, 25.0, 50.0, -10.0]


def _rows(cells) -> pd.DataFrame:
    """Long-format rows (DESIGN.md columns) from (participant, group, level, n_correct,
    n_incorrect) cells, in a shuffled trial order per participant."""
    rows = []
    for p, g, lv, k_c, k_i in cells:
        for r, resp in enumerate(["correct"] * k_c + ["incorrect"] * k_i):
            rows.append((f"P{p:02d}", g, lv, r + 1, resp))
    df = pd.DataFrame(rows, columns=["participant", "group", "level", "repetition", "response"])
    df = df.sample(frac=1.0, random_state=0).sort_values("participant", kind="stable")
    df["session"] = df["participant"] + "-S1"
    df["trial"] = df.groupby("participant").cumcount() + 1
    df["stimulus"] = df["group"] + "_" + df["level"].map("{:g}".format)
    df["rt_ms"] = 1200 + (df["trial"] * 37) % 900
    df["shown_ms"] = 2400
    df["timestamp"] = pd.Timestamp("2026-01-05T10:00:00") + pd.to_timedelta(df["trial"] * 4, unit="s")
    df["timestamp"] = df["timestamp"].dt.strftime("%Y-%m-%dT%H:%M:%S")
    return df[list(DESIGN_COLUMNS)].reset_index(drop=True)


def table2_ratings_panel(n_participants: int = 19, trials: int = 4) -> pd.DataFrame:
    """A panel whose pooled cells are exactly Table 2's ratings (rounded to whole trials):
    each cell's correct answers spread as evenly as possible over the participants.  With
    19 participants this crashed the d' figure ("'yerr' must not contain negative values")."""
    cells = []
    for g, t in PAPER_TABLE2.items():
        for lv, r in zip(t["levels"], t["rating"]):
            r = PAPER_FILL.get((g, lv), r)
            n = n_participants * trials
            k = int(round(n * r / 100))
            per = [k // n_participants + (1 if i < k % n_participants else 0) for i in range(n_participants)]
            cells += [(i + 1, g, float(lv), c, trials - c) for i, c in enumerate(per)]
    return _rows(cells)


@pytest.fixture(scope="module")
def monkeypatch_save():
    from flipstudy.analysis import figures
    mp = pytest.MonkeyPatch()
    mp.setattr(figures, "save", _draw_only)
    yield
    mp.undo()


@st.composite
def response_tables(draw) -> pd.DataFrame:
    n_part = draw(st.integers(1, 50))
    groups = draw(st.lists(st.sampled_from(GROUPS), min_size=1, max_size=3, unique=True))
    cells = []
    for g in groups:
        levels = draw(st.lists(st.sampled_from(LEVELS), min_size=1, max_size=4, unique=True))
        for lv in levels:
            kind = draw(st.sampled_from(["all-correct", "all-incorrect", "mixed", "mixed"]))
            p = draw(st.floats(0.05, 0.95))
            seed = draw(st.integers(0, 2**16))
            rng = np.random.default_rng(seed)
            for i in range(n_part):
                n = draw(st.integers(0, 3)) if n_part <= 8 else int(rng.integers(0, 4))  # 0: missing
                k_i = {"all-correct": 0, "all-incorrect": n}.get(kind, int(rng.binomial(n, p)))
                cells.append((i + 1, g, lv, n - k_i, k_i))
    if not any(c + i for *_, c, i in cells):
        cells[0] = cells[0][:3] + (1, 0)
    return _rows(cells)


def _draw_only(fig, stem):
    """Stands in for :func:`analysis.figures.save` in the property test: the figure is
    drawn completely (Agg: layout, every artist, the error bars) but not encoded as PDF
    and PNG, which costs ~1 s per figure (font subsetting) and depends on no data;
    :func:`test_table2_panel_full_analysis_with_figures` writes them for real."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    FigureCanvasAgg(fig).draw()
    paths = [Path(f"{stem}.pdf"), Path(f"{stem}.png")]
    for p in paths:
        p.write_bytes(b"drawn")
    return paths


@pytest.mark.slow
def test_table2_panel_full_analysis_with_figures(tmp_path):
    """The 19-participant panel whose pooled cells are Table 2's ratings, the whole
    pipeline writing every figure (it crashed in the d' figure before)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = analyze(table2_ratings_panel(19), tmp_path, n_boot=100, seed=1, psychometric="psignifit")
    for name in ("dprime.pdf", "dprime.png", "ratings.pdf", "psychometric.pdf", "sheet.png"):
        assert (tmp_path / name).stat().st_size > 5000, name
    assert len(res.table) == 25 and len(res.thresholds) == 5


@settings(max_examples=25, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@example(df=table2_ratings_panel(19))
@given(df=response_tables())
@pytest.mark.slow
def test_analyze_never_crashes_on_a_valid_table(df, monkeypatch_save):
    """The whole pipeline but the psychometric fits (psignifit takes ~1 s a group;
    the next test gives it fewer tables)."""
    with tempfile.TemporaryDirectory(prefix="analyze") as d:
        out = Path(d)
        csv = out / "responses.csv"
        df.to_csv(csv, index=False)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")          # statsmodels/psignifit convergence chatter
            res = analyze(csv, out / "analysis", n_boot=60, seed=1, psychometric="none")
        files = {p.name for p in (out / "analysis").iterdir()}
        for name in ("table.csv", "table_paper.tex", "dprime.pdf", "ratings.png", "sheet.pdf",
                     "summary.json", "notes.md"):
            assert name in files, name
        # every cell of the input is in the table, with the counts of the input
        cnt = df.groupby(["group", "level"])["response"].agg(
            n="size", k=lambda r: int((r == "incorrect").sum())).reset_index()
        got = res.table.set_index(["group", "level"])
        for g, lv, n, k in cnt.itertuples(index=False):
            assert got.loc[(g, lv), "n"] == n and got.loc[(g, lv), "n_incorrect"] == k
        tex = (out / "analysis" / "table_paper.tex").read_text(encoding="utf-8")
        assert tex.isascii()


@pytest.mark.slow
@settings(max_examples=5, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(df=response_tables())
def test_psychometric_fits_and_their_figures_never_crash_on_a_valid_table(df, monkeypatch_save):
    """psignifit on random tables (all-alike cells, one participant, one level): every
    group is fitted or named in a note, a threshold lies in the tested range or is
    NaN with a note, and the psychometric figure and sheet are drawn."""
    with tempfile.TemporaryDirectory(prefix="analyze") as d:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")          # psignifit/statsmodels chatter
            res = analyze(df, Path(d), n_boot=20, seed=1, psychometric="psignifit", gee=False)
        fitted = {f.group for f in res.fits}
        for g in dict.fromkeys(res.table["group"]):
            assert g in fitted or any(n.startswith(f"{g}: ") for n in res.notes), g
        for f in res.fits:
            assert f.note and 0 <= f.params["gamma"] <= 0.9 and 0 <= f.params["lambda"] <= 0.5
            assert np.isnan(f.threshold) or f.x.min() <= f.threshold <= f.x.max(), f
        assert len(res.thresholds) == len(res.fits)
        drawn = {p.name for p in Path(d).iterdir()}
        assert "sheet.pdf" in drawn and ("psychometric.pdf" in drawn) == bool(res.fits)


def test_table2_panel_pools_to_table2():
    """The explicit example above is what it says: its pooled ratings are Table 2's."""
    df = table2_ratings_panel(19)
    rating = 100 * (df["response"] == "correct").groupby([df["group"], df["level"]]).mean()
    for g, t in PAPER_TABLE2.items():
        for lv, r in zip(t["levels"], t["rating"]):
            r = PAPER_FILL.get((g, lv), r)
            assert abs(rating[(g, float(lv))] - r) <= 100 / 76 / 2 + 1e-9


@pytest.mark.skipif(shutil.which("pdflatex") is None,
                    reason="pdflatex not installed (CI installs texlive-latex-base)")
@pytest.mark.parametrize("booktabs", [False, True])
def test_latex_table_compiles_with_pdflatex(tmp_path, booktabs):
    if booktabs and subprocess.run(["kpsewhich", "booktabs.sty"], capture_output=True,
                                   text=True).stdout.strip() == "":
        pytest.skip("booktabs.sty not installed (texlive-latex-recommended)")
    df = table2_ratings_panel(19)
    df.loc[df["group"] == "takeoff-increase", "group"] = "odd_name & 100% #1 {x} ~ é"
    res = analyze(df, tmp_path, n_boot=50, psychometric="none", gee=False, figures=False)
    tex = tmp_path / "table_paper.tex"
    text = tex.read_text(encoding="utf-8")
    assert text.isascii() and "$d'$" in text
    doc = tmp_path / "doc.tex"
    doc.write_text("\\documentclass{article}\n" + ("\\usepackage{booktabs}\n" if booktabs else "")
                   + "\\begin{document}\n\\input{table_paper}\n\\end{document}\n", encoding="ascii")
    r = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error", "doc.tex"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout[-3000:]
    assert (tmp_path / "doc.pdf").stat().st_size > 1000
    assert "odd\\_name \\& 100\\% \\#1 \\{x\\} \\textasciitilde{} e" in tex.read_text()
    assert len(res.table) == 25

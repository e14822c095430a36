"""Analysis of comparison studies: which source's motions do people judge physically possible?

A comparison study (a design with ``[[sources]]``) shows, in each 2AFC trial, one
item as two sources give it and asks which moved in a physically possible way.
From its answers (one row per trial: which source's clip was chosen over which):

* :func:`bradley_terry` — the Bradley–Terry ranking of the sources: P(a chosen
  over b) = logistic(θ_a − θ_b), fitted by maximum likelihood as a logistic
  regression without intercept (statsmodels ``Logit``; design matrix +1 for the
  trial's stimulus source, −1 for its comparison, the first source's column left
  out, so θ_first = 0 and every θ is a log-odds against the first source).  The
  95 % intervals are Wald intervals from the observed information (the MLE's
  covariance), which cover the true θ at about the nominal rate (tested over
  repeated simulated panels).
* :func:`win_rates` — per item and source: comparisons, wins and win rate.
* :func:`agreement` — how well a per-clip number (the score's P(anything
  noticed), or the plain foot-skate, floating and penetration sizes) predicts
  people's choices: the clip with the smaller number is predicted to be chosen.
  Accuracy (ties count one half) and the AUC of the difference (Mann–Whitney,
  ``scipy.stats.mannwhitneyu``), each with a percentile bootstrap interval over
  participants (participants resampled with replacement; the trials of one
  participant stay together).

>>> import numpy as np, pandas as pd
>>> rng = np.random.default_rng(0)
>>> ch = simulate_choices({"gt": 0.0, "a": -1.0, "b": -2.0}, ["a", "b"], "gt", 30, 10, rng)
>>> r = bradley_terry(ch, ["gt", "a", "b"])
>>> list(r.table.sort_values("strength", ascending=False).source)
['gt', 'a', 'b']
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.special import expit
from scipy.stats import mannwhitneyu, norm

from flipstudy.errors import ComparisonError

#: the columns of a choices table (:func:`choices`)
CHOICE_COLUMNS = ["participant", "item", "stimulus", "original", "a", "b", "a_wins"]


def p_first_wins(theta_a, theta_b):
    """P(a is chosen over b) under the Bradley–Terry model with logit strengths.

    >>> float(p_first_wins(1.0, 1.0))
    0.5
    """
    return expit(np.asarray(theta_a, float) - np.asarray(theta_b, float))


def choices(df: pd.DataFrame, source_of: dict, item_of: dict) -> pd.DataFrame:
    """The 2AFC answers of a comparison study as choices: per trial the participant,
    item, ``stimulus`` (source ``a``), its comparison ``original`` (source ``b``) and
    ``a_wins`` (the stimulus was chosen as the physically possible one).  ``df``: the
    responses table (columns participant, task, stimulus, original_stimulus, first,
    response); ``source_of``/``item_of``: stimulus → source / item (the manifest's)."""
    need = ["participant", "stimulus", "response", "first", "original_stimulus"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise ComparisonError(f"responses table: no column {missing[0]!r}; a comparison study's 2AFC "
                              f"answers need {', '.join(need)} (export the study again)")
    d = df[df["task"] == "2afc"] if "task" in df.columns else df
    unknown = sorted((set(d["stimulus"]) | set(d["original_stimulus"])) - set(source_of))
    if unknown:
        raise ComparisonError(f"responses table: stimulus {unknown[0]!r} is not a clip of the study's "
                              f"sources (responses of another study?)")
    chosen_first = d["response"].astype(str).to_numpy() == "first"
    stim_first = d["first"].astype(str).to_numpy() == "modified"
    return pd.DataFrame({
        "participant": d["participant"].astype(str).to_numpy(),
        "item": d["stimulus"].map(item_of).to_numpy(),
        "stimulus": d["stimulus"].to_numpy(), "original": d["original_stimulus"].to_numpy(),
        "a": d["stimulus"].map(source_of).to_numpy(), "b": d["original_stimulus"].map(source_of).to_numpy(),
        "a_wins": (chosen_first == stim_first).astype(int)})


@dataclass(frozen=True)
class Ranking:
    """A Bradley–Terry ranking: ``table`` (source, strength, low, high, se, wins, n),
    strengths in logits relative to ``reference`` (θ = 0), intervals at ``ci``."""
    table: pd.DataFrame
    reference: str
    ci: float
    n_choices: int
    method: str = ("Bradley–Terry by maximum likelihood (statsmodels Logit without intercept, "
                   "θ of the first source fixed at 0); Wald intervals from the observed information")

    def order(self) -> list[str]:
        """The sources from the strongest to the weakest."""
        return list(self.table.sort_values("strength", ascending=False, kind="stable").source)

    def summary(self) -> str:
        lines = [f"Bradley–Terry ranking ({self.n_choices} choices; θ in logits, {self.reference} = 0, "
                 f"{100 * self.ci:g} % intervals):"]
        for r in self.table.sort_values("strength", ascending=False, kind="stable").itertuples():
            lines.append(f"  {r.source:16s} θ = {r.strength:+.2f} [{r.low:+.2f}, {r.high:+.2f}]   "
                         f"won {r.wins}/{r.n}")
        return "\n".join(lines)


def bradley_terry(ch: pd.DataFrame, sources: list[str], ci: float = 0.95) -> Ranking:
    """The Bradley–Terry strengths of ``sources`` (the first is the reference, θ = 0)
    from a choices table (columns ``a``, ``b``, ``a_wins``; see :func:`choices`).
    A source never compared, or one that won or lost every comparison (no finite
    maximum likelihood), raises :class:`~flipstudy.errors.ComparisonError`."""
    import statsmodels.api as sm
    sources = list(sources)
    col = {s: i for i, s in enumerate(sources)}
    bad = sorted((set(ch["a"]) | set(ch["b"])) - set(col))
    if bad:
        raise ComparisonError(f"choices name source {bad[0]!r}, not one of {', '.join(sources)}")
    a = ch["a"].map(col).to_numpy()
    b = ch["b"].map(col).to_numpy()
    y = ch["a_wins"].to_numpy().astype(float)
    n = np.bincount(a, minlength=len(sources)) + np.bincount(b, minlength=len(sources))
    wins = np.bincount(a, weights=y, minlength=len(sources)) + np.bincount(b, weights=1 - y,
                                                                         minlength=len(sources))
    for s, k, w in zip(sources, n, wins):
        if k == 0:
            raise ComparisonError(f"source {s!r} was never compared; no strength can be estimated")
        if w in (0, k):
            raise ComparisonError(f"source {s!r} {'won' if w else 'lost'} all its {int(k)} comparisons: "
                                  f"its Bradley–Terry strength is infinite (more trials or participants)")
    X = np.zeros((len(ch), len(sources)))
    X[np.arange(len(ch)), a] += 1.0
    X[np.arange(len(ch)), b] -= 1.0
    X = X[:, 1:]
    fit = sm.Logit(y, X).fit(disp=0, method="newton", maxiter=100)
    theta = np.concatenate([[0.0], fit.params])
    se = np.concatenate([[0.0], fit.bse])
    z = norm.ppf(0.5 + ci / 2)
    table = pd.DataFrame({"source": sources, "strength": theta, "se": se, "low": theta - z * se,
                          "high": theta + z * se, "wins": wins.astype(int), "n": n.astype(int)})
    return Ranking(table, sources[0], ci, len(ch))


def win_rates(ch: pd.DataFrame) -> pd.DataFrame:
    """Per item and source: comparisons ``n``, ``wins`` and ``win_rate`` (a trial
    counts for both its sources)."""
    both = pd.concat([pd.DataFrame({"item": ch["item"], "source": ch["a"], "win": ch["a_wins"]}),
                      pd.DataFrame({"item": ch["item"], "source": ch["b"], "win": 1 - ch["a_wins"]})])
    t = both.groupby(["item", "source"], sort=True)["win"].agg(["size", "sum"]).reset_index()
    t.columns = ["item", "source", "n", "wins"]
    t["win_rate"] = t["wins"] / t["n"]
    return t


def _acc_auc(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Accuracy of ``x > 0`` as a prediction of ``y`` (ties one half), AUC of ``x``."""
    acc = float(np.mean(np.where(x == 0, 0.5, (x > 0) == (y == 1))))
    pos, neg = x[y == 1], x[y == 0]
    if len(pos) == 0 or len(neg) == 0:
        return acc, float("nan")
    return acc, float(mannwhitneyu(pos, neg).statistic / (len(pos) * len(neg)))


def agreement(ch: pd.DataFrame, metrics: pd.DataFrame, *, n_boot: int = 2000, ci: float = 0.95,
              seed=0) -> pd.DataFrame:
    """How well each metric (columns of ``metrics``, indexed by stimulus; smaller =
    more physically possible) predicts the choices: per metric ``accuracy`` and
    ``auc`` with percentile-bootstrap intervals over participants (``n_boot``
    resamples), and the trials ``n`` it could judge (both clips measured)."""
    rng = np.random.default_rng(seed)
    parts = ch["participant"].to_numpy()
    uniq, inv = np.unique(parts, return_inverse=True)
    rows = []
    q = [(1 - ci) / 2, (1 + ci) / 2]
    for m in metrics.columns:
        v = metrics[m]
        x = (ch["original"].map(v) - ch["stimulus"].map(v)).to_numpy(float)
        y = ch["a_wins"].to_numpy()
        ok = np.isfinite(x)
        x, y, p = x[ok], y[ok], inv[ok]
        if len(x) == 0:
            rows.append({"metric": m, "n": 0})
            continue
        acc, auc = _acc_auc(x, y)
        by = [np.flatnonzero(p == k) for k in range(len(uniq))]
        boots = np.empty((n_boot, 2))
        for i in range(n_boot):
            idx = np.concatenate([by[k] for k in rng.integers(0, len(uniq), len(uniq))])
            boots[i] = _acc_auc(x[idx], y[idx])
        lo, hi = np.nanquantile(boots, q, axis=0)
        rows.append({"metric": m, "n": int(len(x)), "accuracy": acc, "accuracy_low": lo[0],
                     "accuracy_high": hi[0], "auc": auc, "auc_low": lo[1], "auc_high": hi[1]})
    return pd.DataFrame(rows)


def simulate_choices(strengths: dict, challengers: list[str], reference: str, n_items: int,
                     n_participants: int, rng: np.random.Generator, repetitions: int = 1) -> pd.DataFrame:
    """Choices of a panel of observers with known source ``strengths`` (logits): every
    participant compares each challenger with ``reference`` on every item
    ``repetitions`` times, choosing with :func:`p_first_wins` — the answers a
    comparison study's simulated participants give
    (:func:`flipstudy.study.simulate.comparison_probability`), without sessions."""
    P, I, C, R = n_participants, n_items, len(challengers), repetitions
    part = np.repeat(np.arange(P), I * C * R)
    item = np.tile(np.repeat(np.arange(I), C * R), P)
    chal = np.tile(np.repeat(np.arange(C), R), P * I)
    a = np.asarray(challengers)[chal]
    th = np.array([strengths[c] for c in challengers])[chal]
    wins = (rng.random(len(a)) < p_first_wins(th, strengths[reference])).astype(int)
    return pd.DataFrame({"participant": [f"sim{k + 1:03d}" for k in part], "item": item.astype(str),
                         "stimulus": [f"{i}_{s}" for i, s in zip(item, a)],
                         "original": [f"{i}_{reference}" for i in item], "a": a, "b": reference,
                         "a_wins": wins})


@dataclass(frozen=True)
class ComparisonAnalysis:
    """What :func:`analyze_choices` found: the ranking, the per-item win rates, the
    agreement of the per-clip numbers with the choices, and the files written."""
    ranking: Ranking
    wins: pd.DataFrame
    agreement: pd.DataFrame
    participants: int
    files: dict = field(default_factory=dict)
    notes: tuple = ()
    label: str = ""             # which participants, "N = … (… real, … simulated)"

    def summary(self) -> str:
        """What ``flipstudy analyze`` prints (:class:`flipstudy.results.CompareResult`)."""
        from flipstudy.records import CompareReport
        from flipstudy.results import CompareResult
        return CompareResult(Path(self.files.get("json", ".")).parent,
                             CompareReport.from_dict(self.to_dict())).summary()

    def to_dict(self) -> dict:
        return {"participants": self.participants, "participants_label": self.label,
                "choices": self.ranking.n_choices,
                "ranking": json.loads(self.ranking.table.to_json(orient="records")),
                "reference": self.ranking.reference, "ci": self.ranking.ci, "method": self.ranking.method,
                "agreement": json.loads(self.agreement.to_json(orient="records")),
                "files": {k: str(v) for k, v in self.files.items()}, "notes": list(self.notes)}


def analyze_choices(ch: pd.DataFrame, sources: list[str], metrics: pd.DataFrame | None = None,
                    out_dir=None, *, n_boot: int = 2000, ci: float = 0.95, seed=0,
                    figures: bool = True, label: str | None = None) -> ComparisonAnalysis:
    """Ranking, win rates and agreement of a comparison study's choices; with
    ``out_dir`` the tables (``ranking.csv``, ``win_rates.csv``, ``agreement.csv``,
    ``comparison.json``), ``notes.md`` and the figure (``comparison.png``/``.pdf``).
    ``label``: which participants the answers are from
    (:func:`flipstudy.analysis.io.participants_label`), on the figure and in the notes;
    default ``N = …`` from the choices."""
    if not len(ch):
        raise ComparisonError("no 2AFC answers of a comparison study to analyse")
    ranking = bradley_terry(ch, sources, ci)
    wins = win_rates(ch)
    agree = agreement(ch, metrics, n_boot=n_boot, ci=ci, seed=seed) if metrics is not None \
        else pd.DataFrame()
    files, n = {}, int(ch["participant"].nunique())
    label = label or f"N = {n} participant{'s' if n != 1 else ''}"
    res = ComparisonAnalysis(ranking, wins, agree, n, files, label=label)
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        ranking.table.to_csv(out / "ranking.csv", index=False, float_format="%.6f")
        wins.to_csv(out / "win_rates.csv", index=False, float_format="%.6f")
        agree.to_csv(out / "agreement.csv", index=False, float_format="%.6f")
        files.update(ranking=out / "ranking.csv", win_rates=out / "win_rates.csv",
                     agreement=out / "agreement.csv")
        if figures:
            files["figure"] = comparison_figure(ranking, wins, out / "comparison.png", label=label)
        (out / "notes.md").write_text(_notes_md(res, ch, sources), encoding="utf-8")
        files["notes"] = out / "notes.md"
        (out / "comparison.json").write_text(json.dumps(res.to_dict(), indent=1, default=float) + "\n")
        files["json"] = out / "comparison.json"
    return res


def _notes_md(res: ComparisonAnalysis, ch: pd.DataFrame, sources) -> str:
    """``notes.md`` of a comparison analysis: who, what was compared, the ranking, the
    agreement and the notes, as the other analyses write theirs."""
    r, rk = res.to_dict(), res.ranking
    lines = ["# Comparison notes", "",
             f"{res.label}; {rk.n_choices} choices between {len(sources)} sources "
             f"({', '.join(sources)}) over {ch['item'].nunique()} item(s).", "",
             f"Ranking: {rk.method}; θ in logits, {rk.reference} = 0, {100 * rk.ci:g} % intervals.", "",
             "| source | θ | interval | won |", "|:--|--:|:--|--:|"]
    lines += [f"| {x['source']} | {x['strength']:+.2f} | [{x['low']:+.2f}, {x['high']:+.2f}] | "
              f"{x['wins']}/{x['n']} |" for x in sorted(r["ranking"], key=lambda x: -x["strength"])]
    if r["agreement"]:
        lines += ["", "## Agreement of the clips' numbers with the choices", "",
                  "Smaller number predicted chosen; bootstrap intervals over participants.", "",
                  "| metric | accuracy | AUC | trials |", "|:--|:--|:--|--:|"]
        lines += [f"| {a['metric']} | {a['accuracy']:.2f} [{a['accuracy_low']:.2f}, "
                  f"{a['accuracy_high']:.2f}] | {a['auc']:.2f} [{a['auc_low']:.2f}, "
                  f"{a['auc_high']:.2f}] | {a['n']} |" if a.get("n")
                  else f"| {a['metric']} | not measured on these clips | | 0 |" for a in r["agreement"]]
    if res.participants < 5:
        lines += ["", f"- {res.participants} participant(s): the intervals over participants are "
                      f"not meaningful below 5."]
    lines += [f"- {x}" for x in res.notes]
    return "\n".join(lines) + "\n"


def comparison_figure(ranking: Ranking, wins: pd.DataFrame, path, label: str | None = None) -> Path:
    """Left: the sources' strengths with their intervals; right: each item's win
    rate per source; ``label`` (which participants) in small type underneath.
    Writes ``path`` (PNG) and the same name as PDF."""
    import matplotlib.pyplot as plt
    t = ranking.table.sort_values("strength", ascending=True, kind="stable")
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9, 3.4), gridspec_kw={"width_ratios": [1, 1.4]})
    yy = np.arange(len(t))
    ax.errorbar(t.strength, yy, xerr=[t.strength - t.low, t.high - t.strength], fmt="o", capsize=4)
    ax.axvline(0, color="0.7", lw=0.8)
    ax.set_yticks(yy, t.source)
    ax.set_xlabel(f"Bradley–Terry θ (logit vs {ranking.reference}), {100 * ranking.ci:g} % CI")
    ax.set_title("ranking of the sources")
    piv = wins.pivot(index="item", columns="source", values="win_rate")
    piv = piv[[s for s in ranking.order() if s in piv.columns]]
    piv.plot.bar(ax=bx, width=0.8, rot=0)
    bx.axhline(0.5, color="0.5", lw=0.8, ls="--")
    bx.set_ylim(0, 1)
    bx.set_ylabel("win rate (chosen as possible)")
    bx.set_title("per item")
    bx.legend(fontsize=8, loc="upper right")
    if label:
        fig.supxlabel(label, fontsize=7, color="#444444")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    fig.savefig(path.with_suffix(".pdf"))
    plt.close(fig)
    return path


__all__ = ["p_first_wins", "choices", "bradley_terry", "Ranking", "win_rates", "agreement",
           "simulate_choices", "analyze_choices", "ComparisonAnalysis", "comparison_figure"]

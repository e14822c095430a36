"""``analyze``: responses in, tables, statistics and figures out."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .core import summarize
from flipstudy.errors import ResponsesError
from .io import group_order, load_responses, participants_label, resolve_responses_path, select_participants
from .sdt import CORRECTION_TEXT, normalise_correction
from .stats import fit_psychometric, gee_levels
from .tables import paper_layout, to_latex, to_markdown
from .tasks import fit_tasks, has_tasks, split, summarize_tasks, thresholds_frame
from .thresholds import group_thresholds, participant_thresholds
from .units import group_kinds, is_pose_rate, pose_rate_of

#: the default figure-sheet image slots, in display order
IMAGE_SLOTS = ("ghost original", "ghost strongest error", "trail original", "trail strongest error")

#: below this many participants, intervals and tests over participants are not meaningful
MIN_PARTICIPANTS = 5

PAPER_CAPTION = ("Mean ratings (percent of answers \"correct\") and sensitivity d′ (in parentheses) "
                 "per error group and level.")


@dataclass
class Result:
    """What :func:`analyze` computed and wrote.

    ``table``: one row per group and level (the columns of ``table.csv``);
    ``participants``: per-participant d′; ``gee``: each level against its
    original; ``thresholds``: one row per group; ``fits``: the
    :class:`~flipstudy.analysis.stats.PsychometricFit` objects; ``paper``: the paper's
    layout as strings; ``files``: name → path of every file written;
    ``notes``: sentences worth reading (corrections, thresholds not reached,
    missing images...).

    Attributes
    ----------
    table, participants, gee, thresholds, paper : pandas.DataFrame
    fits : list of PsychometricFit
    notes : list of str
    files : dict of str to pathlib.Path

    Examples
    --------
    >>> from flipstudy.analysis import analyze
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> r = analyze(paper_panel(19, seed=1), None, psychometric="none", gee=False, n_boot=100)
    >>> type(r).__name__, r.files
    ('Result', {})
    """
    table: pd.DataFrame
    participants: pd.DataFrame
    gee: pd.DataFrame
    thresholds: pd.DataFrame
    fits: list
    paper: pd.DataFrame
    notes: list[str]
    files: dict[str, Path] = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    participant_thresholds: pd.DataFrame | None = None
    group_thresholds: pd.DataFrame | None = None
    kinds: dict = field(default_factory=dict)       # group → error kind (column ``kind``)
    exclusions: object | None = None                # ExclusionReport when the design states rules

    def to_dict(self) -> dict:
        """JSON-ready summary (what ``flipstudy analyze --json`` prints)."""
        def clean(v):
            if isinstance(v, (float, np.floating)):
                return None if not math.isfinite(float(v)) else float(v)
            if isinstance(v, (np.integer,)):
                return int(v)
            if isinstance(v, (np.bool_,)):
                return bool(v)
            return v

        def records(df):
            return [{k: clean(v) for k, v in r.items()} for r in df.to_dict("records")]
        out = {"settings": self.settings,
               "table": records(self.table),
               "thresholds": records(self.thresholds)}
        if self.participant_thresholds is not None:
            out["thresholds_participants"] = records(self.participant_thresholds)
            out["thresholds_groups"] = records(self.group_thresholds)
        if self.exclusions is not None:
            out["exclusion_rules"] = list(self.exclusions.rules)
            out["flow"] = records(self.exclusions.flow)
        return {**out, "notes": list(self.notes), "files": {k: str(v) for k, v in self.files.items()}}


def split_by_style(df: pd.DataFrame, table: pd.DataFrame):
    """With a ``style`` column (the character style, from the manifest) of more
    than one value: the table gains a ``style`` column, ordered by style, and a
    note says which groups each style has.  Otherwise the table is unchanged.

    Examples
    --------
    >>> df = pd.DataFrame({"group": ["a", "b"], "style": ["stick", "mannequin"]})
    >>> t, note = split_by_style(df, pd.DataFrame({"group": ["a", "b"], "level": [0, 0]}))
    >>> t["style"].tolist(), note
    (['mannequin', 'stick'], 'Character styles: mannequin: b; stick: a.')
    """
    if "style" not in df.columns:
        return table, None
    st = df["style"].fillna("").astype(str).str.strip()
    if st.nunique() <= 1:
        return table, None
    per = st.groupby(df["group"]).agg(lambda v: ", ".join(sorted(set(v))))
    t = table.copy()
    t.insert(1, "style", t["group"].map(per).fillna(""))
    t = t.sort_values("style", kind="stable").reset_index(drop=True)
    by = {}
    for g, s_ in per.items():
        by.setdefault(s_, []).append(g)
    note = "Character styles: " + "; ".join(f"{k}: {', '.join(group_order(v))}"
                                            for k, v in sorted(by.items())) + "."
    return t, note


def _normalise_images(images) -> dict:
    if images is None:
        return {}
    if isinstance(images, (str, Path)):
        images = [images]
    if isinstance(images, dict):
        return {str(k): Path(v) for k, v in images.items()}
    out = {}
    for i, p in enumerate(images):
        label = IMAGE_SLOTS[i] if i < len(IMAGE_SLOTS) else Path(p).stem
        out[label] = Path(p)
    return out


def analyze(responses, out_dir=None, *, correction: str = "loglinear", images=None, seed=0,
            n_boot: int = 2000, ci: float = 0.95, psychometric: str = "psignifit",
            gee: bool = True, figures: bool = True, include_simulated: bool = False,
            include_incomplete: bool = False, quest_specs: dict | None = None,
            exclusions: dict | None = None, kept_out: dict | None = None) -> Result:
    """Run the whole analysis and write its outputs.

    ``responses``: a DataFrame, a responses CSV or a study folder (its
    ``responses.csv``).  ``out_dir``: where to write (None: compute only).
    ``correction``: ``"loglinear"`` (default), ``"loglinear-all"`` or
    ``"1/(2N)"`` (see :mod:`flipstudy.analysis.sdt`).  ``images``: for the figure sheet,
    a mapping label → PNG path or a list of up to four paths (ghost original,
    ghost strongest error, trail original, trail strongest error).
    ``seed``: every random draw (bootstrap, posterior samples).
    ``psychometric``: ``"psignifit"`` (a psychometric function per group) or ``"none"``.
    ``include_simulated`` / ``include_incomplete``: keep simulated participants
    (column ``simulated``) / sessions marked ``complete`` = false, which are
    left out by default (:func:`flipstudy.analysis.io.select_participants`); which
    participants were used is in ``settings["participants"]``, in every table
    caption, figure, ``notes.md`` and ``summary.json``.

    Answers with a ``task`` of ``2afc`` or a ``method`` of ``quest+``
    (:mod:`flipstudy.analysis.tasks`): the table gains a ``task`` column (2AFC d′ =
    √2·z(P correct)), 2AFC fits fix γ = ½, and every group gets per-participant
    thresholds (``thresholds_participants.csv``) and their distribution
    (``thresholds_groups.csv``); ``quest_specs``: group → (levels, task,
    :class:`~flipstudy.analysis.adaptive.QuestSettings`) of the design, to replay
    QUEST+ groups (without it their stored thresholds are used).

    ``exclusions``: the design's ``[exclusions]`` table (a dict;
    :mod:`flipstudy.analysis.exclusions`), applied before anything is computed: the
    excluded participants and the catch trials are left out, ``flow.csv`` and the
    ``flow`` figure report recruited → completed → excluded by rule → analysed, and
    ``responses_exclusions.csv`` keeps every row with ``excluded`` and ``exclusion_rule``.
    The flow starts with the runs ``import-web`` kept out of the tables (``kept_out``:
    ``{reason: runs}``; None: read from the ``quarantine.csv`` beside ``responses``).

    Files (in ``out_dir``): ``table.csv``, ``table_paper.csv``,
    ``table_paper.md``, ``table_paper.tex``, ``participants.csv``,
    ``levels_vs_original.csv`` (GEE), ``thresholds.csv``, ``notes.md``,
    ``summary.json`` and the figures ``ratings``, ``dprime``,
    ``psychometric``, ``sheet`` (``.pdf`` + ``.png``).

    Parameters
    ----------
    responses : pandas.DataFrame, str or pathlib.Path
        A table, a responses CSV or a study folder.
    out_dir : str or pathlib.Path, optional
        Where to write; None computes only.
    correction : {"loglinear", "loglinear-all", "1/(2N)"}
    psychometric : {"psignifit", "none"}
    gee, figures : bool
        Fit the GEE odds ratios; draw the figures.
    include_simulated, include_incomplete : bool
        Analyse simulated or unfinished sessions too.

    Returns
    -------
    Result

    Raises
    ------
    ResponsesError

    Examples
    --------
    >>> from flipstudy.analysis.simulate import paper_panel
    >>> r = analyze(paper_panel(19, seed=1), None, psychometric="none", gee=False, n_boot=200)
    >>> list(r.table.columns[:5])
    ['group', 'level', 'n', 'n_incorrect', 'n_participants']
    """
    correction = normalise_correction(correction)
    df, who, report = _select(responses, exclusions, kept_out, include_simulated, include_incomplete)
    label = participants_label(who)
    tasks = has_tasks(df)
    table, participants, notes, yes_no = _describe(df, tasks, correction, n_boot, seed, ci)
    _participant_notes(notes, who, label, report)
    table, g = _gee_step(table, yes_no, df, notes, gee=gee, tasks=tasks, ci=ci)
    fits, thresholds = _fit_step(df, notes, tasks=tasks, psychometric=psychometric, ci=ci, seed=seed)
    per_participant, per_group = (_participant_threshold_step(df, fits, quest_specs, notes) if tasks
                                  else (None, None))
    kinds = _kinds_step(df, notes)
    paper = paper_layout(table, kinds=kinds) if len(table) else pd.DataFrame(columns=["group"])
    result = Result(table=table, participants=participants, gee=g, thresholds=thresholds, fits=fits,
                    paper=paper, notes=notes, participant_thresholds=per_participant,
                    group_thresholds=per_group, kinds=kinds, exclusions=report,
                    settings={"correction": correction, "correction_text": CORRECTION_TEXT[correction],
                              "n_boot": n_boot, "seed": seed, "ci": ci, "psychometric": psychometric,
                              "n_participants": int(df["participant"].nunique()),
                              "participants": who, "participants_label": label,
                              "n_trials": int((~df["shared_copy"]).sum()),
                              "groups": (group_order(df["group"].unique()) if tasks
                                         else list(dict.fromkeys(table["group"])))})
    if out_dir is not None:
        _write(result, Path(out_dir), images, tasks=tasks, gee=gee, figures=figures, ci=ci)
    return result


# the named steps of :func:`analyze`, in its order; each appends its notes to ``notes``

def _select(responses, exclusions, kept_out, include_simulated: bool, include_incomplete: bool):
    """The trials to analyse: (df, who, exclusion report or None); raises
    :class:`ResponsesError` when none is left."""
    df = load_responses(responses, catch_groups=(exclusions or {}).get("catch_groups", ()))
    report = None
    if exclusions is not None:
        from .exclusions import apply_exclusions, kept_out_at_import, with_kept_out
        df, first = select_participants(df, include_simulated=include_simulated, include_incomplete=True)
        report = apply_exclusions(df, exclusions, include_incomplete=include_incomplete)
        if kept_out is None and isinstance(responses, (str, Path)):
            kept_out = kept_out_at_import([resolve_responses_path(responses)])
        report.flow = with_kept_out(report.flow, kept_out)
        df = report.kept()
    df, who = select_participants(df, include_simulated=include_simulated,
                                  include_incomplete=include_incomplete)
    if report is not None:
        who["simulated_left_out"] = first["simulated_left_out"]
    if df.empty:
        why = []
        if who["simulated_left_out"]:
            why.append(f"{len(who['simulated_left_out'])} simulated participant(s) are left out "
                       f"(pass --include-simulated to analyse them)")
        if who["incomplete_left_out"]:
            why.append(f"{len(who['incomplete_left_out'])} incomplete session(s) are left out "
                       f"(--include-incomplete)")
        raise ResponsesError(f"{responses if not isinstance(responses, pd.DataFrame) else 'responses'}: "
                             f"no trials to analyse: " + "; ".join(why or ["no participants"]))
    return df, who, report


def _describe(df: pd.DataFrame, tasks: bool, correction: str, n_boot: int, seed, ci: float):
    """Ratings and d′ per group and level: (table, participants, notes, the yes/no trials)."""
    if tasks:
        table, participants, notes = summarize_tasks(df, correction, n_boot, seed, ci)
        yes_no = split(df)[0]
    else:
        table, participants, notes = summarize(df, correction=correction, n_boot=n_boot, seed=seed, ci=ci)
        yes_no = df
    if "repeat" in df.columns:
        n_rep = int((pd.to_numeric(df["repeat"], errors="coerce").fillna(0) == 1)[~df["shared_copy"]].sum())
        if n_rep:
            notes.append(f"Repeats: {n_rep} trial(s) flagged for dropped frames were shown once more at "
                         f"the end of their web session ([session] repeat_dropped); the repeat's answer "
                         f"is used in place of the flagged first one (kept in the responses table with "
                         f"repeat = 0).")
    table, style_note = split_by_style(df, table)
    if style_note:
        notes.append(style_note)
    if df["shared_original"].any():
        shared = set(df.loc[df["shared_original"], "group"])
        notes.append("Shared original: the groups " + ", ".join(group_order(shared)) + " share one "
                     "original per base clip (shown `repetitions` times); its answers are the "
                     "level-0 cell of each of them, and their d′ are computed against it.")
    return table, participants, notes, yes_no


def _participant_notes(notes: list, who: dict, label: str, report) -> None:
    """The notes on who was analysed, put first."""
    notes.insert(0, "Participants: " + label + "."
                 + (f" Simulated participants left out: {', '.join(who['simulated_left_out'])}."
                    if who["simulated_left_out"] else "")
                 + (f" Incomplete sessions left out: {', '.join(who['incomplete_left_out'])}."
                    if who["incomplete_left_out"] else "")
                 + (" Simulated participants (flipstudy simulate) are included: these results "
                    "describe the observer model, not people." if who["simulated"] else ""))
    if report is not None:
        flow = ", ".join(f"{st} {n}" for st, n in zip(report.flow["stage"], report.flow["n"]))
        notes.insert(1, "Exclusions stated in the design ([exclusions]), applied before the analysis: "
                     + ("; ".join(report.rules) or "no rule") + f". Flow: {flow}. Excluded participants' "
                     "rows and the catch trials are kept in responses_exclusions.csv (excluded, "
                     "exclusion_rule), not analysed.")
    if who["n"] < MIN_PARTICIPANTS:
        notes.insert(1, f"With {who['n']} participant{'s' if who['n'] != 1 else ''} (fewer than "
                        f"{MIN_PARTICIPANTS}), the intervals over participants (bootstrap), the GEE "
                        f"tests (participants as clusters) and the thresholds are not meaningful: "
                        f"read them as descriptions of these answers only.")


def _gee_step(table, yes_no, df, notes: list, *, gee: bool, tasks: bool, ci: float):
    """Each level against its original: (table with the GEE columns, the GEE frame)."""
    if not (gee and len(yes_no)):
        return table, pd.DataFrame(columns=["group", "level", "gee_or", "gee_ci_low", "gee_ci_high",
                                            "gee_p", "gee_p_holm", "gee_note"])
    g = gee_levels(yes_no, ci=ci)
    table = table.merge(g, on=["group", "level"], how="left")
    notes.append("Each level against its group's original: GEE logistic model of P(incorrect) on "
                 "level as a category (reference: level 0), Binomial family, exchangeable "
                 "working correlation, participants as clusters, bias-reduced (Mancl–DeRouen) "
                 "sandwich covariance; odds ratios with 95 % Wald CIs, p values Holm-adjusted "
                 "over all levels of all groups in gee_p_holm.")
    for msg in sorted(set(m for m in g["gee_note"] if m)):
        notes.append("GEE: " + msg)
    if tasks and len(yes_no) < len(df):
        notes.append("GEE: yes/no constant-stimuli groups only (a 2AFC group has no level-0 cell; "
                     "QUEST+ levels are chosen by the procedure).")
    return table, g


def _fit_step(df, notes: list, *, tasks: bool, psychometric: str, ci: float, seed):
    """A psychometric function per group: (fits, thresholds frame)."""
    if tasks:
        fits, fit_notes = fit_tasks(df, psychometric, ci, seed)
        thresholds = thresholds_frame(fits)
    else:
        fits, fit_notes = fit_psychometric(df, psychometric, ci=ci, seed=seed)
        thresholds = pd.DataFrame([f.row() for f in fits]) if fits else pd.DataFrame(
            columns=["group", "method", "threshold", "threshold_ci_low", "threshold_ci_high", "reached"])
    notes += fit_notes
    if fits:
        notes.append(
            "Psychometric functions: P(incorrect) = γ + (1 − γ − λ)·Φ((|level| − m)/s) per group "
            "(psignifit; see analysis.stats). Detection threshold x*: the error at which "
            "P(incorrect) is halfway between the base rate γ and 1, P(x*) = (1 + γ)/2; "
            "'not reached' when x* lies beyond the largest tested level.")
        notes.append("psignifit 4: Schütt, Harmeling, Macke & Wichmann (2016), Vision Research 122, "
                     "105–123; intervals of x* are 95 % credible intervals from its posterior.")
        for f in fits:
            if not f.reached:
                why = next((p for p in f.note.split("; ") if p.startswith("not reached")), "not reached")
                notes.append(f"{f.group}: threshold {why}")
    return fits, thresholds


def _participant_threshold_step(df, fits, quest_specs, notes: list):
    """Per-participant thresholds of answers with tasks: (per participant, per group)."""
    per_participant, t_notes = participant_thresholds(df, quest_specs)
    per_group = group_thresholds(per_participant, fits)
    notes += t_notes
    notes.append("Per-participant thresholds (thresholds_participants.csv): each participant's "
                 "answers to a group replayed through that group's QUEST+ model (the psychometric "
                 "function above on a grid of m, width and γ; 2AFC: γ = ½; λ fixed), x* = "
                 "posterior mean with its 95 % equal-tailed posterior interval, the same definition "
                 "for adaptive and constant groups; thresholds_groups.csv: their distribution "
                 "per group beside the pooled psignifit x*.")
    return per_participant, per_group


def _kinds_step(df, notes: list) -> dict:
    """group → error kind, with the note on pose-rate groups."""
    kinds = group_kinds(df)
    if any(is_pose_rate(k) for k in kinds.values()):
        notes.append("Pose-rate groups (" + ", ".join(g for g in group_order(kinds) if is_pose_rate(kinds[g]))
                     + "): levels are poses per second N (0: the original motion); their psychometric "
                     "function and threshold x* are against the time each pose is held, 1000/N ms "
                     "(the original at 0 ms), so x* in ms is N* = 1000/x* poses per second.")
    return kinds


def _write(result: Result, out: Path, images, *, tasks: bool, gee: bool, figures: bool, ci: float) -> None:
    """Every file of ``result`` in ``out``: tables, figures, ``notes.md`` and ``summary.json``."""
    out.mkdir(parents=True, exist_ok=True)
    _write_tables(result, out, tasks=tasks, gee=gee)
    if figures:
        _write_figures(result, out, images, tasks=tasks, ci=ci)
    files = result.files
    files["notes.md"] = out / "notes.md"
    files["summary.json"] = out / "summary.json"
    files["notes.md"].write_text(_notes_md(result), encoding="utf-8")
    files["summary.json"].write_text(json.dumps(result.to_dict(), indent=2, ensure_ascii=False) + "\n",
                                     encoding="utf-8")


def _write_tables(result: Result, out: Path, *, tasks: bool, gee: bool) -> None:
    """The tables of ``result`` as CSV, Markdown and LaTeX files in ``out`` (into ``result.files``)."""
    files, table, report = result.files, result.table, result.exclusions
    correction, label = result.settings["correction"], result.settings["participants_label"]
    files["table.csv"] = out / "table.csv"
    table.to_csv(files["table.csv"], index=False)
    files["table_paper.csv"] = out / "table_paper.csv"
    result.paper.to_csv(files["table_paper.csv"], index=False)
    caption = PAPER_CAPTION + f" Correction for rates of 0 or 1: {correction}. {label}."
    if tasks and (table["task"] == "2afc").any():
        caption += " 2AFC groups: percent correct choices (d′ = √2·z(P correct))."
    if len(table):
        files["table_paper.md"] = out / "table_paper.md"
        files["table_paper.md"].write_text(to_markdown(table, caption, result.kinds), encoding="utf-8")
        files["table_paper.tex"] = out / "table_paper.tex"
        files["table_paper.tex"].write_text(to_latex(table, caption, kinds=result.kinds), encoding="utf-8")
    files["participants.csv"] = out / "participants.csv"
    result.participants.to_csv(files["participants.csv"], index=False)
    if report is not None:
        rows = report.answers()                            # the answers as given, once each
        for name, frame in (("flow.csv", report.flow), ("exclusions_participants.csv", report.participants),
                            ("responses_exclusions.csv", rows)):
            files[name] = out / name
            frame.to_csv(files[name], index=False)
    if gee and len(result.gee):
        files["levels_vs_original.csv"] = out / "levels_vs_original.csv"
        result.gee.to_csv(files["levels_vs_original.csv"], index=False)
    if result.fits:
        files["thresholds.csv"] = out / "thresholds.csv"
        result.thresholds.to_csv(files["thresholds.csv"], index=False)
    if result.participant_thresholds is not None:
        for name, frame in (("thresholds_participants.csv", result.participant_thresholds),
                            ("thresholds_groups.csv", result.group_thresholds)):
            files[name] = out / name
            frame.to_csv(files[name], index=False)


def _write_figures(result: Result, out: Path, images, *, tasks: bool, ci: float) -> None:
    """The figures of ``result`` (PDF + PNG) in ``out``; the sheet's notes join ``result.notes``."""
    from .figures import (dprime_figure, psychometric_figure, ratings_figure, save, sheet_figure,
                          thresholds_figure)
    files, table, fits, kinds = result.files, result.table, result.fits, result.kinds
    per_participant, label = result.participant_thresholds, result.settings["participants_label"]
    ci_label = f"{ci:.0%} CI"
    yn_table = table[table["task"] == "yes-no"] if tasks else table
    yn_fits = [f for f in fits if getattr(f, "task", "yes-no") == "yes-no"]
    afc_fits = [f for f in fits if getattr(f, "task", "yes-no") == "2afc"]
    figs = []
    if len(yn_table):
        figs.append(("ratings", ratings_figure(yn_table, ci_label, kinds)))
    if len(table):
        figs.append(("dprime", dprime_figure(table, ci_label, kinds)))
    if yn_fits:
        figs.append(("psychometric", psychometric_figure(yn_fits, yn_table, "psignifit 4 (Bayesian, MAP)")))
    if afc_fits:
        figs.append(("psychometric_2afc", psychometric_figure(
            afc_fits, table[table["task"] == "2afc"], "psignifit 4, 2AFC (γ = ½)",
            ylabel="P(original chosen)")))
    if per_participant is not None and len(per_participant):
        figs.append(("thresholds_participants", thresholds_figure(per_participant, result.group_thresholds)))
    if result.exclusions is not None:
        from .exclusions import flow_figure
        figs.append(("flow", flow_figure(result.exclusions.flow)))
    for name, fig in figs:
        for p in save(_labelled(fig, label), out / name):
            files[p.name] = p
    imgs = _normalise_images(images)
    fig, sheet_notes = sheet_figure(yn_fits, yn_table if len(yn_table) else table, imgs)
    result.notes += sheet_notes
    for p in save(_labelled(fig, label), out / "sheet"):
        files[p.name] = p


def _labelled(fig, label: str):
    """The participants the figure shows, in small type: the title of a figure legend
    (so it never lies over its entries), else under everything else."""
    from .figures import style
    with style():
        if fig.legends:
            leg = fig.legends[0]
            leg.set_title(label, prop={"size": 7})
            leg.get_title().set_color("#444444")
        else:
            fig.supxlabel(label, fontsize=7, color="#444444")
    return fig


def _notes_md(r: Result) -> str:
    s = r.settings
    lines = ["# Analysis notes", "",
             f"{s['participants_label']}; {s['n_trials']} trials, groups: "
             f"{', '.join(s['groups'])}.", "",
             f"Correction for rates of 0 or 1: **{s['correction']}** — {s['correction_text']}.", ""]
    lines += [f"- {n}" for n in r.notes]
    if r.exclusions is not None:
        lines += ["", "## Exclusions (stated in the design before the data)", ""]
        lines += [f"- {x}" for x in r.exclusions.rules] or ["- no rule"]
        lines += ["", "| stage | participants |", "|:--|--:|"]
        lines += [f"| {st} | {n} |" for st, n in zip(r.exclusions.flow["stage"], r.exclusions.flow["n"])]
        lines.append("")
    lines += ["", "## Table (paper layout)", "", to_markdown(r.table, s["participants_label"] + ".", r.kinds)]
    if len(r.thresholds):
        lines += ["## Detection thresholds", "",
                  "| group | x* (%) | interval | P(reached) | γ | λ | note |", "|:--|--:|:--|--:|--:|--:|:--|"]
        for _, t in r.thresholds.iterrows():
            x = "not reached" if not t["reached"] else f"{t['threshold']:.1f}"
            if is_pose_rate(r.kinds.get(t["group"])):      # a hold time, not a percent
                x = x if not t["reached"] else f"{x} ms = {pose_rate_of(t['threshold']):.1f} poses/s"
            hi = "open" if not np.isfinite(t["threshold_ci_high"]) else f"{t['threshold_ci_high']:.1f}"
            lo = "—" if not np.isfinite(t["threshold_ci_low"]) else f"{t['threshold_ci_low']:.1f}"
            lines.append(f"| {t['group']} | {x} | [{lo}, {hi}] | {t['p_reached']:.2f} | "
                         f"{t['gamma']:.2f} | {t['lambda']:.2f} | {t['note']} |")
        lines.append("")
    if r.group_thresholds is not None and len(r.group_thresholds):
        lines += ["## Per-participant thresholds (distribution per group)", "",
                  "| group | task | method | N | mean x* (%) | SD | quartiles | mean interval width |",
                  "|:--|:--|:--|--:|--:|--:|:--|--:|"]
        for _, t in r.group_thresholds.iterrows():
            lines.append(f"| {t['group']} | {t['task']} | {t['method']} | {t['n_participants']} | "
                         f"{t['mean']:.1f} | {t['sd']:.1f} | {t['q25']:.1f}, {t['median']:.1f}, "
                         f"{t['q75']:.1f} | {t['mean_ci_width']:.1f} |")
        lines.append("")
    return "\n".join(lines) + "\n"

"""The pipeline as typed steps: build, render, simulate, export, import, analyze,
reproduce.  Each step is one call that takes what the command line names (files,
folders, options, a cluster address) and returns a result of
:mod:`flipstudy.results` (a frozen dataclass with ``summary()`` — the text
``flipstudy`` prints — and ``save_json``/``load_json``).  The CLI
(:mod:`flipstudy.study.cli`) parses, calls one step and prints its summary.

Examples
--------
>>> import tempfile, pathlib
>>> from flipstudy.study import pipeline
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = make_demo_study(pathlib.Path(tmp.name) / "s", videos=False)   # 8 trials
>>> pipeline.simulate(study, 2, seed=1).participants
('sim001', 'sim002')
>>> exp = pipeline.export(study, include_simulated=True)
>>> exp.rows, exp.simulated, exp.responses.name
(16, ('sim001', 'sim002'), 'responses.csv')
>>> type(exp).load_json(exp.save_json(study / "export.json")) == exp
True
>>> tmp.cleanup()
"""
from __future__ import annotations

from pathlib import Path

from flipstudy.records import AnalyzeReport, PlanRow, SessionStatus
from flipstudy.results import (AnalyzeResult, BuildResult, ExportResult, ImportResult, RenderResult,
                               PlanResult, ReproduceResult, SimulateResult,
                               StatusResult)

__all__ = ["build", "render", "simulate", "export", "import_results", "analyze", "reproduce",
           "status", "plan", "quest_specs", "group_grids"]


def build(design, out, *, force: bool = False, progress: bool = True, cluster: str | None = None
          ) -> BuildResult:
    """``flipstudy stimuli``: the stimuli of ``design`` (a DESIGN.toml path or a loaded
    :class:`~flipstudy.stimuli.design.Design`) into the study folder ``out``.  A folder
    replaced with ``force`` must hold no real participant's answers; what it held is
    the result's ``replaced``."""
    import dataclasses

    from flipstudy.stimuli.design import load_design
    from flipstudy.stimuli.stimset import build_stimuli

    from .archive import describe, refuse_real_answers
    from .cluster import open_cluster
    if not hasattr(design, "groups"):
        design = load_design(design)
    replaced = {}

    def replace_check(folder, foreign):
        # refuses while the study holds any real answer or another study; what other
        # commands made and recorded goes with the old set, every other file is kept
        replaced["answers"] = refuse_real_answers(folder, foreign, shown=Path(out))
        replaced.update(_replaceable(folder, Path(out)))
        return replaced["removed"]

    from .lock import StudyLock, study_closed
    with StudyLock(out, "stimuli"), study_closed(out, "stimuli --force"), open_cluster(cluster) as c:
        res = build_stimuli(design, out, force=force, progress=progress, replace_check=replace_check,
                            cluster=c)
    if replaced:
        kept = replaced["kept"]
        res = dataclasses.replace(res, replaced=(
            f"replaced {out}: it held no real participant's answers ({describe(replaced['answers'])}); "
            f"removed with it: {', '.join(replaced['gone']) or 'nothing else'}"
            + (f"; kept, as they were: {', '.join(kept[:6])}{' ...' if len(kept) > 6 else ''}"
               if kept else "")))
    return res


def _replaceable(folder: Path, shown: Path) -> dict:
    """What ``stimuli --force`` does with the old study ``folder``: ``removed`` (the
    recorded outputs that go with the old set), ``gone`` (those present, by top-level
    name) and ``kept`` (every other file, which stays); refuses a study inside it."""
    from flipstudy.errors import StudyHasAnswersError
    from flipstudy.stimuli.replace import kept_files, own_files

    from .owned import files_below, recorded_outputs, study_below
    inner = study_below(folder)
    if inner is not None:
        raise StudyHasAnswersError(f"{shown} holds the study {inner}; `flipstudy stimuli --force` never "
                              f"deletes a study: move it out first, or build into another --out")
    removed = recorded_outputs(folder)
    own = own_files(folder)
    gone = sorted({f.split("/")[0] + ("/" if "/" in f else "") for f in files_below(folder)
                   if f in removed and f.split("/")[0] not in own})
    return {"removed": removed, "gone": gone, "kept": kept_files(folder, removed)}


def render(study_dir, *, cluster: str | None = None, **options) -> RenderResult:
    """``flipstudy render``: :func:`flipstudy.render.study.render_study` (``options`` are
    its keywords), on the Dask cluster at ``cluster`` when given."""
    from flipstudy.render.study import render_study

    import contextlib

    from .cluster import open_cluster
    from .lock import StudyLock, study_closed
    # --force replaces videos a `run` server may be showing
    held = study_closed(study_dir, "render --force") if options.get("force") else contextlib.nullcontext()
    with StudyLock(getattr(study_dir, "folder", study_dir), "render"), held, open_cluster(cluster) as c:
        return render_study(study_dir, cluster=c, replace_check=lambda names: _refuse_replacing_seen(
            study_dir, names), **options)


def _refuse_replacing_seen(study_dir, names) -> None:
    """Refuse to make again videos of a study holding real participants' answers:
    they answered the videos as they are, and the next participant would see others."""
    from .archive import answers_in, describe, holds_answers
    from flipstudy.errors import StudyHasAnswersError
    a = answers_in(study_dir)
    if not holds_answers(a):
        return
    d = Path(study_dir)
    raise StudyHasAnswersError(
        f"{d} holds {describe(a)}; rendering now would replace {len(names)} video(s) they may have "
        f"seen (first: {names[0]}), so later participants would answer other pictures. The videos "
        f"as they are still serve `flipstudy run`. For the new look, build a new study "
        f"(`flipstudy stimuli {d / 'design.toml'} --out NEW && flipstudy render NEW`), or move "
        f"this one aside first with `flipstudy archive {d}`")


def status(study_dir) -> StatusResult:
    """``flipstudy status``: the sessions of a study (none before the first), the
    local ones and those ``import-web`` imported (source ``web-…``)."""
    from flipstudy.errors import FlipstudyFileNotFoundError

    from .export import status as _status
    from .store import db_path
    d = Path(study_dir)
    if not (d / "manifest.csv").is_file():
        raise FlipstudyFileNotFoundError(f"{d} is not a study folder (no manifest.csv)")
    from .web.status import web_status
    rows = _status(d) if (db_path(d).exists() or db_path(d).is_symlink()) else []
    return StatusResult(study=d, sessions=tuple(SessionStatus.from_dict(r) for r in [*rows, *web_status(d)]))


def simulate(study_dir, participants: int, *, model=None, seed: int = 0, strengths=None) -> SimulateResult:
    """``flipstudy simulate``: simulated observers answer every trial
    (:func:`flipstudy.study.simulate.simulate`; ``strengths``: a comparison study's
    known source strengths)."""
    from .simulate import sim_ids, simulate as _simulate
    ids = _simulate(study_dir, participants, model=model, seed=seed, strengths=strengths)
    return SimulateResult(study=str(study_dir), participants=tuple(ids),
                          finished_before=tuple(p for p in sim_ids(participants) if p not in ids))


def export(study_dir, out=None, *, participants_out=None, include_simulated: bool = False) -> ExportResult:
    """``flipstudy export``: :func:`flipstudy.study.export.export_responses`."""
    from .export import export_responses
    return export_responses(study_dir, out, participants_out=participants_out,
                            include_simulated=include_simulated)


def import_results(study_dir, files) -> ImportResult:
    """``flipstudy import-web``: :func:`flipstudy.study.web.importer.import_web`."""
    from .web.importer import import_web
    return import_web(study_dir, files)


def analyze(responses, out=None, *, images=None, **options) -> AnalyzeResult:
    """``flipstudy analyze``: one or more response tables (or study folders) analysed
    together into ``out`` (default: beside the first, ``analysis/``), with the QUEST+
    models of the design beside the first table (to replay adaptive answers).
    ``images``: the figure sheet's images (label → path); ``options`` go to
    :func:`flipstudy.analysis.pipeline.analyze`."""
    from flipstudy.analysis.io import combine_responses, resolve_responses_path
    from flipstudy.analysis.pipeline import analyze as _analyze
    from flipstudy.analysis.tables import to_markdown
    from flipstudy.stimuli.design import load_design
    from .export import refuse_no_answers
    responses = list(responses) if isinstance(responses, (list, tuple)) else [responses]
    for r in responses:                    # no answers yet: the commands that give some
        refuse_no_answers(r)
    src = resolve_responses_path(responses[0])
    from .frozen import refuse_changed_design
    for r in responses:                    # a study whose design changed after its answers
        refuse_changed_design(resolve_responses_path(r).parent, "analyze")
    out = Path(out) if out else src.parent / "analysis"
    design = src.parent / "design.toml"
    if not design.is_file() and src.parent.name == "web":     # import-web's STUDY/web/responses.csv
        design = src.parent.parent / "design.toml"
    d = load_design(design) if design.is_file() else None
    specs = quest_specs(d) if d is not None else None
    rules = d.exclusions.to_dict() if d is not None and not d.exclusions.is_default else None
    if len(responses) > 1:
        src = combine_responses(responses)
    # a study folder, or a response table inside one (its exported responses.csv): the
    # sheet shows the study's own ghosts and trails, where it has rendered them
    if not images and len(responses) == 1 and (src.parent / "manifest.csv").is_file() \
            and (src.parent / "render").is_dir():
        from flipstudy.stimuli.contract import StimulusSet
        from .reproduce import sheet_images        # the study's own ghosts and trails
        images = sheet_images(StimulusSet.read(src.parent, files=False, design=False),
                              src.parent / "render")
    from flipstudy.analysis.exclusions import kept_out_at_import    # the runs import-web kept out
    kept_out = kept_out_at_import([resolve_responses_path(r) for r in responses])
    res = _analyze(src, out, images=images or None, quest_specs=specs, exclusions=rules, kept_out=kept_out,
                   **options)
    return AnalyzeResult(out=out, report=AnalyzeReport.from_dict(res.to_dict()),
                         table_markdown=to_markdown(res.table))


def reproduce(out, *, cluster: str | None = None, **options) -> ReproduceResult:
    """``flipstudy reproduce``: :func:`flipstudy.study.reproduce.reproduce`, on the
    Dask cluster at ``cluster`` when given."""
    from .cluster import open_cluster
    from .reproduce import reproduce as _reproduce
    with open_cluster(cluster) as c:
        return _reproduce(out, cluster=c, **options)


def plan(design_path, *, groups=(), task: str | None = None, target_width: float = 15.0,
         observers: int = 200, seed: int = 0, max_trials: int = 200, threshold=(25.0, 8.0)
         ) -> PlanResult:
    """``flipstudy plan``: QUEST+ against constant stimuli for each group of a design
    (``groups``: only these), with simulated observers
    (:func:`flipstudy.analysis.plan.plan_group`)."""
    from flipstudy.analysis.plan import format_plan, plan_group
    from flipstudy.errors import FlipstudyValueError
    from flipstudy.stimuli.design import load_design
    design = load_design(design_path)
    chosen = [g for g in design.groups if not groups or g.name in groups]
    missing = set(groups) - {g.name for g in design.groups}
    if missing:
        raise FlipstudyValueError(f"{design_path}: no group {', '.join(sorted(missing))} (groups: "
                                  f"{', '.join(g.name for g in design.groups)})")
    if observers < 10 or max_trials < 5:
        raise FlipstudyValueError("--observers: at least 10; --max-trials: at least 5")
    rows = []
    for g in chosen:
        t = _task(design, g, task)
        quest, constant = group_grids(g.levels, t)
        rows += plan_group(g.name, t, quest, constant, target_width=target_width,
                           settings=_settings(g), n_observers=observers, max_trials=max_trials,
                           seed=seed, threshold=tuple(threshold))
    clean = tuple({k: (v if not isinstance(v, float) or v == v and abs(v) != float("inf") else None)
                   for k, v in r.items()} for r in rows)
    return PlanResult(rows=tuple(PlanRow.from_dict(r) for r in clean), table=format_plan(rows, target_width, max_trials=max_trials),
                      observers=observers, threshold=tuple(threshold), seed=seed)


# ---- a design's groups as the analysis's QUEST+ models (analyze and plan)

#: a group with at most this many levels is a constant-stimuli design as it stands;
#: QUEST+ then chooses from a 1 % grid over its range
CONSTANT_MAX_LEVELS = 10


def _settings(group):
    from dataclasses import asdict

    from flipstudy.analysis.adaptive import QuestSettings
    q = getattr(group, "quest", None)
    if q is None:
        return QuestSettings()
    if isinstance(q, QuestSettings):
        return q
    return QuestSettings(**asdict(q))


def _task(design, group, override=None) -> str:
    return override or getattr(group, "task", None) or getattr(design, "task", None) or "yes-no"


def quest_specs(design) -> dict:
    """group name → (levels, task, QuestSettings) of every group of a loaded design."""
    return {g.name: (list(g.levels), _task(design, g), _settings(g)) for g in design.groups}


def group_grids(levels, task: str):
    """(QUEST+ grid, constant levels) for a group's levels: a dense grid is QUEST+'s and
    constant stimuli get 5 levels spread over it; a few levels are the constant design and
    QUEST+ gets a 1 % grid over their range.

    >>> quest, constant = group_grids([0, 10, 20, 30], "2afc")
    >>> quest[[0, -1]].tolist(), constant.tolist()
    ([0.0, 30.0], [10.0, 20.0, 30.0])
    """
    import numpy as np
    lv = np.unique(np.abs(np.asarray(levels, float)))
    top = float(lv.max())
    if len(lv) > CONSTANT_MAX_LEVELS:
        quest = lv
        constant = np.unique(np.round(np.linspace(0, top, 5) / (lv[1] - lv[0])) * (lv[1] - lv[0]))
    else:
        quest, constant = np.arange(0.0, np.floor(top) + 1.0), lv
    if task == "2afc":
        constant = constant[constant > 0]
    return quest, constant

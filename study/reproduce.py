"""``flipstudy reproduce``: the whole platform on the embedded default, end to end.

The study of Majkowska & Faloutsos 2007 (Section 7) on the built-in, physically
exact flips:

1. ``design.toml``      the paper's design (what ``flipstudy init`` writes)
2. ``study/``           46 stimuli, each measured by the analyser (``flipstudy stimuli``)
3. ``study/render/``    stimulus videos, ghost and marker-trail composites, one
                        camera and one style for all (``flipstudy render``)
4. ``study/sessions.sqlite``  a simulated panel of 19 participants answering every
                        trial through the session runner's storage path
                        (``flipstudy simulate``; stored as source=simulated),
                        exported with ``--include-simulated`` to ``responses.csv``
                        (``simulated=true`` on every row) and analysed as such
5. ``analysis/``        mean ratings, d′, GEE tests, psychometric fits, the
                        Table-2 layout (CSV, Markdown, LaTeX) and the figures,
                        with a figure sheet beside a ghost and a trail composite
                        of the original backflip and its strongest error

Everything is built in a hidden folder beside ``OUT`` and moved into place at
the end, so an interrupted run leaves nothing half-written.  The simulated
observers follow the paper's Table 2 (see :mod:`flipstudy.study.simulate`): the table that
comes out should resemble the paper's, within the noise of 19 participants.
"""
from __future__ import annotations

import contextlib
import json

from flipstudy.errors import ReproduceError
from flipstudy.records import ReproduceFiles, StageSeconds, Threshold
from flipstudy.results import ReproduceResult

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from flipstudy.stimuli._progress import Heartbeat, Progress
from flipstudy.stimuli.contract import Stimulus, StimulusSet

#: the original and its strongest error shown beside the curves on the sheet
SHEET_ORIGINAL = "backflip_reference"
SHEET_ERROR = "backflip_abrupt-decrease_50"
#: video size of the reproduce run (as ``flipstudy render``'s default)
SIZE = (640, 480)
#: the reproduce run renders in ``flipstudy render``'s default style (FXAA
#: anti-aliasing), so ``flipstudy render OUT/study`` finds every output up to date
STYLE: dict = {}


def sheet_label(row: Stimulus) -> str:
    r"""A sheet panel's title: the stimulus and its error (kind, profile, signed
    nominal level).

    >>> from flipstudy.vocab.kinds import AM
    >>> sheet_label(Stimulus("backflip_abrupt-decrease_50", "backflip", "abrupt-decrease",
    ...                      AM.name, "abrupt", 50.0, nominal_error_pct=-50.0))
    'backflip_abrupt-decrease_50\nangular momentum, abrupt, −50 %'
    >>> sheet_label(Stimulus("backflip_reference", "backflip", "reference", "reference"))
    'backflip_reference\noriginal (no error)'
    """
    name, kind = row.stimulus, row.kind
    if kind == "reference" or not row.nominal_error_pct:
        return f"{name}\noriginal (no error)"
    level = row.nominal_error_pct
    parts = [kind.replace("-", " ")] + ([row.profile] if row.profile else [])
    return f"{name}\n" + ", ".join(parts) + f", {'+' if level > 0 else '−'}{abs(level):g} %"


def sheet_images(stimuli: StimulusSet, render_dir) -> dict:
    """The figure sheet's images of a study (label → path): the ghost and trail composites of
    an original (:data:`SHEET_ORIGINAL`, else the first reference or level-0 stimulus) and of
    its clip's strongest error (:data:`SHEET_ERROR`, else the largest |nominal error|), those
    of the pair that ``render_dir`` holds; ``analyze STUDY`` and ``reproduce`` show the same."""
    rows = list(stimuli)
    plain = [s for s in rows if s.kind == "reference" or not s.nominal_error_pct]
    if SHEET_ORIGINAL in stimuli and SHEET_ERROR in stimuli:
        pair = [stimuli[SHEET_ORIGINAL], stimuli[SHEET_ERROR]]
    elif plain:
        errs = [s for s in rows if s.clip == plain[0].clip and s.nominal_error_pct]
        pair = plain[:1] + ([max(errs, key=lambda s: abs(s.nominal_error_pct))] if errs else [])
    else:
        return {}
    out = {f"{what}s: {sheet_label(s)}": Path(render_dir) / f"{s.stimulus}_{what}.png"
           for what in ("ghost", "trail") for s in pair}
    return {k: p for k, p in out.items() if p.is_file()}


def _say(quiet: bool, text: str) -> None:
    if not quiet:
        print(text, file=sys.stderr, flush=True)


def _swap(value, pairs):
    if isinstance(value, str):
        for old, new in pairs:
            value = value.replace(old, new)
        return value
    if isinstance(value, list):
        return [_swap(v, pairs) for v in value]
    if isinstance(value, dict):
        return {k: _swap(v, pairs) for k, v in value.items()}
    return value


def _repoint(work: Path, out: Path) -> None:
    """Make the records written during the build (``render.json``, ``summary.json``,
    ``notes.md``) name ``out``, where the build is moved, instead of the temporary
    ``work`` folder, which is gone once the build is in place."""
    pairs = [(str(work.resolve()), str(out.resolve())), (str(work), str(out))]
    for rel in ("study/render/render.json", "analysis/summary.json"):
        p = work / rel
        if p.is_file():
            data = _swap(json.loads(p.read_text(encoding="utf-8")), pairs)
            p.write_text(json.dumps(data, indent=2, ensure_ascii=rel.startswith("study")) + "\n", encoding="utf-8")
    notes = work / "analysis" / "notes.md"
    if notes.is_file():
        notes.write_text(_swap(notes.read_text(encoding="utf-8"), pairs), encoding="utf-8")


def _outputs(out: Path) -> dict:
    """What a run leaves at ``out``, by name (:class:`~flipstudy.results.ReproduceResult` ``files``)."""
    a = out / "analysis"
    return {
        "design": out / "design.toml",
        "manifest": out / "study" / "manifest.csv",
        "stimuli": out / "study",
        "videos": out / "study" / "render",
        "render_settings": out / "study" / "render" / "render.json",
        "sessions": out / "study" / "sessions.sqlite",
        "responses": out / "study" / "responses.csv",
        "participants": out / "study" / "participants.csv",
        "analysis": a,
        "table": a / "table.csv",
        "table_paper": a / "table_paper.md",
        "table_latex": a / "table_paper.tex",
        "figure_ratings": a / "ratings.png",
        "figure_dprime": a / "dprime.png",
        "figure_psychometric": a / "psychometric.png",
        "figure_sheet": a / "sheet.png",
        "notes": a / "notes.md",
    }


def _guard(out: Path, stack=None) -> None:
    """``--force`` never replaces real participants' answers, nor a study a ``flipstudy
    run`` server has open (``stack``: hold them closed until it exits), nor a file that
    an earlier run did not record making (:data:`flipstudy.study.owned.MADE_RECORD`)."""
    from .archive import refuse_real_answers
    from .lock import study_closed
    from .owned import made_by_record, refuse_not_made
    if not out.is_dir():
        return
    for d in [out, *sorted(p for p in out.iterdir() if p.is_dir() and p.name != ".locks")]:
        hold = study_closed(d, "reproduce --force")
        if stack is None:
            with hold:
                pass
        else:
            stack.enter_context(hold)
        refuse_real_answers(d, shown=d, command="reproduce --force")
    refuse_not_made(out, made_by_record(out), "reproduce --force", "the earlier reproduce run")


def _move_into_place(work: Path, out: Path) -> None:
    """Record what the run made, then put ``work`` at ``out`` (checked once more)."""
    from .owned import record_made
    record_made(work, "reproduce")
    with contextlib.ExitStack() as held:
        _guard(out, held)          # answers may have arrived while the run went on
        if out.exists():
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
            work.rename(out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            work.rename(out)


def reproduce(out, *, participants: int = 19, seed: int = 1, jobs: int | None = None,
              size=SIZE, force: bool = False, quiet: bool = False, cluster=None) -> ReproduceResult:
    """Run the whole pipeline into ``out``; returns a :class:`~flipstudy.results.ReproduceResult`
    (the files, the seconds per stage, the counts, the table as Markdown, the thresholds).

    Examples
    --------
    Not run with the doctests: the whole pipeline (52 stimuli rendered) takes
    about two minutes; ``tests/study/test_reproduce.py`` runs it.

    >>> r = reproduce("paper/")                  # doctest: +SKIP
    >>> sorted(r.files)[:3]                      # doctest: +SKIP
    ['analysis', 'design', 'figure_dprime']
    """
    from flipstudy.analysis.pipeline import analyze
    from flipstudy.analysis.tables import to_markdown
    from flipstudy.render.study import render_study
    from flipstudy.render.style import Style
    from flipstudy.stimuli.design import PAPER_DESIGN, load_design
    from flipstudy.stimuli.stimset import build_stimuli

    from .export import export_responses
    from .simulate import simulate

    shown, out = str(out), Path(out)
    if out.exists() and not force and (not out.is_dir() or any(out.iterdir())):
        raise ReproduceError(f"{out} exists and is not empty; choose another --out or pass --force "
                             f"to replace it")
    _guard(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    seconds: dict = {}
    t_all = time.perf_counter()
    try:
        n_stages = 5

        def stage(i, name):
            _say(quiet, f"[{i}/{n_stages}] {name}")
            return time.perf_counter()

        t = stage(1, "design: the paper's study (Section 7), written to design.toml")
        design_path = work / "design.toml"
        design_path.write_text(PAPER_DESIGN, encoding="utf-8")
        design = load_design(design_path)
        seconds["design"] = time.perf_counter() - t

        t = stage(2, "stimuli: inject and measure every error")
        study = work / "study"
        build_stimuli(design, study, progress=not quiet, cluster=cluster)
        stimuli = StimulusSet.read(study)             # read and checked once, then handed on
        worst = max(abs(r.measured_error_pct - r.nominal_error_pct) for r in stimuli.tests)
        seconds["stimuli"] = time.perf_counter() - t

        aa = Style.from_dict(STYLE).anti_aliasing
        t = stage(3, f"render: videos, ghost and trail composites at {size[0]}x{size[1]} "
                     f"({aa.upper() if aa != 'none' else 'no'} anti-aliasing)")
        rec = render_study(stimuli, what=("video", "ghost", "trail"), size=size, jobs=jobs,
                           style=STYLE, progress=not quiet, cluster=cluster)
        seconds["render"] = time.perf_counter() - t

        t = stage(4, f"sessions: {participants} simulated participants (observers of the paper's "
                     f"Table 2), exported")
        bar = Progress(participants, "participants", not quiet)
        try:
            simulate(stimuli, participants, seed=seed, progress=lambda pid, session: bar.step(pid))
        finally:
            bar.close()
        exp = export_responses(stimuli, include_simulated=True)    # marked simulated=true
        seconds["sessions"] = time.perf_counter() - t

        t = stage(5, "analysis: ratings, d′, GEE, psychometric fits, tables, figures")
        render_dir = study / "render"
        images = sheet_images(stimuli, render_dir)
        with Heartbeat("analysis", enabled=not quiet):
            result = analyze(exp.responses, work / "analysis", images=images, seed=seed,
                             include_simulated=True)
        seconds["analysis"] = time.perf_counter() - t

        _repoint(work, out)               # the records name OUT, not the build folder
        _move_into_place(work, out)       # nothing half-written is ever at OUT
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    seconds["total"] = time.perf_counter() - t_all

    files = _outputs(out)
    missing = [str(p) for p in files.values() if not p.exists()]
    if missing:
        raise ReproduceError(f"the run finished but these outputs are missing: {missing}")
    return ReproduceResult(
        out=str(shown).rstrip("/"), files=ReproduceFiles.from_dict({k: str(v) for k, v in files.items()}),
        seconds=StageSeconds.from_dict(dict(seconds)), n_stimuli=len(stimuli), worst_gap_pct=worst,
        n_videos=sum(1 for s in rec.record.stimuli.values() if "video" in s.files),
        n_responses=exp.rows, n_simulated=len(exp.simulated), table_md=to_markdown(result.table),
        thresholds=tuple(Threshold.from_dict(t) for t in result.to_dict()["thresholds"]))

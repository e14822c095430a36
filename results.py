"""The typed results of the pipeline's steps (see :mod:`flipstudy.study.pipeline`).

Each step — build, render, simulate, export, import, analyze, reproduce —
returns one frozen dataclass of this module: its fields are what the step did
(files written, counts, participants), :meth:`~StepResult.summary` is the text
``flipstudy`` prints for it, and :meth:`~StepResult.save_json` /
:meth:`~StepResult.load_json` round-trip it through a JSON file.  Results are
read by attribute (none is indexed like a dict); what a field holds beyond
numbers, text and paths is a typed record of :mod:`flipstudy.records`.  Like
:mod:`flipstudy.errors`, the module sits at the package root and imports none of
the four parts, so every part can return its step's result.

Examples
--------
>>> import tempfile, pathlib
>>> r = ExportResult(responses=pathlib.Path("s/responses.csv"),
...                  participants=pathlib.Path("s/participants.csv"), truth=None, rows=88,
...                  sessions=1, real=("P01",))
>>> print(r.summary())
wrote 88 responses of 1 real participant(s) to s/responses.csv and 1 session(s) to s/participants.csv
>>> with tempfile.TemporaryDirectory() as tmp:
...     ExportResult.load_json(r.save_json(pathlib.Path(tmp) / "export.json")) == r
True
"""
from __future__ import annotations

import abc
import dataclasses
import json
import typing
from dataclasses import dataclass, field
from pathlib import Path

from .records import (AnalyzeReport, CompareReport, ImportedFile, PlanRow, RenderRecord, ReproduceFiles,
                      SessionStatus, StageSeconds, Threshold, from_json, to_json)


@dataclass(frozen=True)
class StepResult(abc.ABC):
    """Base of the step results: ``to_dict``/``from_dict``, ``save_json``/``load_json``
    and ``summary()``.  Fields hold JSON-ready values (numbers, strings, paths,
    tuples of them, and :class:`~flipstudy.records.Record` objects); ``summary()`` is
    one convention for all: no arguments, the exact text the command prints, without
    a trailing newline."""

    @abc.abstractmethod
    def summary(self) -> str:
        """The text ``flipstudy`` prints for this step (each step's result defines it)."""

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict (paths as strings, tuples as lists)."""
        return {f.name: to_json(getattr(self, f.name)) for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, data: dict):
        """The result of :meth:`to_dict` back, each field as its declared type."""
        hints = typing.get_type_hints(cls)
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - names
        if unknown:
            from flipstudy.errors import FlipstudyValueError
            raise FlipstudyValueError(f"{cls.__name__}: unknown field(s) {', '.join(sorted(unknown))}")
        return cls(**{k: from_json(hints[k], v) for k, v in data.items()})

    def save_json(self, path) -> Path:
        """Write :meth:`to_dict` to ``path`` (JSON, UTF-8); returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
        return path

    @classmethod
    def load_json(cls, path):
        """A result written by :meth:`save_json`."""
        path = Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            from flipstudy.errors import FlipstudyValueError
            raise FlipstudyValueError(f"{path}: not a saved {cls.__name__} ({e})") from None
        if not isinstance(data, dict):
            from flipstudy.errors import FlipstudyValueError
            raise FlipstudyValueError(f"{path}: not a saved {cls.__name__} (expected a JSON object)")
        return cls.from_dict(data)


# ---- build: the stimuli of a design (flipstudy.stimuli.stimset.build_stimuli)

@dataclass(frozen=True, eq=True)
class BuildResult(StepResult):
    """A built study folder: ``rows`` are the manifest's rows (column → text) in
    order; ``replaced``: what the folder held that the build replaced (set by the
    caller that allowed it, ``""`` when nothing was replaced)."""
    out: Path
    rows: tuple[dict[str, str], ...]
    tolerance_pct: float
    replaced: str = ""

    @property
    def worst_gap_pct(self) -> float:
        """The largest |measured − nominal| error over the stimuli, in points."""
        return max((abs(float(r["measured_error_pct"]) - float(r["nominal_error_pct"]))
                    for r in self.rows), default=0.0)

    def summary(self) -> str:
        lines = [self.replaced] if self.replaced else []
        lines.append(f"wrote {len(self.rows)} stimuli to {self.out} (manifest.csv, .bvh, .npz); largest "
                     f"gap between measured and nominal error {self.worst_gap_pct:.2f} points "
                     f"(tolerance {self.tolerance_pct:g})")
        return "\n".join(lines)


# ---- render: a study's videos and stills (flipstudy.render.study.render_study)

@dataclass(frozen=True)
class RenderResult(StepResult):
    """A render of a study: what, at which size and rate, how many outputs were
    made or already up to date; ``record`` is the ``render/render.json`` written
    (a :class:`~flipstudy.records.RenderRecord`)."""
    study: Path
    what: tuple[str, ...]
    size: tuple[int, int]
    fps: float
    jobs: int
    made: int
    up_to_date: int
    seconds: float
    n_stimuli: int
    record_path: Path
    record: RenderRecord | None = field(repr=False, default=None)

    def summary(self) -> str:
        return (f"rendered {self.n_stimuli} stimuli ({', '.join(self.what)}) at {self.size[0]}x"
                f"{self.size[1]}, {self.fps:g} fps: {self.made} output(s) made, {self.up_to_date} "
                f"already up to date; {self.jobs} worker(s), {self.seconds:.1f} s\n"
                f"  settings  {self.record_path}")


# ---- simulate: simulated observers answer a study (flipstudy.study.simulate.simulate)

@dataclass(frozen=True)
class SimulateResult(StepResult):
    """Simulated participants stored in a study's ``sessions.sqlite``: ``participants``
    those this step answered for, ``finished_before`` those asked for that had finished
    already (left as they were)."""
    study: str
    participants: tuple[str, ...]
    finished_before: tuple[str, ...] = ()

    def summary(self) -> str:
        ids, old = self.participants, self.finished_before
        span = (lambda x: x[0] if len(x) == 1 else f"{x[0]}..{x[-1]}")
        done = (f"simulated {len(ids)} participant(s) ({span(ids)})" if ids else
                "simulated no participant")
        return (f"{done} in {self.study}/sessions.sqlite, stored as source=simulated"
                + (f"; {len(old)} had finished already ({span(old)}), left as they are" if old else "")
                + f"; export and analyze leave them out unless --include-simulated. next: "
                  f"flipstudy export {self.study} --include-simulated")


# ---- export: responses.csv and participants.csv (flipstudy.study.export.export_responses)

@dataclass(frozen=True)
class ExportResult(StepResult):
    """An export of a study's sessions: the files written and whose answers they hold."""
    responses: Path
    participants: Path
    truth: Path | None
    rows: int
    sessions: int
    real: tuple[str, ...] = ()
    simulated: tuple[str, ...] = ()
    simulated_left_out: tuple[str, ...] = ()
    incomplete: tuple[str, ...] = ()

    def summary(self) -> str:
        who = f"{len(self.real)} real participant(s)"
        if self.simulated:
            who += f" and {len(self.simulated)} simulated (marked simulated=true on every row)"
        lines = [f"wrote {self.rows} responses of {who} to {self.responses} and {self.sessions} "
                 f"session(s) to {self.participants}"]
        if self.simulated_left_out:
            lines.append(f"left out {len(self.simulated_left_out)} simulated participant(s) "
                         f"({self.simulated_left_out[0]}..{self.simulated_left_out[-1]}); "
                         f"--include-simulated writes them, marked")
        if self.incomplete:
            lines.append(f"{len(self.incomplete)} incomplete session(s), marked complete=false (analyze "
                         f"leaves them out by default): {', '.join(self.incomplete[:8])}"
                         + (", ..." if len(self.incomplete) > 8 else ""))
        return "\n".join(lines)


# ---- import: web results into STUDY/web/ (flipstudy.study.web.importer.import_web)

@dataclass(frozen=True)
class ImportResult(StepResult):
    """An import of web results files: per file what happened (``files``: file,
    status, records, new_answers), and the tables written under ``STUDY/web/``."""
    files: tuple[ImportedFile, ...]
    answers: int
    participants: int
    sessions: int
    incomplete: tuple[str, ...]
    flagged: tuple[str, ...]
    repeats: tuple[str, ...]
    duplicates: int
    responses: Path
    participants_csv: Path
    description: Path | None = None
    study: str = ""
    #: what was kept out of the tables and why, one line each (``quarantine_csv`` lists them)
    quarantined: tuple[str, ...] = ()
    quarantine_csv: Path | None = None

    def summary(self) -> str:
        lines = []
        for f in self.files:
            if f.status == "imported":
                lines.append(f"{f.file}: {f.records} records, {f.new_answers} new answers")
            elif f.status == "nothing new":
                lines.append(f"{f.file}: {f.records} records, every one already imported; the "
                             f"file is not kept")
            else:
                lines.append(f"{f.file}: already imported (same content), nothing new")
        lines.append(f"{self.responses}: {self.answers} answers of {self.participants} web "
                     f"participant(s) in {self.sessions} session(s)"
                     + (f"; {self.duplicates} records read more than once, kept once"
                        if self.duplicates else ""))
        if self.quarantined:
            lines.append(f"kept out of the tables ({len(self.quarantined)}; listed in "
                         f"{self.quarantine_csv}, the records stay in web/imports/):")
            lines += [f"  {q}" for q in self.quarantined[:20]]
            if len(self.quarantined) > 20:
                lines.append(f"  ... and {len(self.quarantined) - 20} more")
        if self.incomplete:
            lines.append(f"{len(self.incomplete)} incomplete session(s), marked complete=false: "
                         + ", ".join(self.incomplete[:8]))
        if self.flagged:
            lines.append(f"{len(self.flagged)} trial(s) with dropped frames over the threshold, marked "
                         f"playback_flagged=true: " + ", ".join(self.flagged[:8]))
        if self.repeats:
            lines.append(f"{len(self.repeats)} flagged trial(s) shown once more at the end, rows with "
                         f"repeat=1 (analyze uses them in place of the flagged first answers): "
                         + ", ".join(self.repeats[:8]))
        lines.append(f"next: flipstudy analyze {self.responses.parent}  (or with the local answers: "
                     f"flipstudy analyze {self.study}/responses.csv {self.responses} --out DIR)")
        return "\n".join(lines)


# ---- analyze: the tables and figures of a response table (flipstudy.analysis.pipeline.analyze)

@dataclass(frozen=True)
class AnalyzeResult(StepResult):
    """An analysis written to ``out``: ``report`` (its ``to_dict()`` is what ``analyze
    --json`` prints) holds the settings, table, thresholds, notes and files;
    ``table_markdown`` is the table shown."""
    out: Path
    report: AnalyzeReport
    table_markdown: str

    #: the notes the summary repeats (the others are in notes.md)
    NOTABLE = ("not found", "no images", "failed", "differ from the ones the session stored", "no design")

    def summary(self) -> str:
        r = self.report
        s = r.settings
        who = s.participants
        lines = [f"analysed {s.n_trials} trials of {s.participants_label} "
                 f"({len(s.groups)} groups); correction for rates of 0 or 1: {s.correction}"]
        if who.simulated_left_out:
            lines.append(f"left out {len(who.simulated_left_out)} simulated participant(s) "
                         f"(--include-simulated to keep them)")
        if who.incomplete_left_out:
            lines.append(f"left out {len(who.incomplete_left_out)} incomplete session(s) "
                         f"(--include-incomplete to keep them): {', '.join(who.incomplete_left_out[:8])}"
                         + (", ..." if len(who.incomplete_left_out) > 8 else ""))
        if r.flow:
            lines.append("participant flow ([exclusions]): " + " → ".join(f"{f.stage} {f.n}" for f in r.flow))
        if who.n < 5:
            lines.append(f"note: with {who.n} participant(s), intervals and tests over participants "
                         f"are not meaningful (notes.md)")
        lines += ["", self.table_markdown]
        if r.thresholds:
            lines.append("detection thresholds (P(incorrect) = (1 + γ)/2):")
            for t in r.thresholds:
                if t.reached:
                    hi = "open" if t.threshold_ci_high is None else f"{t.threshold_ci_high:.1f}"
                    lines.append(f"  {t.group:20s} {t.threshold:5.1f} %  [{t.threshold_ci_low:.1f}, {hi}]")
                else:
                    lines.append(f"  {t.group:20s} not reached")
        if r.thresholds_groups:
            lines.append("per-participant thresholds x* (thresholds_participants.csv), per group:")
            for t in r.thresholds_groups:
                lines.append(f"  {t.group:20s} {t.method:8s} {t.task:6s} N = "
                             f"{t.n_participants:<3d} median {t.median:5.1f} %  quartiles "
                             f"[{t.q25:.1f}, {t.q75:.1f}]  mean 95 % interval width "
                             f"{t.mean_ci_width:.1f} %")
        lines += [f"note: {n}" for n in r.notes if any(k in n for k in self.NOTABLE)]
        lines.append(f"\nwrote {len(r.files)} files to {self.out}/ (table.csv, table_paper.md/.tex, "
                     f"figures, notes.md)")
        return "\n".join(lines)


# ---- reproduce: the paper's study end to end (flipstudy.study.reproduce.reproduce)

@dataclass(frozen=True)
class ReproduceResult(StepResult):
    """A reproduce run into ``out``: the files (name → path), the seconds per stage,
    the counts the summary states, the table as Markdown and the thresholds."""
    out: str
    files: ReproduceFiles
    seconds: StageSeconds
    n_stimuli: int
    worst_gap_pct: float
    n_videos: int
    n_responses: int
    n_simulated: int
    table_md: str
    thresholds: tuple[Threshold, ...] = ()

    def summary(self) -> str:
        s, f, out = self.seconds, self.files, self.out
        lines = [f"flipstudy reproduce: done in {s.total:.0f} s "
                 f"(stimuli {s.stimuli:.0f} s, render {s.render:.0f} s, "
                 f"sessions {s.sessions:.0f} s, analysis {s.analysis:.0f} s)", "",
                 self.table_md.rstrip(), ""]
        if self.thresholds:
            lines.append("detection thresholds (P(incorrect) halfway from the base rate to 1):")
            for t in self.thresholds:
                lines.append(f"  {t.group:18s} " + (f"{t.threshold:.1f} %" if t.reached
                                                       else "not reached within the tested levels"))
            lines.append("")
        lines += [
            f"outputs in {out}/:",
            f"  {f.design}  the paper's design (edit and rerun `flipstudy stimuli`)",
            f"  {f.manifest}  {self.n_stimuli} stimuli, nominal and measured errors "
            f"(largest gap {self.worst_gap_pct:.2f} points)",
            f"  {f.videos}/  {self.n_videos} stimulus videos (.mp4), ghost and trail composites "
            f"(.png), render.json",
            f"  {f.sessions}  every simulated answer; {f.responses} ({self.n_responses} rows, "
            f"simulated=true)",
            f"  {f.table_paper}  the Table-2 layout (also .csv, .tex; table.csv has every column)",
            f"  {f.figure_ratings}, {Path(f.figure_dprime).name}, "
            f"{Path(f.figure_psychometric).name}, {Path(f.figure_sheet).name}  figures (PNG + PDF)",
            f"  {f.notes}  methods: correction, tests, fits",
            "",
            f"{f.stimuli} holds {self.n_simulated} simulated participants (marked simulated=true; "
            f"the analysis above includes them with --include-simulated). Real participants go into "
            f"a fresh study, never this one:",
            f"  flipstudy stimuli {f.design} --out mystudy && flipstudy render mystudy && "
            f"flipstudy run mystudy --participant P01",
        ]
        return "\n".join(lines)




# ---- status: who has done what (flipstudy.study.export.status)

@dataclass(frozen=True)
class StatusResult(StepResult):
    """The sessions of a study, one :class:`~flipstudy.records.SessionStatus` per
    session: the local ones, then those ``import-web`` imported (source ``web-…``);
    their ``to_dict()`` is what ``status --json`` prints."""
    study: Path
    sessions: tuple[SessionStatus, ...]

    def summary(self) -> str:
        rows = self.sessions
        if not rows:
            return "no sessions yet"
        head = ("participant", "session", "source", "answered", "", "started", "last answer", "finished")
        table = [(r.participant, str(r.session), r.source, f"{r.answered}/{r.total}",
                  "" if r.complete else "INCOMPLETE",
                  r.started or "—", r.last_answer or "—", r.finished or "no") for r in rows]
        widths = [max(len(h), *(len(t[i]) for t in table)) for i, h in enumerate(head)]

        def line(cells):
            return "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip()
        lines = [line(head), *(line(t) for t in table)]
        done = sum(1 for r in rows if r.finished)
        lines.append(f"{len(rows)} session(s), {done} finished")
        real = sorted({r.participant for r in rows if not r.simulated})
        sim = sorted({r.participant for r in rows if r.simulated})
        web = sorted({r.participant for r in rows if str(r.source).startswith("web")})
        lines.append(f"{len(real)} real participant(s)"
                     + (f" ({len(web)} imported from the web, in web/responses.csv)" if web else "")
                     + f", {len(sim)} simulated"
                     + (" (left out of export and analyze unless --include-simulated)" if sim else ""))
        inc = [r for r in rows if not r.complete]
        if inc:
            lines.append(f"{len(inc)} incomplete session(s) (analyze leaves them out by default): "
                         + ", ".join(f"{r.participant}/{r.session} {r.answered}/{r.total}"
                                     for r in inc))
        return "\n".join(lines)



# ---- plan: a power analysis of a design (flipstudy.analysis.plan)

@dataclass(frozen=True)
class PlanResult(StepResult):
    """A power analysis: one :class:`~flipstudy.records.PlanRow` per group and method
    (their ``to_dict()`` is what ``plan --json`` prints, non-finite numbers as None), the table as text and the settings it ran with."""
    rows: tuple[PlanRow, ...]
    table: str
    observers: int
    threshold: tuple[float, float]
    seed: int

    def summary(self) -> str:
        return (f"{self.table}\n\n{self.observers} simulated observers per group (x* ~ "
                f"N({self.threshold[0]:g}, {self.threshold[1]:g}) %, widths 8–40 %, yes/no base rates "
                f"0.05–0.45, lapse 0.02), seed {self.seed}; both methods scored by the same posterior "
                f"(flipstudy.analysis.adaptive).")


# ---- the motion commands: inspect, edit, concat, jump (flipstudy.study.motions)

@dataclass(frozen=True)
class MotionResult(StepResult):
    """What a motion command measured or made: ``out`` the BVH written (None for
    ``inspect``), ``report`` what the command's ``--json`` prints (the method's
    measures, the figures written), ``lines`` the text of the summary."""
    command: str
    out: Path | None
    report: dict
    lines: tuple[str, ...]

    def summary(self) -> str:
        return "\n".join(self.lines)


__all__ = ["StepResult", "BuildResult", "RenderResult", "SimulateResult", "ExportResult",
           "ImportResult", "AnalyzeResult", "ReproduceResult", "StatusResult", "PlanResult",
           "MotionResult", "CompareResult"]


# ---- analyze of a comparison study: the ranking of its sources (flipstudy.study.compare)

@dataclass(frozen=True)
class CompareResult(StepResult):
    """A comparison study's analysis written to ``out``: ``report`` is what ``analyze
    --json`` prints (participants, the Bradley–Terry ranking, the agreement of the
    clips' numbers with the choices, notes, files)."""
    out: Path
    report: CompareReport

    def summary(self) -> str:
        r = self.report
        rank = sorted(r.ranking, key=lambda x: -x.strength)
        lines = [f"comparison study: {r.participants} participant(s)",
                 f"Bradley–Terry ranking ({r.choices} choices; θ in logits, {r.reference} = 0, "
                 f"{100 * r.ci:g} % intervals):"]
        lines += [f"  {x.source:16s} θ = {x.strength:+.2f} [{x.low:+.2f}, {x.high:+.2f}]   "
                  f"won {x.wins}/{x.n}" for x in rank]
        if r.agreement:
            lines.append("agreement with people's choices (smaller number predicted chosen; "
                         "bootstrap over participants):")
            for a in r.agreement:
                lines.append(f"  {a.metric:22s} accuracy {a.accuracy:.2f} [{a.accuracy_low:.2f}, "
                             f"{a.accuracy_high:.2f}]  AUC {a.auc:.2f} [{a.auc_low:.2f}, "
                             f"{a.auc_high:.2f}]  ({a.n} trials)" if a.n
                             else f"  {a.metric:22s} not measured on these clips")
        lines += [f"note: {n}" for n in r.notes]
        lines += [f"wrote {p}" for p in r.files.values()]
        return "\n".join(lines)

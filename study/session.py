"""One participant's session: open or resume it, and take its answers.

The functions here are the single path by which answers reach the database:
the server's POST handlers call :func:`submit_answer` and
:func:`submit_demographics`, and so do the simulated observers
(:mod:`flipstudy.study.simulate`).

Adaptive (quest+) trials are stored as slots; :meth:`Session.resolve` fills one
with the level QUEST+ picks from the group's last stored state
(:class:`flipstudy.analysis.adaptive.Quest`, rebuilt with ``Quest.from_json``, or
a new one) and the stimulus of that level and the slot's clip.  Its answer must
name that stimulus; it is stored with the group's QUEST+ state after it, in the
same transaction, so a session killed at any moment resumes with exactly the
same posterior and next level.  When a group's ``stop_width`` is reached its
remaining slots are skipped.  A 2AFC answer is "first" or "second" (the motion
judged physically correct); yes/no answers are "correct" or "incorrect".

Examples
--------
On a tiny study (:func:`flipstudy.study.demo.make_demo_study`):

>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = load_study(make_demo_study(pathlib.Path(tmp.name) / "study"))
>>> s = open_session(study, "P01")
>>> submit_answer(s, {"participant": "P01", "session": 1, "trial": 1,
...                   "stimulus": s.trials[0].stimulus, "response": "correct",
...                   "rt_ms": 812.0, "shown_ms": 2400.0, "late_frames": 0})
{'status': 'stored', 'trial': 1, 'next_trial': 2, 'finished': False, 'next': {'trial': 2, ...}}
>>> tmp.cleanup()
"""
from __future__ import annotations

from flipstudy.errors import RequestError, SessionError, StudyChangedError
import hashlib
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

from flipstudy.stimuli.contract import STIMULUS_RE, Stimulus, StimulusSet  # noqa: F401  (STIMULUS_RE re-exported)

from . import store
from .order import Trial, participant_seed, reference_stimuli, trial_order
from .validate import check_participant, check_task_response, parse_answer, parse_demographics

VIDEO_EXT = ".mp4"


def study_fingerprint(study_dir) -> dict:
    """What identifies a study folder as the one a server opened: the identity
    (device, inode) of the folder and of ``sessions.sqlite`` (None: absent), and
    the SHA-256 of ``manifest.csv`` and ``design.toml`` (None: absent)."""
    d = Path(study_dir)

    def ident(p):
        try:
            st = p.stat()
        except OSError:
            return None
        return (st.st_dev, st.st_ino)

    def digest(p):
        try:
            return hashlib.sha256(p.read_bytes()).hexdigest()
        except OSError:
            return None
    return {"folder": ident(d), "sessions.sqlite": ident(store.db_path(d)),
            "manifest.csv": digest(d / "manifest.csv"), "design.toml": digest(d / "design.toml")}


@dataclass
class Study:
    """A study folder: its design, stimuli (:class:`~flipstudy.stimuli.contract.StimulusSet`,
    read and checked once) and rendered videos."""
    dir: Path
    design: object
    stimuli: StimulusSet

    @property
    def manifest(self) -> tuple[Stimulus, ...]:
        """The stimuli in manifest order."""
        return self.stimuli.stimuli

    @property
    def manifest_sha256(self) -> str:
        return self.stimuli.manifest_sha256

    @property
    def by_name(self) -> StimulusSet:
        """Stimulus name → :class:`~flipstudy.stimuli.contract.Stimulus` (``name in``, ``[name]``)."""
        return self.stimuli
    design_text: str = ""          # design.toml as read (recorded with the first answer)

    @property
    def render_dir(self) -> Path:
        return self.dir / "render"

    def video_path(self, stimulus: str) -> Path:
        return self.render_dir / f"{stimulus}{VIDEO_EXT}"

    @property
    def references(self) -> list[Stimulus]:
        return reference_stimuli(self.manifest)

    def missing_videos(self) -> list[str]:
        return [r.stimulus for r in self.manifest if not self.video_path(r.stimulus).is_file()]

    def group(self, name: str):
        """The design's group ``name`` (None for the shared originals' pseudo-group)."""
        return next((g for g in self.design.groups if g.name == name), None)

    def quest_model(self, group: str):
        """The QUEST+ model of a quest+ group (its levels, task and settings;
        :func:`flipstudy.analysis.adaptive.quest_model`, cached there)."""
        from dataclasses import asdict

        from flipstudy.analysis.adaptive import QuestSettings, quest_model
        g = self.group(group)
        if g is None or not g.adaptive:
            raise SessionError(f"group {group!r} is not a quest+ group of {self.dir / 'design.toml'}")
        return quest_model(g.levels, g.task, QuestSettings(**asdict(g.quest)))

    def stimulus_at(self, group: str, clip: str, level: float) -> str:
        """The stimulus of ``group`` × ``clip`` × ``level`` (level 0 of a group that
        shares the original: the clip's shared original)."""
        key = (group, clip, round(level, 6))
        if key not in self._levels:
            raise SessionError(f"{self.dir / 'manifest.csv'}: no stimulus of group {group!r}, clip "
                               f"{clip!r} at level {level:g} %; rebuild the stimuli")
        return self._levels[key]

    @property
    def _levels(self) -> dict:
        idx = self.__dict__.get("_level_index")
        if idx is None:
            idx = {}
            for r in self.manifest:
                if r.is_reference:
                    continue
                idx[(r.group, r.clip, round(r.level, 6))] = r.stimulus
                if r.original:
                    idx.setdefault((r.group, r.clip, 0.0), r.original)
            self.__dict__["_level_index"] = idx
        return idx


def load_study(study_dir) -> Study:
    """The study in ``study_dir`` (a folder, or a :class:`~flipstudy.stimuli.contract.StimulusSet`
    already read): its ``design.toml`` and its ``manifest.csv``, read and checked once
    (:meth:`StimulusSet.read <flipstudy.stimuli.contract.StimulusSet.read>`; the
    motion files are not needed by a session, the videos are checked by
    :func:`flipstudy.render.record.check_rendered`), and the session's limits."""
    from flipstudy.stimuli.design import TRIALS_MAX
    if isinstance(study_dir, StimulusSet):
        stimuli, d = study_dir, study_dir.folder
    else:
        d = Path(study_dir)
        if not d.is_dir():
            raise SessionError(f"{d}: no such study folder (make one with `flipstudy stimuli DESIGN.toml "
                               f"--out {d}`)")
        stimuli = None
    if not (d / "design.toml").is_file():
        raise SessionError(f"{d / 'design.toml'}: missing; a study folder made by `flipstudy stimuli` "
                           f"holds a copy of its design")
    if stimuli is None:
        stimuli = StimulusSet.read(d, files=False)
    design = stimuli.design
    if design is None:
        from flipstudy.stimuli.design import load_design
        design = load_design(d / "design.toml")
    n_tests = len(stimuli.tests)
    if any(g.adaptive or g.task != "yes-no" for g in design.groups) and not getattr(design, "compares", False):
        n = design.trials_per_participant()
        if n > TRIALS_MAX:
            raise SessionError(f"{d / 'design.toml'}: {n} trials per participant; at most {TRIALS_MAX}")
    elif n_tests * design.repetitions > TRIALS_MAX:
        raise SessionError(f"{d / 'manifest.csv'}: {n_tests} test stimuli × repetitions = "
                           f"{design.repetitions} is {n_tests * design.repetitions} trials per "
                           f"participant; at most {TRIALS_MAX}")
    return Study(d, design, stimuli, (d / "design.toml").read_bytes().decode("utf-8", errors="replace"))


@dataclass
class Session:
    """An open session: who, which session, its stored trial order."""
    study: Study
    participant: str
    session: int
    source: str
    trials: list[Trial]
    resumed: bool = False
    _conn: object = field(default=None, repr=False)
    _lock: object = field(default_factory=threading.Lock, repr=False)
    _pinned: dict | None = field(default=None, repr=False)
    _changed: str | None = field(default=None, repr=False)

    def pin(self) -> None:
        """Remember which study folder this session stores into (:func:`study_fingerprint`),
        with the database connection open on it; :meth:`check_intact` then refuses
        once anything of it was replaced or changed.  The server pins its session."""
        before = study_fingerprint(self.study.dir)
        with self.db():
            pass
        after = study_fingerprint(self.study.dir)
        if before != after or after["sessions.sqlite"] is None:
            raise StudyChangedError(f"{self.study.dir} changed while the session was being opened; "
                               f"start it again")
        self._pinned = after

    def check_intact(self) -> None:
        """Raise :class:`StudyChangedError` when the pinned study folder was replaced or
        its database, manifest or design changed (once changed, always refused)."""
        if self._pinned is None:
            return
        if self._changed is None:
            now = study_fingerprint(self.study.dir)
            diff = [k for k in self._pinned if now[k] != self._pinned[k]]
            if diff:
                what = ("the folder was replaced or moved" if "folder" in diff else
                        ", ".join(f"{k} {'is gone' if now[k] is None else 'was replaced' if k == 'sessions.sqlite' else 'changed'}"
                                  for k in diff))
                self._changed = (f"{self.study.dir}: {what} while this server was serving "
                                 f"participant {self.participant}")
        if self._changed is not None:
            raise StudyChangedError(self._changed)

    @property
    def n_trials(self) -> int:
        return len(self.trials)

    @contextmanager
    def db(self):
        """The session's database connection, one user at a time (threads)."""
        with self._lock:
            if self._conn is None:
                self._conn = store.connect(self.study.dir)
            yield self._conn

    def close(self) -> None:
        with self._lock:
            if self._conn is not None:
                self._conn.close()
                self._conn = None

    def state(self) -> dict:
        """``answered`` (count), ``next_trial`` (1-based: the first trial neither
        answered nor skipped, see :meth:`skipped`; ``n_trials + 1`` when done),
        ``finished`` and ``demographics`` (stored or not)."""
        with self.db() as conn:
            n = store.count_answers(conn, self.participant, self.session)
            nxt = store.next_open_trial(conn, self.participant, self.session)
            demo = store.has_demographics(conn, self.participant, self.session)
        return {"answered": n, "next_trial": nxt or self.n_trials + 1, "finished": nxt is None,
                "demographics": demo}

    def skipped(self) -> list[int]:
        """The quest+ slots left out because their group stopped early (``stop_width``);
        ``next_trial`` jumps over them."""
        with self.db() as conn:
            return store.skipped_trials(conn, self.participant, self.session)

    def trial(self, trial_no: int) -> Trial:
        """The stored trial ``trial_no`` (1-based; an adaptive slot unresolved)."""
        if isinstance(trial_no, bool) or not isinstance(trial_no, int) or not 1 <= trial_no <= self.n_trials:
            raise SessionError(f"trial {trial_no!r}: this session has trials 1 to {self.n_trials}")
        return self.trials[trial_no - 1]

    def resolve(self, trial_no: int) -> Trial:
        """The trial as it is shown: a constant trial as stored; an adaptive slot
        with the stimulus and level it showed (answered) or that QUEST+ picks now
        from the group's stored answers (the current trial's; a later slot's
        level may still change with the answers before it)."""
        t = self.trial(trial_no)
        if not t.adaptive:
            return t
        with self.db() as conn:
            row = conn.execute("SELECT shown_stimulus, shown_level FROM responses WHERE "
                               "participant=? AND session=? AND trial=?",
                               (self.participant, self.session, t.trial)).fetchone()
            if row is not None and row["shown_stimulus"]:
                return replace(t, stimulus=row["shown_stimulus"], level=float(row["shown_level"]))
            return self._pick(self.quest(t.group, conn), t)

    def quest(self, group: str, conn=None):
        """The group's QUEST+ run after its stored answers (``Quest.from_json`` of
        the last stored state, or a new run)."""
        from flipstudy.analysis.adaptive import Quest
        model = self.study.quest_model(group)
        if conn is None:
            with self.db() as c:
                return self.quest(group, c)
        state = store.last_quest_state(conn, self.participant, self.session, group)
        return Quest.from_json(model, state) if state else Quest.new(model)

    def _pick(self, quest, t: Trial) -> Trial:
        level = quest.next_level()
        return replace(t, stimulus=self.study.stimulus_at(t.group, t.clip, level), level=level)


def open_session(study: Study, participant: str, *, new_session: bool = False,
                 source: str = "browser", dry_run: bool = False, _retried: bool = False) -> Session:
    """Resume the participant's unfinished session, or start one.

    A new session's trial order is stored before this returns (so before the
    first trial is served).  A finished participant is refused unless
    ``new_session`` (which starts session n+1 and keeps session n).
    ``dry_run``: make every check but store nothing.  A session is created holding
    the study's lock (:class:`~flipstudy.study.lock.StudyLock`), so it never
    interleaves with another command writing the study (an ``import-web`` whose
    participants a local ID may not take, a ``simulate``).
    """
    import contextlib

    from .lock import StudyLock
    held = contextlib.nullcontext() if dry_run else \
        StudyLock(study.dir, "run" if source == "browser" else "simulate")
    with held:
        return _open_session(study, participant, new_session=new_session, source=source,
                             dry_run=dry_run, _retried=_retried)


def _open_session(study: Study, participant: str, *, new_session: bool, source: str,
                  dry_run: bool, _retried: bool) -> Session:
    try:
        check_participant(participant)
    except RequestError as e:
        raise SessionError(e.message) from None
    from .frozen import refuse_changed_design
    refuse_changed_design(study.dir, "run" if source == "browser" else "simulate")
    conn = store.connect(study.dir)
    try:
        last = store.latest_session(conn, participant)
        if last is not None and last["source"] != source:
            raise SessionError(f"participant {participant} is a {last['source']} participant in "
                               f"{store.db_path(study.dir)}; choose another ID")
        if last is not None and not new_session:
            s = last["session"]
            if last["finished"]:
                raise SessionError(
                    f"participant {participant} already finished session {s} "
                    f"(at {last['finished']}); their answers are kept and will not be "
                    f"overwritten. To run {participant} again, pass --new-session "
                    f"(starts session {s + 1}; session {s} stays in the database).")
            if last["manifest_sha256"] != study.manifest_sha256:
                raise SessionError(
                    f"participant {participant}, session {s}: {study.dir / 'manifest.csv'} changed "
                    f"since this session started, so its stored trial order may name stimuli "
                    f"that differ now; restore the stimuli it was started with, or start a new "
                    f"session with --new-session")
            trials = store.load_trials(conn, participant, s)
            missing = [x for t in trials for x in (t.stimulus, t.original)
                       if x and x not in study.by_name]
            if missing:
                raise SessionError(f"session {s} of {participant} names stimuli not in the "
                                   f"manifest: {missing[:3]}")
            resumed = Session(study, participant, s, source, trials, resumed=True)
            _check_quest_states(resumed, conn)
            return resumed
        if last is None and participant in web_participants(study.dir):
            raise SessionError(
                f"participant {participant} has answers imported from the web site "
                f"({study.dir / 'web' / 'participants.csv'}); one study has one participant-ID "
                f"namespace across local, simulated and web sessions: choose another ID")
        s = 1 if last is None else last["session"] + 1
        if any(g.task == "2afc" for g in study.design.groups) and not store.accepts_2afc(conn):
            raise SessionError(f"{store.db_path(study.dir)} was made by an older flipstudy (schema "
                               f"1): it accepts only correct/incorrect answers, not a 2AFC group's "
                               f"first/second; run this design in a new study folder")
        def order(conn) -> list:
            manifest, between = study.manifest, tuple(study.design.online.between)
            if between:  # between-subject conditions: the least-filled first (ties: the design's
                # order), counted in the transaction that stores this session (store.create_session)
                counts = store.condition_counts(conn, between, source)
                condition = min(between, key=lambda c: counts[c])
                manifest = [r for r in manifest if r.group not in between or r.group == condition]
            return trial_order(study.design, manifest, participant, s)
        seed = participant_seed(study.design.seed, participant, s)
        trials = order(conn) if dry_run else None
        if not dry_run:
            try:
                trials = store.create_session(conn, participant, s, source, seed,
                                              study.manifest_sha256, order)
            except store.ConflictError:
                if _retried:
                    raise SessionError(f"participant {participant}: session {s} is being created "
                                       f"by another process; try again") from None
                # another process created this session between our read and our write:
                # it is the session asked for, so open (resume) that one
                conn.close()
                return open_session(study, participant, new_session=False, source=source,
                                    _retried=True)
        return Session(study, participant, s, source, trials, resumed=False)
    finally:
        conn.close()


def web_participants(study_dir) -> set[str]:
    """The participant IDs of the study's imported web results (``web/participants.csv``,
    rebuilt by every ``import-web``)."""
    import csv
    p = Path(study_dir) / "web" / "participants.csv"
    if not p.is_file():
        return set()
    try:
        with p.open(newline="", encoding="utf-8", errors="replace") as f:
            return {r.get("participant") or "" for r in csv.DictReader(f)} - {""}
    except (OSError, csv.Error) as e:
        raise SessionError(f"{p}: cannot be read ({e}); it lists the web participants, whose IDs "
                           f"a local session may not take") from None


def _check_quest_states(session: Session, conn) -> None:
    """A resumed session's stored QUEST+ states must belong to its groups' models
    now (the design's quest+ keys or levels unchanged)."""
    from flipstudy.errors import FlipstudyValueError
    for g in sorted({t.group for t in session.trials if t.adaptive}):
        try:
            session.quest(g, conn)
        except (FlipstudyValueError, SessionError) as e:
            raise SessionError(
                f"participant {session.participant}, session {session.session}: the stored QUEST+ "
                f"state of group {g!r} does not fit {session.study.dir / 'design.toml'} now ({e}); "
                f"restore the design the session started with, or start a new session with "
                f"--new-session") from None


def submit_answer(session: Session, payload: dict, *, timestamp: str | None = None) -> dict:
    """Validate and store one answer: the path of every answer (page and simulation).

    Returns ``{"status": "stored"|"duplicate", "trial", "next_trial", "finished",
    "next"}`` (``next``: :meth:`Session.resolve` of ``next_trial`` as a dict, None
    when finished); raises :class:`RequestError` (400 malformed or a response
    that does not fit the trial's task, 403 wrong participant/session, 409 not the
    current trial, a conflicting second answer, or not the stimulus the trial
    shows: an adaptive trial's is :meth:`Session.resolve`'s)."""
    if not isinstance(payload, dict):
        raise RequestError(400, "an answer must be a JSON object")
    ans = parse_answer(payload, participant=session.participant, session=session.session,
                       n_trials=session.n_trials, replay_allowed=bool(session.study.design.session.replay))
    if (ans["input"] == "simulated") != (session.source == "simulated"):
        raise RequestError(400, f"input: {ans['input']!r} does not fit a {session.source} session")
    t = session.trials[ans["trial"] - 1]
    check_task_response(t.task, ans["response"])

    def adaptive(conn, row) -> dict:
        quest = session.quest(t.group, conn)          # read inside the answer's transaction
        shown = session._pick(quest, t)
        if ans["stimulus"] != shown.stimulus:
            raise store.ConflictError(f"trial {t.trial} shows {shown.stimulus!r} (level {shown.level:g} %, "
                                 f"chosen by QUEST+), not {ans['stimulus']!r}")
        quest.update(shown.level, detected(t, ans["response"]))
        th = quest.threshold()
        skip = [x.trial for x in session.trials if x.group == t.group and x.trial > t.trial] \
            if quest.finished() else []
        return {"shown_stimulus": shown.stimulus, "shown_level": shown.level,
                "quest_state": quest.to_json(), "quest_threshold": th["threshold"],
                "quest_ci_low": th["ci_low"], "quest_ci_high": th["ci_high"], "skip": skip}

    with session.db() as conn:
        try:
            status = store.insert_answer(conn, session.participant, session.session,
                                         session.n_trials, ans, timestamp, adaptive=adaptive,
                                         design_text=session.study.design_text or None)
        except store.ConflictError as e:
            raise RequestError(409, str(e)) from None
        nxt = store.next_open_trial(conn, session.participant, session.session)
    return {"status": status, "trial": ans["trial"], "next_trial": nxt or session.n_trials + 1,
            "finished": nxt is None, "next": session.resolve(nxt).to_dict() if nxt else None}


def detected(trial: Trial, response: str) -> bool:
    """The psychometric outcome of an answer: yes/no "incorrect" (an error seen);
    2AFC the original chosen as the physically correct motion.

    >>> t = Trial(1, "s", "c", "g", "k", 10.0, 1, task="2afc", first="modified")
    >>> detected(t, "second"), detected(t, "first")
    (True, False)
    """
    if trial.task == "2afc":
        return (response == "first") == (trial.first == "original")
    return response == "incorrect"


def submit_demographics(session: Session, payload: dict) -> dict:
    """Validate and store the demographics (once per session)."""
    if not isinstance(payload, dict):
        raise RequestError(400, "demographics must be a JSON object")
    values = parse_demographics(payload, participant=session.participant, session=session.session)
    with session.db() as conn:
        try:
            status = store.insert_demographics(conn, session.participant, session.session, values)
        except store.ConflictError as e:
            raise RequestError(409, str(e)) from None
    return {"status": status}

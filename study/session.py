"""One participant's session: open or resume it, and take its answers.

The functions here are the single path by which answers reach the database:
the server's POST handlers call :func:`submit_answer` and
:func:`submit_demographics`, and so do the simulated observers
(:mod:`flipstudy.study.simulate`).

Example
-------
On a tiny study (:func:`flipstudy.study.demo.make_demo_study`):

>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = load_study(make_demo_study(pathlib.Path(tmp.name) / "study"))
>>> s = open_session(study, "P01")
>>> submit_answer(s, {"participant": "P01", "session": 1, "trial": 1,
...                   "stimulus": s.trials[0].stimulus, "response": "correct",
...                   "rt_ms": 812.0, "shown_ms": 2400.0, "late_frames": 0})
{'status': 'stored', 'trial': 1, 'next_trial': 2, 'finished': False}
>>> tmp.cleanup()
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyError
import hashlib
import re
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from . import store
from .order import Trial, participant_seed, reference_stimuli, trial_order
from .validate import RequestError, check_participant, parse_answer, parse_demographics

VIDEO_EXT = ".mp4"
STIMULUS_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,200}")


class SessionError(FlipstudyError, ValueError):
    """A session that cannot be opened; the message tells the experimenter what to do."""


@dataclass
class Study:
    """A study folder: its design, manifest and rendered videos."""
    dir: Path
    design: object
    manifest: list[dict]
    manifest_sha256: str
    by_name: dict = field(default_factory=dict)

    @property
    def render_dir(self) -> Path:
        return self.dir / "render"

    def video_path(self, stimulus: str) -> Path:
        return self.render_dir / f"{stimulus}{VIDEO_EXT}"

    @property
    def references(self) -> list[dict]:
        return reference_stimuli(self.manifest)

    def missing_videos(self) -> list[str]:
        return [r["stimulus"] for r in self.manifest if not self.video_path(r["stimulus"]).is_file()]


def load_study(study_dir) -> Study:
    """Read ``STUDY_DIR/design.toml`` and ``STUDY_DIR/manifest.csv``."""
    from flipstudy.stimuli.design import load_design
    from flipstudy.stimuli.stimset import read_manifest
    d = Path(study_dir)
    if not d.is_dir():
        raise SessionError(f"{d}: no such study folder (make one with `flipstudy stimuli DESIGN.toml "
                           f"--out {d}`)")
    if not (d / "design.toml").is_file():
        raise SessionError(f"{d / 'design.toml'}: missing; a study folder made by `flipstudy stimuli` "
                           f"holds a copy of its design")
    design = load_design(d / "design.toml")
    manifest = read_manifest(d)
    for i, r in enumerate(manifest, start=2):
        name = r.get("stimulus", "")
        if not STIMULUS_RE.fullmatch(name or ""):
            raise SessionError(f"{d / 'manifest.csv'}: line {i}: stimulus name {name!r} is not a "
                               f"plain file name")
    from flipstudy.stimuli.design import TRIALS_MAX
    names = [r.get("stimulus", "") for r in manifest]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise SessionError(f"{d / 'manifest.csv'}: stimulus {dup[0]!r} is listed more than once; "
                           f"rebuild the stimuli with `flipstudy stimuli`")
    n_tests = sum(1 for r in manifest if r.get("group") != "reference")
    if n_tests * design.repetitions > TRIALS_MAX:
        raise SessionError(f"{d / 'manifest.csv'}: {n_tests} test stimuli × repetitions = "
                           f"{design.repetitions} is {n_tests * design.repetitions} trials per "
                           f"participant; at most {TRIALS_MAX}")
    sha = hashlib.sha256((d / "manifest.csv").read_bytes()).hexdigest()
    return Study(d, design, manifest, sha, {r["stimulus"]: r for r in manifest})


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
        """``answered`` (count), ``next_trial`` (1-based; ``n_trials + 1`` when
        done), ``finished`` and ``demographics`` (stored or not)."""
        with self.db() as conn:
            n = store.count_answers(conn, self.participant, self.session)
            demo = store.has_demographics(conn, self.participant, self.session)
        return {"answered": n, "next_trial": n + 1, "finished": n >= self.n_trials,
                "demographics": demo}


def open_session(study: Study, participant: str, *, new_session: bool = False,
                 source: str = "browser", dry_run: bool = False, _retried: bool = False) -> Session:
    """Resume the participant's unfinished session, or start one.

    A new session's trial order is stored before this returns (so before the
    first trial is served).  A finished participant is refused unless
    ``new_session`` (which starts session n+1 and keeps session n).
    ``dry_run``: make every check but store nothing.
    """
    try:
        check_participant(participant)
    except RequestError as e:
        raise SessionError(e.message) from None
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
            missing = [t.stimulus for t in trials if t.stimulus not in study.by_name]
            if missing:
                raise SessionError(f"session {s} of {participant} names stimuli not in the "
                                   f"manifest: {missing[:3]}")
            return Session(study, participant, s, source, trials, resumed=True)
        s = 1 if last is None else last["session"] + 1
        trials = trial_order(study.design, study.manifest, participant, s)
        seed = participant_seed(study.design.seed, participant, s)
        if not dry_run:
            try:
                store.create_session(conn, participant, s, source, seed, study.manifest_sha256,
                                     trials)
            except store.Conflict:
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


def submit_answer(session: Session, payload: dict, *, timestamp: str | None = None) -> dict:
    """Validate and store one answer: the path of every answer (page and simulation).

    Returns ``{"status": "stored"|"duplicate", "trial", "next_trial", "finished"}``;
    raises :class:`RequestError` (400 malformed, 403 wrong participant/session,
    409 not the current trial or a conflicting second answer)."""
    if not isinstance(payload, dict):
        raise RequestError(400, "an answer must be a JSON object")
    ans = parse_answer(payload, participant=session.participant, session=session.session,
                       n_trials=session.n_trials, replay_allowed=bool(session.study.design.session.replay))
    if (ans["input"] == "simulated") != (session.source == "simulated"):
        raise RequestError(400, f"input: {ans['input']!r} does not fit a {session.source} session")
    with session.db() as conn:
        try:
            status = store.insert_answer(conn, session.participant, session.session,
                                         session.n_trials, ans, timestamp)
        except store.Conflict as e:
            raise RequestError(409, str(e)) from None
        n = store.count_answers(conn, session.participant, session.session)
    return {"status": status, "trial": ans["trial"], "next_trial": n + 1,
            "finished": n >= session.n_trials}


def submit_demographics(session: Session, payload: dict) -> dict:
    """Validate and store the demographics (once per session)."""
    if not isinstance(payload, dict):
        raise RequestError(400, "demographics must be a JSON object")
    values = parse_demographics(payload, participant=session.participant, session=session.session)
    with session.db() as conn:
        try:
            status = store.insert_demographics(conn, session.participant, session.session, values)
        except store.Conflict as e:
            raise RequestError(409, str(e)) from None
    return {"status": status}

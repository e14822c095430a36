"""Simulated observers: whole sessions answered through the same storage path as
the participant page.

An observer model gives, for each error group, the probability of answering
"correct" at a few levels; between them it is interpolated linearly.  Every
simulated participant gets a random effect: a shift ``u ~ N(0, sigma)`` of the
logit of that probability.  The model's base logits are calibrated so that the
mean over participants equals the model's probability exactly (the logit-normal
mean is not the probability at the mean logit), so a simulated panel reproduces
the model's ratings in expectation.

The default model is Table 2 of Majkowska & Faloutsos 2007 (mean ratings, % of
"correct" answers); its empty smooth-increase 37 % cell is interpolated
between 25 % (72) and 50 % (41).  The shared original of the angular-momentum
groups (group ``original``) is answered "correct" with their level-0 72 %, the
take-off group's own original with 63 %.  A model without an ``original``
group answers the shared original with the mean of the level-0 probabilities
of the groups that share it.  A catch group (``[exclusions] catch_groups``) the
model does not name is answered with the model of its kind
(:func:`with_catch_groups`: the paper's group of its kind, profile and sign,
the largest level's probability held for its gross levels).

Model file (TOML)::

    sigma = 0.3                                 # SD of the participant logit shift
    [groups.smooth-increase]
    levels    = [0, 17, 25, 37, 50]
    p_correct = [0.72, 0.71, 0.72, 0.56, 0.41]  # probabilities (or percentages > 1)

Studies with a quest+ or a 2AFC group (or ``population=...``) are answered by
observers with known psychometric functions instead
(:class:`flipstudy.analysis.adaptive.Observer`, the analysis's curve): each
simulated participant gets one observer per group, drawn from a population
(:func:`flipstudy.analysis.adaptive.population`; x* normal, width log-uniform,
base rate uniform, fixed lapse: :data:`DEFAULT_POPULATION`), with one base rate γ
per participant for all their yes/no groups (the shared originals are judged
with it).  A yes/no trial is answered "incorrect" with the observer's
P(detected) at the level shown, a 2AFC trial picks the original as the correct
one with that probability.  Adaptive trials are resolved
(:meth:`flipstudy.study.session.Session.resolve`) and answered like any other;
constant and adaptive groups of one participant share nothing but γ.  The
observers' parameters (the truth an analysis should recover) are stored with
the session (``sessions.simulated_truth``, JSON) and exported as
``simulated_truth.csv`` (:func:`flipstudy.study.export.export_responses`).

Simulated participants are ``sim001``, ``sim002``, …; each one's random
numbers come from SHA-256 of the seed and the ID, so the answers do not depend
on how many others are simulated.  Every answer goes as JSON bytes through the
calls the server's POST handler makes (:func:`flipstudy.study.validate.parse_json_object`,
then :func:`flipstudy.study.session.submit_answer`), so it is validated and stored alike.

Examples
--------
On a tiny study (:func:`flipstudy.study.demo.make_demo_study`: 8 trials):

>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> study = make_demo_study(pathlib.Path(tmp.name) / "study")
>>> simulate(study, 3, seed=1)
['sim001', 'sim002', 'sim003']
>>> tmp.cleanup()
"""
from __future__ import annotations

from flipstudy.errors import FlipstudyValueError, ModelError, SessionError

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import brentq
from scipy.special import expit

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from flipstudy.analysis.simulate import PAPER_TABLE2

from . import store
from .lock import study_writer
from .session import load_study, open_session, submit_answer, submit_demographics
from .validate import DEMOGRAPHIC_FIELDS, PREFER_NOT, parse_json_object

#: Majkowska & Faloutsos 2007, Table 2 (:data:`flipstudy.analysis.simulate.PAPER_TABLE2`):
#: (levels, mean ratings in % judged correct) per group.  None = the cell the paper
#: leaves empty (interpolated linearly in :data:`DEFAULT_MODEL`).
PAPER_RATINGS = {g: (t["levels"], t["rating"]) for g, t in PAPER_TABLE2.items()}
# the angular-momentum groups' shared original (the 72 of their level-0 column)
PAPER_RATINGS["original"] = ((0,), (72,))
DEFAULT_SIGMA = 0.3


def _fill(levels, ratings) -> list[float]:
    """Fill None cells by linear interpolation between their known neighbours."""
    lv = np.asarray(levels, float)
    known = [i for i, r in enumerate(ratings) if r is not None]
    vals = np.interp(lv, lv[known], np.asarray([ratings[i] for i in known], float))
    return [float(v) for v in vals]


@dataclass
class ObserverModel:
    """P(answer "correct") per group as a piecewise-linear function of the level,
    and the SD of the participants' logit shift."""
    groups: dict[str, tuple[np.ndarray, np.ndarray]]
    sigma: float = DEFAULT_SIGMA
    source: str = "Majkowska & Faloutsos 2007, Table 2"
    _calibrated: dict = field(default_factory=dict, repr=False)

    def p_correct(self, group: str, level: float) -> float:
        """The model's probability of "correct" (the panel mean) at ``level``."""
        if group not in self.groups:
            raise ModelError(f"observer model ({self.source}) has no group {group!r}; it has "
                             f"{sorted(self.groups)}. Pass --model FILE with a [groups.{group}] table")
        lv, p = self.groups[group]
        if not lv[0] - 1e-9 <= level <= lv[-1] + 1e-9:
            raise ModelError(f"observer model ({self.source}), group {group!r}: level {level:g} is "
                             f"outside its levels {lv[0]:g}..{lv[-1]:g}; add levels to the model")
        return float(np.interp(level, lv, p))

    def base_logit(self, group: str, level: float) -> float:
        """The logit b with E[expit(b + u)] = p_correct, u ~ N(0, sigma)."""
        key = (group, round(float(level), 9))
        if key not in self._calibrated:
            self._calibrated[key] = _calibrate(self.p_correct(group, level), self.sigma)
        return self._calibrated[key]

    def probability(self, group: str, level: float, shift: float) -> float:
        """P("correct") for a participant whose logit shift is ``shift``."""
        return float(expit(self.base_logit(group, level) + shift))


_GH_X, _GH_W = np.polynomial.hermite_e.hermegauss(40)
_GH_W = _GH_W / _GH_W.sum()


def _calibrate(p: float, sigma: float) -> float:
    if p <= 0.0 or p >= 1.0 or sigma == 0.0:
        return math.inf if p >= 1 else -math.inf if p <= 0 else math.log(p / (1 - p))
    # E[expit(b + u)] (Gauss-Hermite) increases with b: its root is the base logit
    return brentq(lambda b: float(np.dot(_GH_W, expit(b + sigma * _GH_X))) - p, -30.0, 30.0,
                  xtol=1e-13, rtol=4 * np.finfo(float).eps)


def default_model(sigma: float = DEFAULT_SIGMA) -> ObserverModel:
    """The paper's Table 2 (missing cell interpolated) as an observer model."""
    groups = {g: (np.asarray(lv, float), np.asarray(_fill(lv, r), float) / 100.0)
              for g, (lv, r) in PAPER_RATINGS.items()}
    return ObserverModel(groups, sigma)


DEFAULT_MODEL = default_model()


def parse_model(text: str, source: str = "<model>") -> ObserverModel:
    """An observer model from TOML text (see the module docstring)."""
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ModelError(f"{source}: not valid TOML: {e}") from None
    unknown = set(d) - {"sigma", "groups", "name"}
    if unknown:
        raise ModelError(f"{source}: unknown key(s) {sorted(unknown)}; expected sigma, groups")
    sigma = d.get("sigma", DEFAULT_SIGMA)
    if isinstance(sigma, bool) or not isinstance(sigma, (int, float)) or not (0 <= sigma <= 5):
        raise ModelError(f"{source}: sigma: expected a number from 0 to 5, got {sigma!r}")
    groups_in = d.get("groups")
    if not isinstance(groups_in, dict) or not groups_in:
        raise ModelError(f"{source}: expected [groups.NAME] tables with levels and p_correct")
    groups = {}
    for g, t in groups_in.items():
        w = f"{source}: [groups.{g}]"
        if not isinstance(t, dict) or set(t) != {"levels", "p_correct"}:
            raise ModelError(f"{w}: expected exactly the keys levels and p_correct")
        lv, p = t["levels"], t["p_correct"]
        if (not isinstance(lv, list) or not isinstance(p, list) or not lv or len(lv) != len(p)):
            raise ModelError(f"{w}: levels and p_correct must be lists of the same, non-zero length")
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in lv + p):
            raise ModelError(f"{w}: levels and p_correct must hold numbers")
        lv = np.asarray(lv, float)
        p = np.asarray(p, float)
        if np.any(np.diff(lv) <= 0):
            raise ModelError(f"{w}.levels: must increase strictly, got {lv.tolist()}")
        if np.any(p > 1):
            p = p / 100.0                      # percentages
        if np.any(p < 0) or np.any(p > 1) or not np.all(np.isfinite(p)):
            raise ModelError(f"{w}.p_correct: probabilities from 0 to 1 (or percentages 0-100)")
        groups[str(g)] = (lv, p)
    return ObserverModel(groups, float(sigma), source)


def load_model(path) -> ObserverModel:
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as e:
        raise ModelError(f"{p}: cannot read the observer model: {e.strerror}") from None
    return parse_model(text, str(p))


def _with_shared_original(model: ObserverModel, manifest, catch_groups=()) -> ObserverModel:
    """``model`` with an ``original`` group when the manifest has shared originals
    and the model lacks one: the mean level-0 probability of the sharing groups
    (the catch groups are not among them)."""
    from flipstudy.stimuli.design import SHARED_ORIGINAL_GROUP as SO
    if SO in model.groups or not any(r.group == SO for r in manifest):
        return model
    sharing = sorted({r.group for r in manifest if r.group not in (SO, "reference", *catch_groups)
                      and r.original.endswith(f"_{SO}")})
    if not sharing:
        raise ModelError(f"observer model ({model.source}) has no group {SO!r} for the shared "
                         f"originals; add [groups.{SO}] levels = [0] p_correct = [...]")
    p = float(np.mean([model.p_correct(g, 0.0) for g in sharing]))
    groups = dict(model.groups)
    groups[SO] = (np.array([0.0]), np.array([p]))
    return ObserverModel(groups, model.sigma, model.source)


def with_catch_groups(model: ObserverModel, design) -> ObserverModel:
    """``model`` with a table for each catch group (``[exclusions] catch_groups``) it
    lacks: the model of the catch group's kind, the model's group that the paper's
    design names after the same kind, profile and sign (e.g. ``abrupt-increase``),
    its probability at the largest level held for the larger, gross levels of the
    catch group.  A catch group with no such model group is left to the model's
    error (pass ``--model FILE``)."""
    from flipstudy.analysis.calibrate import FWP_GROUPS
    groups, added = dict(model.groups), False
    for name in design.exclusions.catch_groups:
        g = next(x for x in design.groups if x.name == name)
        like = [n for n, key in FWP_GROUPS.items() if key == (g.kind, g.profile, g.sign) and n in groups]
        if name in groups or not like:
            continue
        lv, p = groups[like[0]]
        top = max(g.levels)
        if top > lv[-1]:
            lv, p = np.append(lv, top), np.append(p, p[-1])
        groups[name], added = (lv, p), True
    if not added:
        return model
    return ObserverModel(groups, model.sigma, model.source)


def _pilot_model(model: ObserverModel, study) -> ObserverModel:
    """``model`` for the study's groups: its catch groups (:func:`with_catch_groups`) and
    its shared original (the mean of the sharing groups, catch groups not among them)."""
    catch = study.design.exclusions.catch_groups
    return _with_shared_original(with_catch_groups(model, study.design), study.manifest, catch)


def sim_ids(n: int) -> list[str]:
    width = max(3, len(str(n)))
    return [f"sim{i:0{width}d}" for i in range(1, n + 1)]


def _rng(seed: int, participant: str) -> np.random.Generator:
    h = hashlib.sha256(f"simulate:{int(seed)}:{participant}".encode()).digest()
    return np.random.default_rng(int.from_bytes(h[:8], "big"))


def _post(fn, session, obj: dict) -> dict:
    """The server's POST path: JSON bytes → parse_json_object → submit_*."""
    return fn(session, parse_json_object(json.dumps(obj).encode()))


#: the population of simulated observers (keywords of flipstudy.analysis.adaptive.population):
#: x* ~ N(25, 8) % within 3..57 %, width log-uniform 8..40 %, γ uniform 0.05..0.45, λ = 0.02
DEFAULT_POPULATION = {"threshold": (25.0, 8.0), "width": (8.0, 40.0), "gamma": (0.05, 0.45),
                      "lapse": 0.02, "bounds": (3.0, 57.0)}


def needs_observers(design) -> bool:
    """Does the design have a quest+ or 2AFC group (answered by :func:`draw_observers`)?"""
    return any(g.adaptive or g.task == "2afc" for g in design.groups)


def draw_observers(design, rng: np.random.Generator, population: dict | None = None) -> dict:
    """One simulated participant's observers: ``{group: Observer}`` (the shared
    originals' pseudo-group judged by the participant's yes/no observer), one γ
    for all yes/no groups."""
    from dataclasses import replace

    from flipstudy.analysis.adaptive import population as draw
    from flipstudy.stimuli.design import SHARED_ORIGINAL_GROUP
    pop = {**DEFAULT_POPULATION, **(population or {})}
    out, gamma = {}, None
    for g in design.groups:
        (o,) = draw(1, rng, g.task, **pop)
        if g.task == "yes-no":
            gamma = o.gamma if gamma is None else gamma
            o = replace(o, gamma=gamma)
        out[g.name] = o
    sharing = [g.name for g in design.groups if g.task == "yes-no" and g.original == "shared"
               and g.name not in design.exclusions.catch_groups]
    if sharing:
        out[SHARED_ORIGINAL_GROUP] = out[sharing[0]]
    return out


def truth_json(observers: dict) -> str:
    """The observers' parameters as stored in ``sessions.simulated_truth``."""
    from flipstudy.stimuli.design import SHARED_ORIGINAL_GROUP
    groups = {g: {"task": o.task, "threshold": o.threshold, "width": o.width, "gamma": o.gamma,
                  "lapse": o.lapse} for g, o in observers.items() if g != SHARED_ORIGINAL_GROUP}
    return json.dumps({"model": "observers", "groups": groups}, sort_keys=True)


def _observer_response(o, t, u: float) -> str:
    """The answer of observer ``o`` to the resolved trial ``t`` for a uniform draw ``u``."""
    seen = u < float(o.p_detect(t.level))
    if t.task == "2afc":                    # seen: the original picked as the correct one
        return "first" if seen == (t.first == "original") else "second"
    return "incorrect" if seen else "correct"


def comparison_probability(strengths: dict, rows, t) -> float:
    """P(the trial's stimulus is chosen) for an observer with source ``strengths``
    (Bradley–Terry logits, :func:`flipstudy.analysis.compare.p_first_wins`): in a
    2AFC trial of a comparison study over the trial's original, in a yes/no trial
    P(answered "correct")."""
    from flipstudy.analysis.compare import p_first_wins
    a = strengths[rows[t.stimulus].source]
    if t.task == "2afc":
        return float(p_first_wins(a, strengths[rows[t.original].source]))
    return float(expit(a))


def check_strengths(strengths: dict, study) -> dict:
    """``strengths`` (source → logit) for the comparison study ``study``: every source
    named, no other; floats."""
    from flipstudy.errors import ComparisonError
    sources = study.stimuli.sources()
    if not sources:
        raise ComparisonError(f"{study.dir}: --strengths simulates "
                              f"a comparison study (a design with [[sources]]); this one has none")
    unknown = sorted(set(strengths) - set(sources))
    missing = [x for x in sources if x not in strengths]
    if unknown or missing:
        raise ComparisonError(f"--strengths: the study's sources are {', '.join(sources)}; "
                              + (f"unknown {', '.join(unknown)}" if unknown else f"missing {', '.join(missing)}"))
    out = {k: float(v) for k, v in strengths.items()}
    bad = [k for k, v in out.items() if not math.isfinite(v) or abs(v) > 20]
    if bad:
        raise ComparisonError(f"--strengths {bad[0]}: expected a finite logit within ±20, got {out[bad[0]]}")
    return out


@study_writer("simulate")
def simulate(study_dir, n: int, model: ObserverModel | str | Path | None = None, seed: int = 0,
             progress=None, population: dict | None = None, strengths: dict | None = None) -> list[str]:
    """Simulate ``n`` participants (``sim001``…) answering every trial of the study.

    ``model`` is an :class:`ObserverModel`, a TOML file, or None (the paper's
    Table 2; for a study with quest+ or 2AFC groups: observers drawn from
    ``population``, see the module docstring; ``population`` given: observers in
    any study).  ``strengths`` (source → Bradley–Terry logit): a comparison study's
    observers with known source preferences (:func:`comparison_probability`; stored as
    the sessions' simulated truth).  Unfinished simulated participants are resumed;
    finished ones are left as they are (their answers would be the same).  Returns the IDs
    this call answered for (not those finished before it).  The whole run holds the
    study's lock (:class:`~flipstudy.study.lock.StudyLock`): a second ``simulate`` waits
    for it, then finds those participants finished.
    """
    study, model, observers, strengths = _setup(study_dir, n, model, population, strengths)
    done = []
    for pid in sim_ids(n):
        try:
            session = open_session(study, pid, source="simulated")
        except SessionError as e:
            if "already finished" in str(e):
                continue
            raise
        done.append(pid)
        _answer_all(study, session, pid, seed, model, observers, population, strengths)
        session.close()
        if progress is not None:
            progress(pid, session)
    return done


def _setup(study_dir, n, model, population, strengths):
    """The study and who answers in :func:`simulate`: (study, observer model, whether
    observers are drawn from a population, source strengths), checked before anything
    is stored."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1 or n > 9999:
        raise FlipstudyValueError(f"--participants: expected 1 to 9999, got {n!r}")
    study = load_study(study_dir)
    if strengths is not None:
        if model is not None or population is not None:
            raise FlipstudyValueError("simulate: pass source strengths, an observer model or a "
                                      "population, not two")
        strengths = check_strengths(strengths, study)
    observers = strengths is None and (population is not None or (model is None and needs_observers(study.design)))
    if observers and model is not None:
        raise FlipstudyValueError("simulate: pass an observer model or a population, not both")
    if strengths is None and not observers and any(g.task == "2afc" for g in study.design.groups):
        raise ModelError("an observer model (ratings of yes/no answers) cannot answer the 2afc "
                         "groups; simulate them with observers (no --model)")
    if model is None:
        model = DEFAULT_MODEL
    elif not isinstance(model, ObserverModel):
        model = load_model(model)
    if not observers and strengths is None:
        model = _pilot_model(model, study)
        groups = {r.group for r in study.manifest if not r.is_reference}
        for g in sorted(groups):                   # fail before anything is stored
            for r in study.manifest:
                if r.group == g:
                    model.p_correct(g, r.level)
    return study, model, observers, strengths


def _answer_all(study, session, pid: str, seed, model, observers: bool, population, strengths) -> None:
    """One simulated participant's demographics and every answer still to give."""
    rows = study.by_name
    rng = _rng(seed, pid)
    shift = float(rng.normal(0.0, model.sigma)) if model.sigma > 0 else 0.0
    state = session.state()
    demo = {"participant": pid, "session": session.session}
    for f in DEMOGRAPHIC_FIELDS:           # drawn even when stored: same stream on resume
        if f["kind"] == "number":
            age = int(rng.integers(19, 31))
            demo[f["name"]] = age if rng.random() > 0.15 else None
        else:
            opts = [o[0] for o in f["options"] if o[0] != PREFER_NOT]
            demo[f["name"]] = opts[int(rng.integers(len(opts)))]
    if not state["demographics"]:
        _post(submit_demographics, session, demo)
    # draw every trial's numbers up front, so a resumed run gives the same answers
    T = session.n_trials
    u = rng.random(T)
    rt = np.exp(rng.normal(np.log(1100.0), 0.4, T))
    jitter = rng.normal(0.0, 8.0, T)
    late = rng.poisson(0.3, T)
    if observers:
        obs = draw_observers(study.design, rng, population)
        with session.db() as conn:
            store.set_simulated_truth(conn, pid, session.session, truth_json(obs))
    elif strengths is not None:
        with session.db() as conn:
            store.set_simulated_truth(conn, pid, session.session, json.dumps(
                {"model": "bradley-terry", "strengths": strengths}, sort_keys=True))
    nxt = state["next_trial"]
    for t, ui, rti, ji, li in zip(session.trials, u, rt, jitter, late):
        if t.trial != nxt:                 # answered, or a skipped quest+ slot
            continue
        t = session.resolve(t.trial)
        if strengths is not None:
            chosen = ui < comparison_probability(strengths, rows, t)
            response = (("first" if chosen == (t.first == "modified") else "second")
                        if t.task == "2afc" else "correct" if chosen else "incorrect")
        elif observers:
            response = _observer_response(obs[t.group], t, float(ui))
        else:
            response = "correct" if ui < model.probability(t.group, t.level, shift) else "incorrect"
        row = rows[t.stimulus]
        dur = 1000.0 * row.frames / row.fps if row.fps > 0 else math.nan
        if not math.isfinite(dur) or dur <= 0:
            dur = 2000.0
        nxt = _post(submit_answer, session, {
            "participant": pid, "session": session.session, "trial": t.trial,
            "stimulus": t.stimulus, "response": response,
            "rt_ms": round(float(min(max(rti, 150.0), 20000.0)), 1),
            "shown_ms": round(max(dur + float(ji), 0.0), 1),
            "late_frames": int(li), "replays": 0, "input": "simulated"})["next_trial"]

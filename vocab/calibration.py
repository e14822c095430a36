"""Calibrations: psychometric functions, fitted to perception studies, that turn a
measured physical error into the probability that a viewer notices it.

A calibration file is JSON (``format`` = :data:`FORMAT`), written by
``flipstudy calibrate`` (:func:`flipstudy.study.calibrate.calibrate`, fitted by
:mod:`flipstudy.analysis.calibrate`) or shipped with
the package (:func:`default_calibration`, made from real human data only).  Schema::

    {"format": "flipstudy-calibration/1",
     "description": "...",                  # what it was made from
     "include_simulated": false,            # true only with --include-simulated
     "sources": [{"name", "citation" | "path", "sha256": {file: hash}, ...}],
     "functions": [{
        "kind": "takeoff-angle",            # a kind of the registry (flipstudy.vocab.kinds):
                                            # injected, or measured only
        "variant": "smooth" | null,         # e.g. the angular-momentum profile
        "sign": 1 | -1 | 0,                 # 0: fitted on both signs pooled
        "task": "yes-no" | "2afc",
        "style": "ellipsoids" | null,       # character style; null: not recorded
        "pooled": false,                    # true: variants and signs pooled (a fallback)
        "unit": "%",                        # of the error magnitude x = |size|
        "params": {"threshold", "width", "gamma", "lambda", "eta"},   # psignifit MAP
        "samples": {"threshold": [...], "width": [...], "gamma": [...], "lambda": [...]},
        "threshold": x*, "threshold_ci": [lo, hi],    # P(x*) = (1 + γ)/2; null: not reached
        "data": {"x": [...], "k": [...], "n": [...]},
        "max_level": 50, "n_real": 19, "n_simulated": 0, "source": 0}]}

The function is the analysis's (:mod:`flipstudy.analysis.stats`):
``P(judged incorrect | x) = γ + (1 − γ − λ) Φ((x − m)/s)``, ``w = s·3.29``.  The
probability that the error is *noticed* is its part above the base rate,
``p(x) = (P(x) − γ)/(1 − γ)`` (high-threshold correction: a viewer who notices
says "incorrect"; one who does not says so at the base rate γ), 0 for no error;
p and its 95 % interval are the median and quantiles over the posterior ``samples``.

>>> cal = default_calibration()
>>> from flipstudy.vocab.kinds import AM
>>> f = cal.lookup(AM.name, "abrupt", -1)
>>> f.source_name
'Majkowska & Faloutsos 2007, Table 2'
>>> p, lo, hi = f.p_noticed(50.0)
>>> bool(lo < p < hi), bool(p > f.p_noticed(17.0)[0])
(True, True)
>>> cal.lookup("foot-skate", None, 1) is None            # measured, not calibrated
True
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np
from scipy.special import ndtr

from flipstudy.errors import CalibrationError
from .psychometric import WIDTH_SCALE, psychometric_curve  # noqa: F401  (re-exported)

FORMAT = "flipstudy-calibration/1"
TASKS = ("yes-no", "2afc")
#: the shipped default calibration (package data)
DEFAULT_FILE = "default_calibration.json"
_PARAMS = ("threshold", "width", "gamma", "lambda")
#: Bytes of a calibration file (32 MiB; one function with 4,000 posterior samples is about 100 kB).
MAX_CALIBRATION_BYTES = 32 * 2**20


def file_sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@dataclass(frozen=True, eq=False)
class PsychFunction:
    """One calibrated psychometric function (one entry of ``functions``)."""
    kind: str
    variant: str | None
    sign: int
    task: str
    style: str | None
    pooled: bool
    unit: str
    params: dict
    samples: np.ndarray          # (S, 4): threshold, width, gamma, lambda
    threshold: float | None
    threshold_ci: tuple
    data: dict
    max_level: float
    n_real: int
    n_simulated: int
    source: int
    source_name: str = ""

    def p_incorrect(self, x):
        """P(judged incorrect | magnitude x) at the point estimate."""
        p = self.params
        return psychometric_curve(x, p["threshold"], p["width"], p["gamma"], p["lambda"])

    def p_noticed_samples(self, x) -> np.ndarray:
        """(S, …) p(x) = (P(x) − γ)/(1 − γ) under every posterior sample."""
        x = np.asarray(x, float)
        m, w, g, l = (self.samples[:, i].reshape((-1,) + (1,) * x.ndim) for i in range(4))
        return np.clip((1 - g - l) / (1 - g) * ndtr((x - m) / (w / WIDTH_SCALE)), 0.0, 1.0)

    def p_noticed(self, x):
        """(p, low, high): the probability of noticing magnitude ``x``: the posterior
        median and its 95 % equal-tailed interval (so p lies inside its interval)."""
        est, lo, hi = np.quantile(self.p_noticed_samples(x), [0.5, 0.025, 0.975], axis=0)
        return est[()], lo[()], hi[()]

    def describe(self) -> str:
        v = f" {self.variant}" if self.variant else ""
        s = {1: " +", -1: " −", 0: " ±"}[self.sign]
        st = f", {self.style}" if self.style else ""
        return (f"{self.kind}{v}{s} ({self.task}{st}{', pooled over variants and signs' if self.pooled else ''}; "
                f"{self.source_name or 'source ' + str(self.source)}, N = {self.n_real} real"
                + (f" + {self.n_simulated} simulated" if self.n_simulated else "") + ")")

    def to_dict(self) -> dict:
        return {"kind": self.kind, "variant": self.variant, "sign": self.sign, "task": self.task,
                "style": self.style, "pooled": self.pooled, "unit": self.unit,
                "params": {k: round(float(v), 6) for k, v in self.params.items()},
                "samples": {k: [round(float(v), 5) for v in self.samples[:, i]]
                            for i, k in enumerate(_PARAMS)},
                "threshold": _num(self.threshold),
                "threshold_ci": [_num(v) for v in self.threshold_ci],
                "data": {k: [float(v) for v in self.data[k]] for k in ("x", "k", "n")},
                "max_level": float(self.max_level), "n_real": int(self.n_real),
                "n_simulated": int(self.n_simulated), "source": int(self.source)}


def _num(v):
    return None if v is None or not np.isfinite(v) else round(float(v), 4)


@dataclass(frozen=True, eq=False)
class Calibration:
    """A calibration file: its functions, sources and provenance."""
    functions: tuple
    sources: tuple
    description: str = ""
    include_simulated: bool = False
    path: str | None = None

    def lookup(self, kind: str, variant: str | None, sign: int, task: str = "yes-no",
               style: str | None = None) -> PsychFunction | None:
        """The function for an error of ``kind``/``variant`` and ``sign``: the exact
        entry first, then an entry pooled over variants and signs (``pooled``); a
        ``style`` given must match (an entry without a style matches any); among
        several, the one with most real participants.  None: not calibrated."""
        sign, variant = int(np.sign(sign)), variant or None
        cands = [f for f in self.functions if f.kind == kind and f.task == task
                 and (style is None or f.style in (None, style))]
        for tier in (lambda f: not f.pooled and f.variant == variant and f.sign == sign,
                     lambda f: f.pooled):
            hit = [f for f in cands if tier(f)]
            if hit:
                return max(hit, key=lambda f: (f.style == style, f.n_real))
        return None

    def kinds(self) -> list[str]:
        return sorted({f.kind for f in self.functions})

    def to_dict(self) -> dict:
        return {"format": FORMAT, "description": self.description,
                "include_simulated": bool(self.include_simulated),
                "sources": list(self.sources), "functions": [f.to_dict() for f in self.functions]}

    def save(self, path) -> Path:
        """Write the JSON file (through a temporary file: nothing half-written)."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.to_dict(), indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        tmp.replace(path)
        return path

    @classmethod
    def from_dict(cls, d: dict, where: str = "calibration") -> "Calibration":
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            got = d.get("format") if isinstance(d, dict) else type(d).__name__
            raise CalibrationError(f"{where}: format: expected {FORMAT!r}, got {got!r}")
        sources = d.get("sources", [])
        if not isinstance(sources, list) or not all(isinstance(x, dict) for x in sources):
            bad = next((i for i, x in enumerate(sources) if not isinstance(x, dict)), None) \
                if isinstance(sources, list) else None
            raise CalibrationError(f"{where}: sources" + (f"[{bad}]" if bad is not None else "")
                                   + ": expected a list of objects (name, citation or path, sha256)")
        functions = d.get("functions") or []
        if not isinstance(functions, list):
            raise CalibrationError(f"{where}: functions: expected a list of objects")
        fns = []
        for i, f in enumerate(functions):
            w = f"{where}: functions[{i}]"
            try:
                samples = np.column_stack([np.asarray(f["samples"][k], float) for k in _PARAMS])
                params = {k: float(v) for k, v in f["params"].items()}
                src = int(f.get("source", 0))
                fn = PsychFunction(
                    kind=str(f["kind"]), variant=f.get("variant"), sign=int(f["sign"]),
                    task=str(f.get("task", "yes-no")), style=f.get("style"),
                    pooled=bool(f.get("pooled", False)), unit=str(f.get("unit", "%")),
                    params=params, samples=samples,
                    threshold=f.get("threshold"), threshold_ci=tuple(f.get("threshold_ci") or (None, None)),
                    data={k: np.asarray(f["data"][k], float) for k in ("x", "k", "n")},
                    max_level=float(f["max_level"]), n_real=int(f["n_real"]),
                    n_simulated=int(f.get("n_simulated", 0)), source=src,
                    source_name=str(sources[src].get("name", "")) if 0 <= src < len(sources) else "")
            except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as e:
                raise CalibrationError(f"{w}: {type(e).__name__}: {str(e)[:200]} (see "
                                       f"flipstudy.stimuli.calibration for the schema)") from None
            if fn.task not in TASKS or fn.sign not in (-1, 0, 1):
                raise CalibrationError(f"{w}: task must be one of {TASKS} and sign 1, -1 or 0")
            missing = [k for k in _PARAMS if k not in params]
            if missing or samples.ndim != 2 or len(samples) < 10:
                raise CalibrationError(f"{w}: params need {list(_PARAMS)} and at least 10 posterior samples")
            _check_ranges(fn, w)
            fns.append(fn)
        if not fns:
            raise CalibrationError(f"{where}: functions: no calibrated function")
        return cls(tuple(fns), tuple(sources), str(d.get("description", "")),
                   bool(d.get("include_simulated", False)), where)

    @classmethod
    def load(cls, path) -> "Calibration":
        """A calibration file: UTF-8 JSON of at most :data:`MAX_CALIBRATION_BYTES`,
        every number in its range (:class:`CalibrationError` naming file and field)."""
        path = Path(path)
        try:
            if not path.is_file():
                raise CalibrationError(f"{path}: no such calibration file" if not path.exists() else
                                       f"{path}: not a regular file; expected a calibration (JSON) file")
            with open(path, "rb") as fh:
                raw = fh.read(MAX_CALIBRATION_BYTES + 1)
        except OSError as e:
            raise CalibrationError(f"{path}: cannot read the calibration file: {e.strerror}") from None
        if len(raw) > MAX_CALIBRATION_BYTES:
            raise CalibrationError(f"{path}: larger than the {MAX_CALIBRATION_BYTES // 2**20} MiB a "
                                   f"calibration file may be (stimuli.calibration.MAX_CALIBRATION_BYTES)")
        try:
            d = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError as e:
            raise CalibrationError(f"{path}: not UTF-8 text (byte {e.start}); expected a calibration "
                                   f"(JSON) file") from None
        except json.JSONDecodeError as e:
            raise CalibrationError(f"{path}: line {e.lineno}: not JSON ({e.msg})") from None
        except RecursionError:
            raise CalibrationError(f"{path}: not a calibration file (JSON nested too deeply)") from None
        return cls.from_dict(d, str(path))


def _bad(where: str, field: str, what: str, value) -> CalibrationError:
    return CalibrationError(f"{where}.{field}: expected {what}, got {value!r}")


def _check_ranges(fn: PsychFunction, w: str) -> None:
    """Every number of a function in its range: threshold finite, width > 0, γ and λ
    in [0, 1) with γ + λ < 1 (the point estimate and every posterior sample), data
    counts 0 <= k <= n, a finite positive max_level."""
    p = fn.params
    for k in p:
        if not np.isfinite(p[k]):
            raise _bad(w, f"params.{k}", "a finite number", p[k])
    if p["width"] <= 0:
        raise _bad(w, "params.width", "a positive width", p["width"])
    for k in ("gamma", "lambda"):
        if not 0 <= p[k] < 1:
            raise _bad(w, f"params.{k}", "a rate in [0, 1)", p[k])
    if p["gamma"] + p["lambda"] >= 1:
        raise _bad(w, "params", "gamma + lambda < 1", (p["gamma"], p["lambda"]))
    S = fn.samples
    for i, k in enumerate(_PARAMS):
        col = S[:, i]
        ok = np.isfinite(col) & ((col > 0) if k == "width" else (col >= 0) & (col < 1)
                                 if k in ("gamma", "lambda") else True)
        if not ok.all():
            j = int(np.flatnonzero(~ok)[0])
            what = "finite numbers" + {"width": " > 0", "gamma": " in [0, 1)", "lambda": " in [0, 1)"}.get(k, "")
            raise _bad(w, f"samples.{k}[{j}]", what, float(col[j]))
    if (S[:, 2] + S[:, 3] >= 1).any():
        j = int(np.flatnonzero(S[:, 2] + S[:, 3] >= 1)[0])
        raise _bad(w, f"samples[{j}]", "gamma + lambda < 1", (float(S[j, 2]), float(S[j, 3])))
    x, k, n = (fn.data[c] for c in ("x", "k", "n"))
    if not (x.shape == k.shape == n.shape and x.ndim == 1):
        raise _bad(w, "data", "x, k and n of one length", (x.shape, k.shape, n.shape))
    if not (np.isfinite(x).all() and np.isfinite(n).all() and (n >= 0).all() and (k >= 0).all() and (k <= n).all()):
        raise _bad(w, "data", "finite levels x and counts 0 <= k <= n", "other values")
    if not (np.isfinite(fn.max_level) and fn.max_level > 0):
        raise _bad(w, "max_level", "a finite positive level", fn.max_level)
    if fn.n_real < 0 or fn.n_simulated < 0:
        raise _bad(w, "n_real", "counts >= 0", (fn.n_real, fn.n_simulated))
    for field, v in (("threshold", fn.threshold), *((f"threshold_ci[{i}]", c) for i, c in enumerate(fn.threshold_ci))):
        if v is not None and not (isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)):
            raise _bad(w, field, "a finite number or null", v)


@lru_cache(maxsize=1)
def default_calibration() -> Calibration:
    """The calibration shipped with the package: real human data only (FwP Table 2;
    see its ``sources``)."""
    text = resources.files("flipstudy.stimuli").joinpath("data", DEFAULT_FILE).read_text(encoding="utf-8")
    return Calibration.from_dict(json.loads(text), f"default (flipstudy/stimuli/data/{DEFAULT_FILE}: "
                                                    f"FwP 2007 Table 2, real participants)")


def get_calibration(calibration=None) -> Calibration:
    """A :class:`Calibration`, a path to one, or None (the default)."""
    if calibration is None:
        return default_calibration()
    if isinstance(calibration, Calibration):
        return calibration
    return Calibration.load(calibration)

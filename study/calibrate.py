"""``flipstudy calibrate``: study folders in, a calibration file out.

Reads each study's answers (simulated participants left out unless asked) and
design (each group's kind, profile, sign, task and style), hashes its files, and
fits with :func:`flipstudy.analysis.calibrate.calibrate_answers`; the result is a
:class:`~flipstudy.stimuli.calibration.Calibration`.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from flipstudy.analysis.calibrate import calibrate_answers
from flipstudy.analysis.io import load_responses, resolve_responses_path, select_participants
from flipstudy.errors import CalibrationError
from flipstudy.stimuli.calibration import Calibration, file_sha256
from flipstudy.stimuli.design import load_design

#: the files of a study whose hashes a calibration records
HASHED = ("design.toml", "manifest.csv", "responses.csv")


def _group_keys(root: Path) -> dict:
    """group → (kind, profile, sign, task, style) from the study's design.toml."""
    design = root / "design.toml"
    if not design.is_file():
        raise CalibrationError(f"{root}: no design.toml: calibrate needs the study's design to know "
                               f"each group's kind, profile, sign, task and style")
    d = load_design(design)
    return {g.name: (g.kind, g.profile, int(g.sign), g.task, d.style_of(g)) for g in d.groups}


def study_answers(study, index: int = 0, *, include_simulated: bool = False):
    """A study's selected answers with its groups' calibration keys, and its source record."""
    csv = resolve_responses_path(study)
    root = csv.parent
    keys = _group_keys(root)
    catch = load_design(root / "design.toml").exclusions.catch_groups   # none takes the shared original
    df = load_responses(csv, catch_groups=catch)
    df, who = select_participants(df, include_simulated=include_simulated)
    unknown = sorted(set(df["group"]) - set(keys))
    if unknown:
        raise CalibrationError(f"{csv}: groups {unknown} are not in {root / 'design.toml'}")
    k = df["group"].map(keys)
    df = df.assign(kind_=k.str[0], variant=k.str[1], sign=k.str[2], task_=k.str[3], style_=k.str[4],
                   source=index, pid=f"{index}/" + df["participant"].astype(str),
                   simulated_=df["participant"].isin(set(who["simulated"])))
    src = {"name": root.name, "path": str(root.resolve()),
           "sha256": {f: file_sha256(root / f) for f in HASHED if (root / f).is_file()},
           "participants": len(who["real"]), "simulated": len(who["simulated"])}
    return df, src


def calibrate(studies, *, include_simulated: bool = False, seed: int = 0,
              n_samples: int = 400) -> Calibration:
    """A calibration from one or more study folders (:mod:`flipstudy.analysis.calibrate`)."""
    parts, sources = [], []
    for i, s in enumerate(studies):
        df, src = study_answers(s, i, include_simulated=include_simulated)
        parts.append(df)
        sources.append(src)
    d = calibrate_answers(pd.concat(parts, ignore_index=True), sources, seed=seed, n_samples=n_samples)
    return Calibration.from_dict(d, "calibration")

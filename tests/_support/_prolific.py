"""Shared builders of issue 32's tests: a catch group's TOML and the records an exported
site writes for one participant (start, answers, end)."""
import json

from flipstudy.study.session import load_study
from flipstudy.study.web.order import order_groups, web_trial_order
from flipstudy.study.web.site import FORMAT
from _site_names import as_site_writes

#: an attention-check group: a gross error (100 % abrupt, twice the paper's largest level)
CATCH_GROUP = """
[[groups]]
name = "catch"
kind = "angular-momentum"
profile = "abrupt"
sign = 1
levels = [100]
"""


def web_records(study_dir, pid, *, run="r1", site_id="s", response=lambda t: "correct", end=True, **extra):
    """The records of one complete run of ``pid`` as the site writes them (``response(trial)``
    gives each answer; ``extra`` goes on every record, e.g. the recruiter's ids)."""
    st = load_study(study_dir)
    trials = web_trial_order(order_groups(st.design, st.manifest), st.design.repetitions, st.design.seed, pid,
                             st.design.online.block_order)
    base = {"format": FORMAT, "site_id": site_id, "study": st.design.name, "manifest_sha256": st.manifest_sha256,
            "host": "jatos", "participant": pid, "run_id": run, "run_started": "2026-01-05T10:00:00.000Z",
            "timestamp": "2026-01-05T10:00:01.000Z", **extra}
    recs = [dict(base, record="start", n_trials=len(trials), order=" ".join(t.stimulus for t in trials),
                 refresh_hz=60.0, consent="2026-01-05T10:00:00.500Z", window="900x760", screen_ok=True)]
    if st.design.online.block_order == "latin-square":      # the blocks' order, as the site records it
        recs[0]["block_order"] = " ".join(dict.fromkeys(t.group for t in trials))
    recs += [dict(base, record="answer", trial=t.trial, stimulus=t.stimulus, group=t.group, level=t.level,
                  repetition=t.repetition, clip=t.clip, kind=t.kind, response=response(t), rt_ms=600.0,
                  shown_ms=400.0, input="key", replays=0, frames_expected=12, frames_presented=12,
                  frames_dropped=0, dropped_pct=0.0, playback_ms=400.0, video_ms=400.0, timing="rvfc",
                  playback_flagged=False, max_dropped_pct=10.0, refresh_hz=60.0) for t in trials]
    if end:
        recs.append(dict(base, record="end", answered=len(trials), n_trials=len(trials)))
    return as_site_writes(study_dir, recs)


def write_jsonl(path, recs):
    path.write_text("".join(json.dumps(r) + "\n" for r in recs))
    return path


def guide_prolific_tables() -> str:
    """The TOML of docs/guide/sessions.md's "Running on Prolific" (its catch group, [online]
    and [exclusions]): what the guide tells a researcher to add to ``flipstudy init``'s design."""
    import re
    from pathlib import Path
    guide = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "sessions.md").read_text()
    block, = [b for b in re.findall(r"```toml\n(.*?)```", guide, re.S) if "catch_groups" in b]
    return block

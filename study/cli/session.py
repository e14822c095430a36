"""Session commands of the ``flipstudy`` CLI: run, export, status, simulate.

``add_commands(subparsers)`` adds them to the main parser (:mod:`flipstudy.study.cli`);
each sets ``func`` to a handler ``handler(args) -> int``.
"""
from __future__ import annotations

import argparse
import json
import sys

from .common import add_json, add_study_dir


def _int_in(lo: int, hi: int | None = None, what: str = "a whole number", rule: str | None = None):
    """An argparse type: a whole number in [lo, hi], refused in one line otherwise."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if v < lo or (hi is not None and v > hi):
            raise argparse.ArgumentTypeError(f"{rule or f'expected a number >= {lo}'}, got {v}")
        return v
    return parse


_port = _int_in(0, 65535, "a port number", "a port is 0..65535 (0: a free one)")
_positive_int = _int_in(1)
_nonneg_int = _int_in(0)


def cmd_run(args) -> int:
    from ..server import serve
    try:
        return serve(args.study_dir, args.participant, host=args.host, port=args.port,
                     open_browser=not args.no_browser, new_session=args.new_session,
                     iti_ms=args.iti_ms, allowed_hosts=args.allowed_host)
    except KeyboardInterrupt:
        return 0


def cmd_export(args) -> int:
    from ..pipeline import export
    print(export(args.study_dir, args.out, participants_out=args.participants_out,
                 include_simulated=args.include_simulated).summary())
    return 0


def cmd_status(args) -> int:
    from ..pipeline import status
    res = status(args.study_dir)
    from ..frozen import design_change
    changed = design_change(args.study_dir)
    if changed:                     # flagged on every call; run, export and analyze refuse
        print(f"flipstudy status: WARNING: {changed}", file=sys.stderr)
    print(json.dumps([r.to_dict() for r in res.sessions], indent=2) if args.json else res.summary())
    return 0


def _strengths(args):
    if getattr(args, "strengths", None) is None:
        return None
    from .compare import strengths_arg
    return strengths_arg(args.strengths)


def cmd_simulate(args) -> int:
    from ..pipeline import simulate
    print(simulate(args.study_dir, args.participants, model=args.model, seed=args.seed,
                   strengths=_strengths(args)).summary())
    return 0


def add_commands(subparsers) -> None:
    """Add ``run``, ``export``, ``status`` and ``simulate`` to an argparse subparsers object."""
    p = subparsers.add_parser(
        "run", help="run one participant's session in the browser (local server)",
        description="Start a local web server for one participant's session and open the "
                    "participant page in the default browser: instructions, demographics, "
                    "examples of correct motions, the test trials (with breaks), the end. "
                    "Answers are stored in STUDY_DIR/sessions.sqlite as they are given; run the "
                    "same command again to resume an interrupted session.")
    add_study_dir(p, "study folder (manifest.csv, design.toml, render/<stimulus>.mp4)")
    p.add_argument("--participant", required=True, metavar="ID",
                   help="participant ID: 1-32 letters, digits, '_' or '-'")
    p.add_argument("--port", type=_port, default=0, help="TCP port (default: a free one)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1, this machine only)")
    p.add_argument("--allowed-host", action="append", default=[], metavar="NAME",
                   help="with a --host other than loopback: a name the participant's browser "
                        "uses for this machine, accepted in the Host header (repeatable; "
                        "default: this machine's host names and addresses)")
    p.add_argument("--no-browser", action="store_true", help="print the URL, do not open a browser")
    p.add_argument("--new-session", action="store_true",
                   help="start a new session for this participant (the earlier ones are kept)")
    p.add_argument("--iti-ms", type=_nonneg_int, default=500, metavar="MS",
                   help="blank interval with a fixation cross before each motion (default 500)")
    p.set_defaults(func=cmd_run)

    p = subparsers.add_parser(
        "export", help="write responses.csv (one row per trial) and participants.csv",
        description="Write the answers as DESIGN.md's long format (participant, session, trial, "
                    "stimulus, group, level, repetition, response, rt_ms, shown_ms, timestamp, "
                    "plus clip, kind, late_frames, replays, input, simulated, complete) and the "
                    "demographics as participants.csv beside it; both atomically. Simulated "
                    "participants are left out unless --include-simulated; sessions that did not "
                    "answer every trial are marked complete=false.")
    add_study_dir(p)
    p.add_argument("--out", metavar="responses.csv", default=None,
                   help="output file (default STUDY_DIR/responses.csv)")
    p.add_argument("--participants-out", metavar="participants.csv", default=None,
                   help="demographics file (default: participants.csv next to --out)")
    p.add_argument("--include-simulated", action="store_true",
                   help="also write the simulated participants (flipstudy simulate), marked "
                        "simulated=true on every row (default: left out)")
    p.add_argument("--exclude-simulated", action="store_true", help=argparse.SUPPRESS)  # the default now
    p.set_defaults(func=cmd_export)

    p = subparsers.add_parser(
        "status", help="who has done what: sessions, answered/total, finished",
        description="One line per participant session: source (browser/simulated), "
                    "answered/total (INCOMPLETE when not every trial is answered), started, last "
                    "answer, finished; then the number of real and simulated participants.")
    add_study_dir(p)
    add_json(p, "print a JSON list")
    p.set_defaults(func=cmd_status)

    p = subparsers.add_parser(
        "simulate", help="answer every trial with simulated observers (sim001...)",
        description="Simulated participants answer every trial through the same validation and "
                    "storage as the participant page. The observer model gives P(correct) per "
                    "group and level (default: the paper's Table 2 ratings) with a per-participant "
                    "logit shift ~ N(0, sigma). A study with quest+ or 2afc groups is answered by "
                    "observers with known psychometric functions instead (one per group and "
                    "participant, drawn from a population); export --include-simulated writes "
                    "their parameters to simulated_truth.csv.")
    add_study_dir(p)
    p.add_argument("--participants", type=_positive_int, required=True, metavar="N",
                   help="number of simulated participants (IDs sim001..)")
    p.add_argument("--model", metavar="MODEL.toml", default=None,
                   help="observer model: [groups.NAME] levels = [...], p_correct = [...]; sigma = 0.3")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--strengths", metavar="SOURCE=LOGIT,...", default=None,
                   help="a comparison study ([[sources]]): observers with these known Bradley–Terry "
                        "source strengths (logits), e.g. gt=0,jitter=-1,floaty=-2")
    p.set_defaults(func=cmd_simulate)

"""Session commands of the ``flipstudy`` CLI: run, export, status, simulate.

``add_commands(subparsers)`` adds them to the main parser (:mod:`flipstudy.study.cli`);
each sets ``func`` to a handler ``handler(args) -> int``.
"""
from __future__ import annotations

from flipstudy.stimuli.exceptions import FlipstudyError

import argparse
import json
import sys

from ..validate import RequestError
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


def _fail(cmd: str, e: Exception) -> int:
    msg = e.message if isinstance(e, RequestError) else str(e)
    print(f"flipstudy {cmd}: error: {msg}", file=sys.stderr)
    return 1


def cmd_run(args) -> int:
    from ..server import serve
    try:
        return serve(args.study_dir, args.participant, host=args.host, port=args.port,
                     open_browser=not args.no_browser, new_session=args.new_session,
                     iti_ms=args.iti_ms, allowed_hosts=args.allowed_host)
    except (FlipstudyError, RequestError) as e:
        return _fail("run", e)
    except KeyboardInterrupt:
        return 0


def cmd_export(args) -> int:
    from ..export import export_responses
    try:
        r = export_responses(args.study_dir, args.out, participants_out=args.participants_out,
                             include_simulated=args.include_simulated)
    except FlipstudyError as e:
        return _fail("export", e)
    who = f"{len(r['real'])} real participant(s)"
    if r["simulated"]:
        who += f" and {len(r['simulated'])} simulated (marked simulated=true on every row)"
    print(f"wrote {r['rows']} responses of {who} to {r['responses']} and {r['sessions']} session(s) "
          f"to {r['participants']}")
    if r["simulated_left_out"]:
        print(f"left out {len(r['simulated_left_out'])} simulated participant(s) "
              f"({r['simulated_left_out'][0]}..{r['simulated_left_out'][-1]}); "
              f"--include-simulated writes them, marked")
    if r["incomplete"]:
        print(f"{len(r['incomplete'])} incomplete session(s), marked complete=false (analyze leaves "
              f"them out by default): {', '.join(r['incomplete'][:8])}"
              + (", ..." if len(r["incomplete"]) > 8 else ""))
    return 0


def cmd_status(args) -> int:
    from pathlib import Path

    from ..export import status
    from ..store import db_path
    d = Path(args.study_dir)
    if not (d / "manifest.csv").is_file():
        return _fail("status", ValueError(f"{d} is not a study folder (no manifest.csv)"))
    try:
        rows = status(d) if db_path(d).exists() else []
    except FlipstudyError as e:
        return _fail("status", e)
    from ..frozen import design_change
    changed = design_change(d)
    if changed:                     # flagged on every call; run, export and analyze refuse
        print(f"flipstudy status: WARNING: {changed}", file=sys.stderr)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    if not rows:
        print("no sessions yet")
        return 0
    head = ("participant", "session", "source", "answered", "", "started", "last answer", "finished")
    table = [(r["participant"], str(r["session"]), r["source"], f"{r['answered']}/{r['total']}",
              "" if r["complete"] else "INCOMPLETE",
              r["started"] or "—", r["last_answer"] or "—", r["finished"] or "no") for r in rows]
    widths = [max(len(h), *(len(t[i]) for t in table)) for i, h in enumerate(head)]
    line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip()  # noqa: E731
    print(line(head))
    for t in table:
        print(line(t))
    done = sum(1 for r in rows if r["finished"])
    print(f"{len(rows)} session(s), {done} finished")
    real = sorted({r["participant"] for r in rows if not r["simulated"]})
    sim = sorted({r["participant"] for r in rows if r["simulated"]})
    print(f"{len(real)} real participant(s), {len(sim)} simulated"
          + (" (left out of export and analyze unless --include-simulated)" if sim else ""))
    inc = [r for r in rows if not r["complete"]]
    if inc:
        print(f"{len(inc)} incomplete session(s) (analyze leaves them out by default): "
              + ", ".join(f"{r['participant']}/{r['session']} {r['answered']}/{r['total']}" for r in inc))
    return 0


def _strengths(args):
    if getattr(args, "strengths", None) is None:
        return None
    from .compare import strengths_arg
    return strengths_arg(args.strengths)


def cmd_simulate(args) -> int:
    from ..simulate import simulate
    try:
        ids = simulate(args.study_dir, args.participants, model=args.model, seed=args.seed,
                       strengths=_strengths(args))
    except (FlipstudyError, RequestError) as e:
        return _fail("simulate", e)
    print(f"simulated {len(ids)} participant(s) ({ids[0]}..{ids[-1]}) in "
          f"{args.study_dir}/sessions.sqlite, stored as source=simulated; export and analyze leave "
          f"them out unless --include-simulated. next: flipstudy export {args.study_dir} "
          f"--include-simulated")
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

"""The study online: ``export-web`` (a static jsPsych site) and ``import-web``
(its results back into the study); see :mod:`flipstudy.study.web`."""
from __future__ import annotations

import argparse


def _pct(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a percentage, got {text!r}") from None
    if not 0 <= v <= 100:
        raise argparse.ArgumentTypeError(f"a percentage is 0..100, got {v:g}")
    return v


def cmd_export_web(args) -> int:
    from ..web.site import export_site
    r = export_site(args.study_dir, args.out, host=args.host, iti_ms=args.iti_ms,
                    max_dropped_pct=args.max_dropped_pct, jspsych_dir=args.jspsych_dir,
                    force=args.force)
    print(f"wrote the {r['host']} site of {args.study_dir} to {r['out']}/ ({r['n_trials']} trials, "
          f"{r['videos']} videos, jsPsych {r['jspsych']}, {r['bytes'] / 1e6:.1f} MB; site {r['site_id']})")
    hint = {"static": "upload the folder to any static web host; participants open index.html "
                      "(?PROLIFIC_PID=... or ?participant=...) and download their answers at the end",
            "jatos": "in JATOS: a new study, its assets folder = this folder, one component with "
                     "HTML file index.html and 'Allow reload' ticked; export the results as data",
            "pavlovia": "push the folder to a Pavlovia project (index.html at its root) and set it "
                        "running; results arrive in its data/ folder as CSV"}[r["host"]]
    print(hint)
    print(f"names: videos and trials go by opaque ids, mapped in {r['site_map']} (keep it with the study; "
          f"never upload it)")
    print(f"dropped frames: a trial over {r['max_dropped_pct']:g} % is flagged "
          f"({'--max-dropped-pct' if args.max_dropped_pct is not None else 'the design'})"
          + ("; flagged trials are shown once more at the end" if r["repeat_dropped"] else ""))
    print(f"next: flipstudy import-web {args.study_dir} RESULTS...")
    return 0


def cmd_import_web(args) -> int:
    from ..pipeline import import_results
    print(import_results(args.study_dir, args.files).summary())
    return 0


def add_commands(subparsers) -> None:
    """Add ``export-web`` and ``import-web``."""
    p = subparsers.add_parser(
        "export-web", help="write the study as a static jsPsych site (any web host, JATOS, Pavlovia)",
        description="Write a self-contained static experiment on jsPsych (fetched with npm at its "
                    "pinned version and copied into the site; nothing is loaded from elsewhere when a "
                    "participant runs it): the local page's screens and trial-order rule, seeded by "
                    "the participant ID from the URL (PROLIFIC_PID, participant, ...) or a generated "
                    "one. Answers are checkpointed in the browser after each trial and sent to the "
                    "host's API (JATOS, Pavlovia); the end screen offers them as a download.")
    p.add_argument("study_dir", metavar="STUDY_DIR")
    p.add_argument("--out", required=True, metavar="SITE", help="folder to write (must not exist)")
    p.add_argument("--host", choices=("static", "jatos", "pavlovia"), default="static",
                   help="where the site runs (default static: answers by download only)")
    p.add_argument("--max-dropped-pct", type=_pct, default=None, metavar="PCT",
                   help="flag a trial whose video dropped more than PCT %% of its frames; overrides "
                        "the design's [session] max_dropped_pct (default: the design's, 10 unless set)")
    p.add_argument("--iti-ms", type=int, default=500, metavar="MS",
                   help="blank interval with a fixation cross before each motion (default 500)")
    p.add_argument("--jspsych-dir", metavar="DIR", default=None,
                   help="a folder whose node_modules holds the pinned jsPsych packages (default: "
                        "fetched with npm into ~/.cache/flipstudy/npm)")
    p.add_argument("--force", action="store_true", help="replace an earlier site at --out")
    p.set_defaults(func=cmd_export_web)

    p = subparsers.add_parser(
        "import-web", help="read JATOS, Pavlovia or download results into STUDY/web/responses.csv",
        description="Read the site's results (JATOS result data or archive, Pavlovia CSV, the "
                    "participant's .jsonl download) into STUDY_DIR/web/responses.csv in the local "
                    "export's long format, source marked. A malformed row refuses the whole import "
                    "with its file and line. Each file is kept under STUDY_DIR/web/imports/; "
                    "importing a file again, or the same answers from two files, adds nothing.")
    p.add_argument("study_dir", metavar="STUDY_DIR")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.set_defaults(func=cmd_import_web)

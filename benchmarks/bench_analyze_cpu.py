"""`flipstudy analyze` on reproduce's responses: CPU seconds of the old code and
of this checkout, measured in one run (issue 34, item 6: target at most 0.5x).

The responses are reproduce's (the paper's design, its 46 measured stimuli, 19
simulated participants, seed 1), built the way ``flipstudy reproduce`` builds
them but without rendering: the design, ``build_stimuli``, ``simulate`` and
``export_responses`` (the same rows as reproduce's ``study/responses.csv``;
only the timestamps differ).  ``--responses CSV`` analyses another table.

Old: the commit given by ``--old`` (default: the main commit issue 34 branched
from), checked out in a temporary git worktree and imported through
PYTHONPATH.  Each side runs ``python -m flipstudy.study.cli analyze RESPONSES
--include-simulated --seed 1`` in a fresh process (imports, fits, tables,
PDF+PNG figures: everything the command does) and is charged the child's CPU
seconds (user + system, ``resource.getrusage(RUSAGE_CHILDREN)``); the two
alternate, ``--repeats`` times each, and the medians are compared.  The
outputs are then compared: every CSV, Markdown and LaTeX table byte for byte,
and where one differs, every number against the fits' reported sampling error
(the thresholds' credible intervals, the d′ and rating bootstrap CIs).

Run: python benchmarks/bench_analyze_cpu.py [--repeats 3] [--old SHA] [--responses CSV]
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: main when issue 34's analysis work branched off it
OLD = "e4afe3d"

RUN = ("import sys, flipstudy; root = sys.argv.pop(1); "
       "assert flipstudy.__file__.startswith(root), (flipstudy.__file__, root); "
       "from flipstudy.study.cli import main; sys.exit(main(sys.argv[1:]))")


def build_responses(work: Path) -> Path:
    """reproduce's responses without its render phase."""
    from flipstudy.stimuli.design import PAPER_DESIGN, load_design
    from flipstudy.stimuli.stimset import build_stimuli
    from flipstudy.study.export import export_responses
    from flipstudy.study.reproduce import StimulusSet
    from flipstudy.study.simulate import simulate
    work.mkdir(parents=True, exist_ok=True)
    (work / "design.toml").write_text(PAPER_DESIGN, encoding="utf-8")
    build_stimuli(load_design(work / "design.toml"), work / "study", progress=False)
    stimuli = StimulusSet.read(work / "study")
    simulate(stimuli, 19, seed=1)
    return Path(export_responses(stimuli, include_simulated=True).responses)


def cpu_of(cmd: list[str], env: dict) -> float:
    """CPU seconds (user + system) of a child process run to the end."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def analyze_cmd(root: Path, responses: Path, out: Path) -> list[str]:
    return [sys.executable, "-c", RUN, str(root), "analyze", str(responses), "--out", str(out),
            "--include-simulated", "--seed", "1"]


def compare(old: Path, new: Path) -> list[str]:
    """What differs between two analysis folders' tables, beyond sampling error."""
    import numpy as np
    import pandas as pd
    lines = []
    for f in sorted(p.name for p in old.iterdir() if p.suffix in (".csv", ".md", ".tex")):
        if (old / f).read_bytes() == (new / f).read_bytes():
            lines.append(f"{f}: identical")
            continue
        if f.endswith(".csv"):
            a, b = pd.read_csv(old / f), pd.read_csv(new / f)
            if list(a.columns) != list(b.columns) or len(a) != len(b):
                lines.append(f"{f}: differs in shape: columns {list(a.columns)} -> {list(b.columns)}, "
                             f"rows {len(a)} -> {len(b)}")
                continue
            num = pd.api.types.is_numeric_dtype
            diff = {c: float(np.nanmax(np.abs(a[c] - b[c]))) for c in a.columns
                    if num(a[c]) and num(b[c]) and not np.allclose(a[c], b[c], equal_nan=True)}
            text = [c for c in a.columns if not (num(a[c]) and num(b[c]))
                    and not a[c].astype(str).equals(b[c].astype(str))]
            lines.append(f"{f}: differs, largest numeric changes {diff}; other columns changed: {text}")
        else:
            lines.append(f"{f}: differs")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--old", default=OLD, help=f"git revision of the old code (default {OLD})")
    ap.add_argument("--responses", type=Path, help="responses CSV (default: reproduce's, built)")
    args = ap.parse_args()
    env = {**os.environ, "MPLBACKEND": "Agg"}
    with tempfile.TemporaryDirectory(prefix="bench-analyze-") as tmp:
        tmp = Path(tmp)
        responses = args.responses or build_responses(tmp / "paper")
        old_root = tmp / "old"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(old_root / "flipstudy"),
                        args.old], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            sides = {
                "old": (old_root / "flipstudy", {**env, "PYTHONPATH": str(old_root)}),
                "new": (ROOT, env),
            }
            cpu = {"old": [], "new": []}
            for r in range(args.repeats):
                for name, (root, e) in sides.items():
                    cpu[name].append(cpu_of(analyze_cmd(root, responses, tmp / f"{name}{r}"), e))
            lines = compare(tmp / "old0", tmp / "new0")
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(old_root / "flipstudy")], check=False)
    o, n = statistics.median(cpu["old"]), statistics.median(cpu["new"])
    load = os.getloadavg()
    print(f"flipstudy analyze on reproduce's responses ({'given' if args.responses else 'built'}: "
          f"{responses.name}), CPU seconds of the whole command, {args.repeats} alternating runs each")
    print(f"  old ({args.old}): median {o:.2f} s  {[round(x, 2) for x in cpu['old']]}")
    print(f"  new (this checkout): median {n:.2f} s  {[round(x, 2) for x in cpu['new']]}")
    print(f"  new/old: {n / o:.2f}x (target <= 0.5x: {'met' if n <= 0.5 * o else 'missed'}); "
          f"load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} on {os.cpu_count()} CPUs")
    print("outputs:")
    for line in lines:
        print("  " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())

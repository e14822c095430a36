"""A worker the readers' fuzzers run in a subprocess: address space limited to
2 GB (``RLIMIT_AS``), each case under a 60 s alarm.  It reads one JSON case per
line on stdin and writes one JSON result per line on stdout:

* ``{"kind": "clip", "path": P, "kwargs": {...}}``: ``load_clip(P, **kwargs)``;
* ``{"kind": "calibration", "path": P}``: ``Calibration.load(P)``;
* ``{"kind": "design", "path": P, "out": O}``: ``Design.from_toml(P)``, for a
  comparison design ``plan_comparison`` (every check made before building), and
  with ``out`` the build into ``O``.

A result is ``{"status": "ok" | "error" | "bug", "message": ..., "seconds": ...}``:
``error`` a :class:`~flipstudy.errors.FlipstudyError` (its message), ``bug`` any
other exception (its traceback), a ``MemoryError`` or the alarm included.
"""
from __future__ import annotations

import json
import resource
import signal
import sys
import time
import traceback

LIMIT_BYTES = 2 * 2**30
CASE_SECONDS = 60


class CaseTimeout(Exception):
    pass


def _alarm(signum, frame):
    raise CaseTimeout(f"case over {CASE_SECONDS} s")


def run(case: dict):
    from flipstudy.stimuli import load_clip
    from flipstudy.stimuli.calibration import Calibration
    from flipstudy.stimuli.design import Design
    if case["kind"] == "clip":
        load_clip(case["path"], **case.get("kwargs", {}))
    elif case["kind"] == "calibration":
        Calibration.load(case["path"])
    elif case["kind"] == "design":
        d = Design.from_toml(case["path"])
        if d.compares:
            from flipstudy.stimuli.compare import plan_comparison
            plan_comparison(d)
        if case.get("out"):
            from flipstudy.stimuli.stimset import build_stimuli
            build_stimuli(d, case["out"], progress=False)
    else:
        raise ValueError(f"unknown case kind {case['kind']!r}")


def main() -> int:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_BYTES, LIMIT_BYTES))
    signal.signal(signal.SIGALRM, _alarm)
    import warnings
    warnings.simplefilter("ignore")
    from flipstudy.errors import FlipstudyError
    for line in sys.stdin:
        case = json.loads(line)
        t0 = time.monotonic()
        signal.alarm(CASE_SECONDS)
        try:
            run(case)
            out = {"status": "ok", "message": ""}
        except FlipstudyError as e:
            out = {"status": "error", "message": str(e)}
        except BaseException:                     # noqa: BLE001 - a bug, reported with its traceback
            out = {"status": "bug", "message": traceback.format_exc()}
        finally:
            signal.alarm(0)
        out["seconds"] = time.monotonic() - t0
        out["id"] = case.get("id")
        print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

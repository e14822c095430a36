"""What the benchmark scripts share: a call run several times, its wall times kept.

The scripts run as ``python benchmarks/bench_X.py``, which puts this folder on
``sys.path``: they import it as ``from _common import ...``.
"""
from __future__ import annotations

import statistics
import time


def wall_times(fn, n: int, *, warmup: bool = False):
    """The wall times in seconds of ``n`` calls of ``fn`` and the last call's
    result; ``warmup``: one untimed call first (imports, caches)."""
    if warmup:
        fn()
    times, out = [], None
    for _ in range(n):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return times, out


def best_s(fn, n: int, *, warmup: bool = False) -> float:
    """The fastest of ``n`` calls of ``fn``, in seconds."""
    return min(wall_times(fn, n, warmup=warmup)[0])


def median_s(fn, n: int, *, warmup: bool = False) -> float:
    """The median of ``n`` calls of ``fn``, in seconds."""
    return statistics.median(wall_times(fn, n, warmup=warmup)[0])


def cpu_times(fn, n: int, *, warmup: bool = False):
    """The CPU times in seconds (``time.process_time``: this process, every
    thread) of ``n`` calls of ``fn``; ``warmup``: one untimed call first."""
    if warmup:
        fn()
    times = []
    for _ in range(n):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return times

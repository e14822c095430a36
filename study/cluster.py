"""Building and rendering a study on Dask distributed (``--cluster ADDRESS``).

:class:`Cluster` connects to a running scheduler (``tcp://host:port``) or starts
a :class:`distributed.LocalCluster` (``local:N``: N worker processes, one thread
each), and runs the same task functions as the local loops, one task per
stimulus: :func:`flipstudy.stimuli.stimset.make_stimulus` for ``flipstudy
stimuli`` and :func:`flipstudy.render.workers.render_on_worker` for ``flipstudy
render``.  The client keeps what must happen in one place: the study lock, the
manifest (rows put back in plan order, so it is the local build's), the atomic
publish of the study folder, moving finished renders into place and
``render.json``.

Files: the workers read and write the study folder directly (the build's
staging folder ``.NAME.tmp-*``, the render's ``render/.partial-PID``), so client
and workers must see it at the same path on a shared filesystem.  Before any
work a probe file written by the client must be read back by every worker (and
a file each worker writes read by the client); otherwise :class:`NoSharedFolderError`
names the workers that cannot see it.  Bytes are not shipped back.

Versions: before any work, every worker's Python and key packages
(:data:`KEY_PACKAGES`) must equal the client's, or :class:`VersionMismatchError`
names them; each task checks again on its worker (a worker that joins later).

Stop and restart: tasks are pure functions of their inputs, so a task whose
worker dies is rerun by the scheduler on another worker (Dask's lineage;
``distributed.scheduler.allowed-failures`` times); a stopped command leaves the
same state as a stopped local one (no study published; renders resumable).
"""
from __future__ import annotations

import logging
import os
import secrets
import sys
from contextlib import nullcontext
from pathlib import Path

from flipstudy.errors import ClusterError, NoSharedFolderError, VersionMismatchError

#: the distributions whose versions must match between client and workers
KEY_PACKAGES = ("flipstudy", "numpy", "scipy", "vtk", "pyvista", "imageio-ffmpeg",
                "OpenImageIO", "dask", "distributed", "cloudpickle")


def installed_versions() -> dict:
    """The Python version and the installed versions of :data:`KEY_PACKAGES`
    (None for one not installed).

    >>> v = installed_versions()
    >>> v["python"] == sys.version.split()[0], sorted(v)[:3]
    (True, ['OpenImageIO', 'cloudpickle', 'dask'])
    """
    from importlib.metadata import PackageNotFoundError, version
    out = {"python": sys.version.split()[0]}
    for name in KEY_PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def _report_versions() -> dict:
    return installed_versions()          # looked up at call time (a test can patch it)


def version_problems(mine: dict, theirs: dict) -> list[str]:
    """``"numpy 2.1.0 (client 2.2.1)"`` for every version that differs.

    >>> version_problems({"numpy": "2.2.1", "python": "3.11.2"},
    ...                  {"numpy": "2.1.0", "python": "3.11.2"})
    ['numpy 2.1.0 (client 2.2.1)']
    """
    return [f"{k} {theirs.get(k)} (client {v})" for k, v in mine.items() if theirs.get(k) != v]


_CHECKED: dict = {}


def _checked(expected: dict, fn, *args):
    """Run ``fn(*args)`` on a worker whose versions equal ``expected`` (checked
    once per worker process)."""
    if _CHECKED.get("expected") != expected:
        bad = version_problems(expected, _report_versions())
        if bad:
            raise VersionMismatchError(f"worker pid {os.getpid()}: {', '.join(bad)}; install the "
                                  f"client's versions on every worker")
        _CHECKED["expected"] = expected
    return fn(*args)


def _value(x):
    """A task that returns its argument: data the scheduler can recompute (its
    lineage is the literal) if the worker holding it dies."""
    return x


def _probe(path: str, token: str) -> tuple[str, str]:
    return _probe_files(path, token)     # looked up at call time (a test can patch it)


def _probe_files(path: str, token: str) -> tuple[str, str]:
    """On a worker: read the client's probe file and write a reply beside it;
    returns ("ok" or what went wrong, the reply's path)."""
    import socket
    reply = f"{path}-{socket.gethostname()}-{os.getpid()}"
    try:
        seen = Path(path).read_text()
        Path(reply).write_text(token)
    except OSError as e:
        return f"{type(e).__name__}: {e}", reply
    return ("ok" if seen == token else f"{path} holds other bytes (another file system?)"), reply


def parse_address(text: str) -> tuple[str, object]:
    """``("local", N)`` for ``local:N``, ``("scheduler", address)`` for a
    scheduler address (``tcp://host:port``, ``tls://``, ``ws://`` …).

    >>> parse_address("local:2"), parse_address("tcp://10.0.0.5:8786")
    (('local', 2), ('scheduler', 'tcp://10.0.0.5:8786'))
    """
    text = str(text).strip()
    if text.startswith("local:"):
        try:
            n = int(text[6:])
        except ValueError:
            n = 0
        if n < 1:
            raise ClusterError(f"--cluster {text!r}: local:N needs a number of workers N >= 1")
        return "local", n
    if "://" in text and text.split("://", 1)[1]:
        return "scheduler", text
    raise ClusterError(f"--cluster {text!r}: expected tcp://HOST:PORT (a running `dask scheduler`) "
                       f"or local:N (a LocalCluster of N worker processes)")


class Cluster:
    """A Dask client for one command: ``with Cluster("local:2") as c:`` and
    pass ``cluster=c`` to :func:`~flipstudy.stimuli.stimset.build_stimuli` and
    :func:`~flipstudy.render.study.render_study`.  Checks the workers' versions
    on entry (:class:`VersionMismatchError`)."""

    def __init__(self, address: str, timeout: float = 60.0):
        from distributed import Client, LocalCluster
        kind, where = parse_address(address)
        self.address, self._local = address, None
        try:
            if kind == "local":
                # Dask starts workers with MALLOC_TRIM_THRESHOLD_=65536, which also fixes
                # glibc's mmap threshold: building a stimulus took 1.7x as long (numpy's
                # arrays mapped and unmapped each time); the workers here start without it
                import dask
                env = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ",
                                                        {}).items()
                       if k != "MALLOC_TRIM_THRESHOLD_"}
                with dask.config.set({"distributed.nanny.pre-spawn-environ": env}):
                    self._local = LocalCluster(n_workers=where, threads_per_worker=1,
                                               processes=True, dashboard_address=":0",
                                               silence_logs=logging.ERROR)
                self.client = Client(self._local)
            else:
                self.client = Client(where, timeout=timeout)
                self.client.wait_for_workers(1, timeout=timeout)
        except (OSError, TimeoutError) as e:
            self.close()
            raise ClusterError(f"--cluster {address}: cannot reach the scheduler or its "
                               f"workers ({e})") from None
        try:
            self.versions = installed_versions()
            self.check_versions()
        except BaseException:
            self.close()
            raise

    @property
    def n_workers(self) -> int:
        """Workers connected now."""
        return len(self.client.scheduler_info()["workers"])

    def check_versions(self) -> None:
        """Refuse (:class:`VersionMismatchError`) any worker whose versions differ."""
        bad = []
        for addr, theirs in sorted(self.client.run(_report_versions).items()):
            p = version_problems(self.versions, theirs)
            if p:
                bad.append(f"{addr}: {', '.join(p)}")
        if bad:
            raise VersionMismatchError(f"--cluster {self.address}: workers differ from this client "
                                  f"(same versions are needed for the same bytes): "
                                  + "; ".join(bad))

    def check_shared(self, folder) -> None:
        """Refuse (:class:`NoSharedFolderError`) unless every worker reads a probe
        file the client writes in ``folder`` and writes one the client reads."""
        folder = Path(folder).resolve()
        token = secrets.token_hex(8)
        probe = folder / f".flipstudy-probe-{token}"
        probe.write_text(token)
        replies, bad = [], []
        try:
            for a, (msg, reply) in sorted(self.client.run(_probe, str(probe), token).items()):
                replies.append(Path(reply))
                if msg == "ok" and not (replies[-1].is_file() and replies[-1].read_text() == token):
                    msg = "the file it wrote did not appear here"
                if msg != "ok":
                    bad.append(f"{a} ({msg})")
        finally:
            for p in [probe, *replies]:
                if p.parent == folder and p.name.startswith(probe.name):   # only our probes
                    p.unlink(missing_ok=True)
        if bad:
            raise NoSharedFolderError(
                f"--cluster {self.address}: {len(bad)} worker(s) cannot see {folder}: "
                + "; ".join(bad) + ". The workers read and write the study folder, so it must be "
                "on a filesystem shared with them at the same path (NFS, Lustre, ...); build "
                "there, or without --cluster")

    def _gather(self, futures: dict, on_result) -> None:
        """``on_result(key, result)`` for each future as it completes (the
        cluster's task stream); the first error cancels the rest and is raised."""
        from distributed import as_completed
        try:
            # results gathered in the background as tasks finish, not one round trip each
            for fut, result in as_completed(list(futures), with_results=True):
                on_result(futures.pop(fut), result)
                fut.release()            # the worker forgets the task (its inputs, its result)
        except BaseException:
            self.client.cancel(list(futures))
            raise

    def map_stimuli(self, fn, design, items, folder, bar) -> list:
        """``fn(design, analysis, item, folder)`` for each ``(item, analysis)`` of
        ``items`` on the workers; returns the results in ``items`` order."""
        self.check_shared(folder)
        run = self.client.submit
        d = run(_value, design, pure=False)
        bases, futs = {}, {}
        for i, (item, a) in enumerate(items):
            if id(a) not in bases:       # each base clip's analysis once
                bases[id(a)] = run(_value, a, pure=False)
            futs[run(_checked, self.versions, fn, d, bases[id(a)], item, str(folder),
                     pure=False, key=f"stimulus-{item[0]}-{secrets.token_hex(4)}")] = i
        rows = [None] * len(items)

        def got(i, row):
            rows[i] = row
            bar.step(items[i][0][0])
        self._gather(futs, got)
        return rows

    def map_render(self, settings: dict, tasks: list, done) -> None:
        """Render ``tasks`` on the workers; ``done(result)`` here for each."""
        from flipstudy.render.workers import render_on_worker
        self.check_shared(Path(settings["out"]))
        s = self.client.submit(_value, settings, pure=False)
        bodies, futs = {}, {}
        for t in tasks:                  # each body (~100 kB) sent once, not with every task
            if id(t["body"]) not in bodies:
                bodies[id(t["body"])] = self.client.submit(_value, t["body"], pure=False)
            t = {**t, "body": bodies[id(t["body"])]}
            futs[self.client.submit(_checked, self.versions, render_on_worker, s, t, pure=False,
                                    key=f"render-{t['stimulus']}-{secrets.token_hex(4)}")] = t
        self._gather(futs, lambda t, res: done(res))

    def close(self) -> None:
        """Close the client (and the LocalCluster this started)."""
        for x in (getattr(self, "client", None), self._local):
            if x is not None:
                try:
                    x.close()
                except Exception:  # noqa: BLE001 — closing a broken connection
                    pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_cluster(address):
    """A :class:`Cluster` for ``address``, or (None) a context that yields None."""
    return nullcontext(None) if not address else Cluster(address)


__all__ = ["Cluster", "ClusterError", "VersionMismatchError", "NoSharedFolderError", "KEY_PACKAGES",
           "installed_versions", "version_problems", "parse_address", "open_cluster"]

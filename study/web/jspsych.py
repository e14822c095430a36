"""jsPsych for the exported site: its npm packages at pinned versions, fetched with
``npm`` into a cache when a site is built (never into the repository), and the
browser bundles copied into the site's ``lib/`` folder.

The pins (:data:`PACKAGES`) are the site's jsPsych; ``flipstudy-site.json`` records
each package's version, npm integrity hash and license, and the page's start
record carries ``jsPsych.version()`` as the browser ran it.  The cache is
``$FLIPSTUDY_NPM_CACHE`` or ``~/.cache/flipstudy/npm``, one folder per set of pins;
a folder that already holds ``node_modules`` from ``npm install`` of the same pins
can be named instead (``export-web --jspsych-dir``), for machines without the
registry.

>>> PACKAGES["jspsych"]
'8.3.0'
>>> sorted(BUNDLES)[:2]
['@jspsych/plugin-html-button-response', '@jspsych/plugin-html-keyboard-response']
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from flipstudy.errors import JsPsychFetchError

#: npm package -> pinned version
PACKAGES = {
    "jspsych": "8.3.0",
    "@jspsych/plugin-instructions": "2.1.0",
    "@jspsych/plugin-survey-html-form": "2.1.0",
    "@jspsych/plugin-preload": "2.1.0",
    "@jspsych/plugin-html-keyboard-response": "2.2.0",
    "@jspsych/plugin-html-button-response": "2.1.0",
    "@jspsych/plugin-video-button-response": "2.1.1",
}
#: npm package -> (file in the package, file in the site's lib/)
BUNDLES = {
    "jspsych": ("dist/index.browser.min.js", "jspsych.js"),
    **{p: ("dist/index.browser.min.js", p.split("/")[1] + ".js") for p in PACKAGES if p != "jspsych"},
}
CSS = ("jspsych", "css/jspsych.css", "jspsych.css")


def _pins_key() -> str:
    return hashlib.sha256(json.dumps(PACKAGES, sort_keys=True).encode()).hexdigest()[:12]


def cache_root() -> Path:
    env = os.environ.get("FLIPSTUDY_NPM_CACHE")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "flipstudy" / "npm"


def _check(folder: Path) -> dict:
    """The packages' records in ``folder/node_modules``; raises when one is missing or
    not at its pinned version."""
    out = {}
    lock = {}
    lock_path = folder / "package-lock.json"
    if lock_path.is_file():
        lock = json.loads(lock_path.read_text()).get("packages", {})
    for name, version in PACKAGES.items():
        pj = folder / "node_modules" / name / "package.json"
        if not pj.is_file():
            raise JsPsychFetchError(f"{folder}: node_modules/{name} is missing (npm install "
                                    f"{name}@{version})")
        meta = json.loads(pj.read_text())
        if meta.get("version") != version:
            raise JsPsychFetchError(f"{pj}: version {meta.get('version')}, the site pins {version}")
        entry = lock.get(f"node_modules/{name}", {})
        out[name] = {"version": version, "license": meta.get("license", ""),
                     "integrity": entry.get("integrity", "")}
    return out


def fetch(jspsych_dir=None, *, npm: str = "npm") -> tuple[Path, dict]:
    """``(folder, packages)``: a folder whose ``node_modules`` holds the pinned
    packages (``jspsych_dir``, or the cache, filled with ``npm install`` when
    empty) and their version/integrity/license records."""
    if jspsych_dir is not None:
        d = Path(jspsych_dir)
        return d, _check(d)
    d = cache_root() / f"jspsych-{PACKAGES['jspsych']}-{_pins_key()}"
    if d.is_dir():
        try:
            return d, _check(d)
        except JsPsychFetchError:
            shutil.rmtree(d, ignore_errors=True)          # a broken cache entry: fetch again
    exe = shutil.which(npm)
    if exe is None:
        raise JsPsychFetchError("the participant page (run, export-web) needs jsPsych, fetched with npm, "
                                "which is not on PATH (apt-get install npm); or name a folder holding "
                                "its node_modules: export-web --jspsych-dir, or $FLIPSTUDY_NPM_CACHE "
                                "holding a filled cache")
    d.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".fetch-", dir=d.parent))
    try:
        (tmp / "package.json").write_text(json.dumps({"name": "flipstudy-site-jspsych", "private": True,
                                                       "version": "0.0.0"}) + "\n")
        cmd = [exe, "install", "--no-audit", "--no-fund", "--ignore-scripts", "--save-exact",
               "--loglevel=error"] + [f"{n}@{v}" for n, v in PACKAGES.items()]
        r = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            tail = (r.stderr or r.stdout).strip().splitlines()[-3:]
            raise JsPsychFetchError(f"npm install of jsPsych failed (exit {r.returncode}): "
                                    + " / ".join(tail))
        packages = _check(tmp)
        try:
            tmp.rename(d)
        except OSError:                                   # another build filled it meanwhile
            shutil.rmtree(tmp, ignore_errors=True)
            return d, _check(d)
        return d, packages
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)

"""The sites exported from a study: ``STUDY/web/sites.json`` (site id → host, folder,
when), written by ``export-web`` and read by ``import-web``, which takes the
results of these sites only."""
from __future__ import annotations

import json
from pathlib import Path

from flipstudy.stimuli._io import atomic_write_text

from ..lock import study_writer
from ._fields import WebImportError

WEB_DIR = "web"
SITES = "sites.json"


@study_writer("export-web")
def remember_site(study_dir, site_id: str, host: str, out, names: str | None = None) -> None:
    """Record in ``STUDY/web/sites.json`` that the site ``site_id`` was exported from
    this study (``export-web``), with the SHA-256 of its ``design.toml`` then;
    ``import-web`` takes results of these sites only, and only while the design is
    the one they were exported with.  ``names="opaque"``: the site names its videos and
    groups by opaque names (:mod:`flipstudy.study.web.opaque`)."""
    import hashlib

    from ..store import utc_now
    path = Path(study_dir) / WEB_DIR / SITES
    sites = read_sites(path) or {}
    sha = hashlib.sha256((Path(study_dir) / "design.toml").read_bytes()).hexdigest()
    sites.setdefault(site_id, {"host": host, "out": str(out), "exported": utc_now(),
                               "design_sha256": sha, **({"names": names} if names else {})})
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(sites, indent=1, sort_keys=True) + "\n")


def read_sites(path: Path) -> dict | None:
    if not path.is_file():
        return None
    try:
        got = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise WebImportError(f"{path}: not readable ({e}); it lists the sites exported from this "
                             f"study") from None
    if not isinstance(got, dict):
        raise WebImportError(f"{path}: expected a JSON object (site id → site)")
    return got



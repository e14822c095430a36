"""The browser tests' screenshot helper: a page's picture in the test's folder,
and a copy in ``$FLIPSTUDY_SCREENSHOTS`` when set (how the README's pictures of
the session and web pages are made)."""
from __future__ import annotations

import os
import shutil
from pathlib import Path


def screenshot(page, name, tmp_path):
    path = tmp_path / name
    page.screenshot(path=str(path))
    keep = os.environ.get("FLIPSTUDY_SCREENSHOTS")
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, Path(keep) / name)
    return path

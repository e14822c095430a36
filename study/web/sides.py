"""Which tone is the character's left side: the sentence and the picture the
instructions show (in the local runner and on the exported site), from the style
the study's videos were rendered in (``render/render.json``; the default style
before the first render).

The picture (:func:`flipstudy.render.sides_figure.sides_image`) is rendered once
per style and kept in ``$XDG_CACHE_HOME/flipstudy/sides`` (``~/.cache/…``), never
in the study folder; the site carries it inside ``config.js`` as a ``data:`` URL.
"""
from __future__ import annotations

import base64
import hashlib
import json
import os
import tempfile
from pathlib import Path

#: the picture's size in CSS pixels (the still and a label on each side)
WIDTH, HEIGHT = 520, 260


def _style(study):
    from flipstudy.render.style import Style
    rec = Path(study.render_dir) / "render.json"
    try:
        return Style.from_dict(json.loads(rec.read_text(encoding="utf-8"))["style"])
    except (OSError, ValueError, KeyError, TypeError):
        return Style()


def cache_dir() -> Path:
    """Where the pictures are kept: ``$XDG_CACHE_HOME/flipstudy/sides`` (default
    ``~/.cache/flipstudy/sides``)."""
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "flipstudy" / "sides"


def _picture(style) -> bytes | None:
    from flipstudy.render.sides_figure import sides_image
    key = hashlib.sha256(json.dumps({"style": style.to_dict(), "v": 2}, sort_keys=True)
                         .encode()).hexdigest()[:20]
    path = cache_dir() / f"{key}.png"
    if path.is_file():
        return path.read_bytes()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".sides-", suffix=".png", dir=path.parent)
        os.close(fd)
        sides_image(tmp, style)
        os.replace(tmp, path)                    # a reader never sees half a picture
    except (ImportError, RuntimeError, OSError):  # no renderer here: the sentence alone
        return None
    return path.read_bytes()


def sides_config(study) -> dict | None:
    """The site's ``sides`` entry: ``text`` (which tone is which side), ``alt``,
    ``image`` (a ``data:image/png`` URL, or None without a renderer), ``width`` and
    ``height``; None when the study's style draws both sides alike."""
    from flipstudy.render.sides_figure import side_words
    style = _style(study)
    words = side_words(style)
    if words is None or words["left"] == words["right"]:
        return None
    text = (f"The figure's left arm and leg are the {words['left']} tone, its right arm and "
            f"leg the {words['right']} one (here seen from behind).")
    png = _picture(style)
    return {"text": text, "alt": f"The figure from behind: left arm and leg {words['left']}, "
                                 f"right arm and leg {words['right']}.",
            "image": None if png is None else "data:image/png;base64," + base64.b64encode(png).decode(),
            "width": WIDTH, "height": HEIGHT}


__all__ = ["sides_config", "cache_dir"]

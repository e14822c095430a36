"""Opaque names in the exported site: no file name or string a participant's browser
receives names a stimulus, a group, an error kind or a level.

``export-web`` names every video and every group of the site by a keyed hash,
HMAC-SHA256 of ``"stimulus:NAME"`` (or ``"group:NAME"``) under a secret key of the
study, truncated to 16 hex digits: ``stimuli/3f0c…e1.mp4`` instead of
``stimuli/backflip_catch_100.mp4``.  The site's trial rows carry the video's name
only (no clip, kind or level), so its records, the answers a participant's browser
keeps and sends, name their trials by the same opaque names.

The key and the map (opaque name → stimulus or group) are kept in the study, in
``STUDY/web/site-map.json`` (:data:`MAP_FILE`), never in the site's folder (which
``export-web`` refuses to write inside the study).  One key per study: every site
exported from it uses the same names, and the map only grows as the manifest does.
``import-web`` reads each record through :func:`reveal`: the names are mapped back
exactly, and a name the map does not know (or a missing map) refuses the import.

The local runner (``flipstudy run``) gives its page the same names (:class:`PageNames`):
its trial screens, examples, video URLs, ``config.js`` and messages name no stimulus,
and each answer's video is mapped back to its stimulus on the server, which stores the
study's own names.

>>> key = bytes(32)
>>> name = opaque_id(key, "stimulus", "backflip_catch_100")
>>> len(name), all(c in "0123456789abcdef" for c in name), "catch" in name
(16, True, False)
>>> opaque_id(key, "group", "catch") != opaque_id(key, "stimulus", "catch")
True
"""
from __future__ import annotations

import hashlib
import hmac
import json
import math
import os
import re
import secrets
from dataclasses import dataclass
from pathlib import Path

from flipstudy.errors import SiteError, WebImportError
from flipstudy.stimuli._io import atomic_write_text

WEB_DIR = "web"
MAP_FILE = "site-map.json"
MAP_FORMAT = "flipstudy-site-map/1"
#: hex digits kept of the HMAC: 64 bits, so two names of one study never share one
ID_HEX = 16
#: the words the map's entries are keyed under (also the HMAC's prefixes)
STIMULUS, GROUP = "stimulus", "group"
ABOUT = ("export-web's opaque names of this study's videos and groups (HMAC-SHA256 under "
         "'key'). import-web needs this file to read the answers back. Keep it with the study; "
         "never upload it: it is what a participant would need to read the conditions.")


def opaque_id(key: bytes, space: str, name: str) -> str:
    """The opaque name of ``name`` (a stimulus or a group, ``space``) under ``key``."""
    return hmac.new(key, f"{space}:{name}".encode("utf-8"), hashlib.sha256).hexdigest()[:ID_HEX]


def map_path(study_dir) -> Path:
    """``STUDY/web/site-map.json``."""
    return Path(study_dir) / WEB_DIR / MAP_FILE


@dataclass(frozen=True)
class SiteMap:
    """A study's key and its opaque names: ``names[space][opaque] = name``."""

    path: Path
    key: bytes
    names: dict

    def id(self, space: str, name: str) -> str:
        """The opaque name of ``name`` (computed from the key: also for a new name)."""
        return opaque_id(self.key, space, name)

    def video(self, stimulus: str) -> str:
        return self.id(STIMULUS, stimulus)

    def group(self, name: str) -> str:
        return self.id(GROUP, name)

    def name(self, space: str, opaque, where: str, field: str) -> str:
        """The stimulus or group ``opaque`` names; :class:`WebImportError` (naming
        ``where``, ``field`` and the map file) when the map does not know it."""
        got = self.names[space].get(opaque) if isinstance(opaque, str) else None
        if got is None:
            raise WebImportError(
                f"{where}: {field} {str(opaque)[:40]!r} is not one of the opaque names in {self.path}; "
                f"import it into the study whose site it came from (or restore that file from the "
                f"study's backup)")
        return got


def _read(path: Path, error=WebImportError) -> SiteMap:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        key = bytes.fromhex(data["key"])
        names = {s: dict(data[s + "s" if s == GROUP else "stimuli"]) for s in (STIMULUS, GROUP)}
        ok = data.get("format") == MAP_FORMAT and len(key) >= 16
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise error(f"{path}: not a readable site map ({type(e).__name__}: {e}); restore it from the "
                    f"study's backup") from None
    if not ok:
        raise error(f"{path}: not a {MAP_FORMAT} file with a key of 16 bytes or more; restore it "
                    f"from the study's backup")
    return SiteMap(path, key, names)


def read_map(study_dir) -> SiteMap:
    """The study's map, read for ``import-web``: a missing or broken file is a
    :class:`WebImportError` naming it."""
    path = map_path(study_dir)
    if not path.is_file():
        raise WebImportError(
            f"{path}: missing; export-web wrote it to map the site's opaque video and trial names "
            f"back to the stimuli, and the answers cannot be read without it: restore it from the "
            f"study's backup (it is never part of the uploaded site)")
    return _read(path)


def site_map(study) -> SiteMap:
    """The map of ``study`` (a loaded study) with every stimulus and group it has now:
    read from ``STUDY/web/site-map.json``, created with a new random key when absent,
    and written again when the study has names it lacks (``export-web``)."""
    path = map_path(study.dir)
    if not path.is_file():
        path.parent.mkdir(parents=True, exist_ok=True)
        body = json.dumps({"format": MAP_FORMAT, "about": ABOUT, "key": secrets.token_hex(32),
                           "stimuli": {}, "groups": {}}, indent=1) + "\n"
        try:                                         # created once: a second export reads this key
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(body)
        except FileExistsError:
            pass
    m = _read(path, SiteError)
    want = {STIMULUS: [r.stimulus for r in study.manifest],
            GROUP: [g.name for g in study.design.groups] + [r.group for r in study.manifest]}
    names = {s: dict(m.names[s]) for s in m.names}
    for space, items in want.items():
        for name in items:
            oid = m.id(space, name)
            if names[space].setdefault(oid, name) != name:
                raise SiteError(f"{path}: {name!r} and {names[space][oid]!r} have the same opaque "
                                f"name {oid}; move the file aside and export again (a new key)")
    if names != m.names:
        data = json.loads(path.read_text(encoding="utf-8"))
        data["stimuli"], data["groups"] = names[STIMULUS], names[GROUP]
        atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    return SiteMap(path, m.key, names)


def hide_config(cfg: dict, m: SiteMap) -> dict:
    """The site's ``window.FLIPSTUDY`` (:func:`flipstudy.study.web.site.site_config`) with
    opaque names: each group and video by its opaque name, each trial row by its video
    only (a 2AFC row also by its comparison's), the between-subject conditions by their
    groups' opaque names, and a new ``site_id`` (the hash of what the site holds)."""
    def row(r):
        out = {"stimulus": m.video(r["stimulus"])}
        if r.get("task") == "2afc":
            out.update(task="2afc", original=m.video(r["original"]) if r.get("original") else "")
        return out
    out = dict(cfg)
    out["groups"] = [[m.group(g), [row(r) for r in rows]] for g, rows in cfg["groups"]]
    out["videos"] = {m.video(s): dict(v, video=f"stimuli/{m.video(s)}.mp4") for s, v in cfg["videos"].items()}
    out["references"] = [{"stimulus": m.video(r["stimulus"]), "video": f"stimuli/{m.video(r['stimulus'])}.mp4"}
                         for r in cfg["references"]]
    out["online"] = dict(cfg["online"], between=[m.group(g) for g in cfg["online"].get("between", [])])
    out.pop("site_id", None)
    out["site_id"] = hashlib.sha256(json.dumps(out, sort_keys=True).encode()).hexdigest()[:16]
    return out


class Revealer:
    """Reads a site's record back in the study's names (:meth:`__call__`); the map is
    read at the first record that needs it.  ``sites``: ``STUDY/web/sites.json`` (a site
    listed there without ``"names": "opaque"`` was exported before the names were
    hidden, and its records name the stimuli themselves)."""

    def __init__(self, study, sites: dict | None):
        self.study, self.sites, self._map = study, sites, None
        self.rows = {r.stimulus: r for r in study.manifest}

    @property
    def map(self) -> SiteMap:
        if self._map is None:
            self._map = read_map(self.study.dir)
        return self._map

    def __call__(self, where: str, rec: dict) -> dict:
        """``rec`` with every opaque name replaced by the stimulus or group it names, and an
        answer's ``level``, ``clip`` and ``kind`` from the manifest row of its stimulus."""
        sid = rec.get("site_id")
        site = (self.sites or {}).get(sid) if isinstance(sid, str) else None
        if isinstance(site, dict) and site.get("names") != "opaque":
            return rec
        m, out = self.map, dict(rec)

        def words(field, space):
            v = rec.get(field)
            if v not in (None, ""):
                if not isinstance(v, str):
                    m.name(space, v, where, field)
                out[field] = " ".join(m.name(space, x, where, field) for x in v.split(" "))
        if self.study.design.online.between:
            words("condition", GROUP)
        if rec.get("record") == "start":
            words("order", STIMULUS)
            if self.study.design.online.block_order == "latin-square":
                words("block_order", GROUP)
        elif rec.get("record") == "answer":
            words("group", GROUP)
            words("original", STIMULUS)
            if "stimulus" in rec:
                out["stimulus"] = s = m.name(STIMULUS, rec["stimulus"], where, "stimulus")
                row = self.rows.get(s)
                out.update(level=row.level if row is not None else math.nan,
                           clip=row.clip if row is not None else "", kind=row.kind if row is not None else "")
        return out


class PageNames:
    """The names the local runner's page knows the stimuli by: the study's opaque names
    (:func:`site_map`, created as ``export-web`` creates it: the exported site's names).

    The server (:mod:`flipstudy.study.server`) sends the page each video, trial and
    example by :meth:`video`, reads each answer's ``stimulus`` back with
    :meth:`stimulus`, and passes each message it sends through :meth:`text`.

    >>> from types import SimpleNamespace as NS
    >>> import tempfile
    >>> st = NS(dir=tempfile.mkdtemp(), manifest=[NS(stimulus="backflip_catch_100", group="catch")],
    ...         design=NS(groups=[NS(name="catch")]))
    >>> names = PageNames(st)
    >>> page = names.video("backflip_catch_100")
    >>> names.stimulus(page), names.stimulus("backflip_catch_100")
    ('backflip_catch_100', None)
    >>> names.text("trial 3 shows 'backflip_catch_100' (level 100 %, chosen by QUEST+)") == f"trial 3 shows '{page}'"
    True
    """

    #: what a message says of a level ("(level 25 %, chosen by QUEST+)"): left out of the page's
    LEVEL_RE = re.compile(r" ?\(level [^)]*\)")

    def __init__(self, study):
        self.map = site_map(study)
        self.real = {self.map.video(r.stimulus): r.stimulus for r in study.manifest}
        self.originals = {r.stimulus: getattr(r, "original", "") for r in study.manifest}
        names = sorted(set(self.real.values()), key=len, reverse=True)
        self._names = (re.compile(r"(?<![\w.-])(?:" + "|".join(re.escape(n) for n in names) + r")(?![\w.-])")
                       if names else None)

    def video(self, stimulus: str) -> str:
        """The page's name of ``stimulus`` (its opaque name)."""
        return self.map.video(stimulus)

    def stimulus(self, page_name) -> str | None:
        """The stimulus the page's ``page_name`` names (None: not one of the page's names)."""
        return self.real.get(page_name) if isinstance(page_name, str) else None

    def pair(self, page_names) -> tuple[str, str] | None:
        """``(modified, first)`` of a 2AFC trial's two videos as the page names them, in
        the order shown: the stimulus that is not the comparison, and ``"original"`` or
        ``"modified"`` (what was shown first); None when they are not the page's names
        of a stimulus and its original.

        >>> from types import SimpleNamespace as NS
        >>> import tempfile
        >>> st = NS(dir=tempfile.mkdtemp(), design=NS(groups=[NS(name="g")]),
        ...         manifest=[NS(stimulus="o", group="g", original=""), NS(stimulus="m", group="g", original="o")])
        >>> names = PageNames(st)
        >>> names.pair([names.video("m"), names.video("o")]), names.pair([names.video("o"), names.video("o")])
        (('m', 'modified'), None)
        """
        if not isinstance(page_names, list) or len(page_names) != 2:
            return None
        a, b = (self.stimulus(x) for x in page_names)
        if a is None or b is None:
            return None
        if self.originals.get(b) == a:
            return b, "original"
        if self.originals.get(a) == b:
            return a, "modified"
        return None

    def text(self, message: str) -> str:
        """``message`` as the page may read it: each stimulus by its page name, no level."""
        message = self.LEVEL_RE.sub("", message)
        return self._names.sub(lambda mo: self.video(mo.group(0)), message) if self._names else message

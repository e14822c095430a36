"""``flipstudy export-web``: the study as a static jsPsych site.

:func:`export_site` writes a folder that any static host serves as it is::

    index.html            the page (a Content-Security-Policy allows only its own folder,
                          and for Pavlovia its API)
    config.js             the study as data: groups and levels, repetitions, keys, texts,
                          each video's frames and frame rate, the dropped-frame threshold
    flipstudy-order.js    the trial-order rule (twin: flipstudy.study.web.order)
    flipstudy-web.js      the timeline on jsPsych, the checkpoint, the host adapter
    flipstudy-web.css
    lib/                  jsPsych and its plugins (npm, pinned: flipstudy.study.web.jspsych)
    stimuli/<id>.mp4      the rendered videos (checked against render.json first), each
                          named by its opaque name (flipstudy.study.web.opaque)
    flipstudy-site.json   what the site is: study, manifest hash, host, jsPsych's packages
                          with versions and integrity hashes, every file's sha256

No file name or string of the folder names a stimulus, group, kind or level: videos,
groups and trials go by keyed hashes whose map (``STUDY/web/site-map.json``, with the
key) stays in the study, outside the folder a researcher uploads.

``host`` is ``static`` (answers kept in the browser and offered as a download),
``jatos`` (the page loads ``jatos.js``, which JATOS serves beside it, and appends every
record to the component's result data) or ``pavlovia`` (Pavlovia's experiment API:
a session is opened, the records saved after every answer, the session closed at the
end).  The dropped-frame threshold is the design's ``[session] max_dropped_pct``
(``max_dropped_pct`` given to the export overrides it), recorded in the site and in
every answer; with ``[session] repeat_dropped = true`` the trials flagged by it are
shown once more after the last trial (their records carry ``repeat = 1``).

Examples
--------
>>> import tempfile, pathlib
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = pathlib.Path(tempfile.mkdtemp())
>>> cfg = site_config(load_study(make_demo_study(tmp / "study")), host="static")
>>> cfg["n_trials"], cfg["host"], sorted(cfg["keys"].items())
(8, 'static', [('correct', 'f'), ('incorrect', 'j')])
>>> cfg["max_dropped_pct"], cfg["repeat_dropped"]          # the design's [session] settings
(10.0, False)
>>> export_site(tmp / "study", tmp / "site", jspsych_dir=...)    # doctest: +SKIP
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path
from types import SimpleNamespace

from flipstudy.errors import SiteError

from .. import timeline as local_timeline
from ..owned import refuse_not_made
from ..session import load_study
from ..validate import DEMOGRAPHIC_FIELDS
from . import jspsych as jsp
from .opaque import hide_config, site_map
from .order import RULE, order_groups
from .sides import sides_config

FORMAT = "flipstudy-web/1"
HOSTS = ("static", "jatos", "pavlovia")
#: the local runner (``flipstudy run``): the same site, served by :mod:`flipstudy.study.server`,
#: with that server as its data endpoint (never written by export-web)
LOCAL = "local"
STATIC = Path(__file__).resolve().parent / "static"
OWN_FILES = ("flipstudy-order.js", "flipstudy-2afc.js", "flipstudy-web.js", "flipstudy-web.css")
#: URL query parameters read as the participant ID, first found wins (Prolific's first)
PARTICIPANT_PARAMS = ("PROLIFIC_PID", "participant", "PARTICIPANT_ID", "workerId", "id")
SITE_RECORD = "flipstudy-site.json"
PAVLOVIA_API = "https://pavlovia.org"


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def probe_video(path: Path) -> dict:
    """``{"frames", "fps", "duration_s"}`` of an MP4, decoded by ffmpeg (imageio-ffmpeg)."""
    import imageio_ffmpeg
    gen = imageio_ffmpeg.read_frames(str(path))
    try:
        meta = next(gen)
    finally:
        gen.close()
    frames, secs = imageio_ffmpeg.count_frames_and_secs(str(path))
    fps = float(meta.get("fps") or 0.0)
    if frames < 1 or fps <= 0:
        raise SiteError(f"{path}: ffmpeg finds {frames} frames at {fps} fps; render it again")
    return {"frames": int(frames), "fps": fps, "duration_s": round(frames / fps, 6)}


def _texts(study, n_trials: int) -> dict:
    """The local page's wording (flipstudy.study.timeline), so both say the same."""
    shim = SimpleNamespace(study=study, n_trials=n_trials, trials=[], participant="", session=1)
    screens = {s["type"]: s for s in local_timeline.build_timeline(
        shim, {"answered": 0, "demographics": False})["timeline"]}
    ex = screens.get("examples", {})
    words = local_timeline.texts(study.design)
    out = {"instructions_title": screens["instructions"]["title"],
           "instructions": screens["instructions"]["paragraphs"],
           "demographics_title": screens["demographics"]["title"],
           "demographics_text": screens["demographics"]["text"],
           "examples_title": ex.get("title", ""), "examples_text": ex.get("text", ""),
           "examples_button": ex.get("button", "Start the test"),
           "keys_sentence": words["keys_sentence"],
           "prompt": local_timeline.PROMPT,
           "end_title": screens["end"]["title"],
           "end_saved": "All your answers are saved. The study is complete.",
           "end_static": "The study is complete. Please download your answers and send the file "
                         "to the experimenter as they asked you to.",
           "end_download": "A copy of your answers stays in this browser; you may also download it."}
    if not local_timeline.is_default(study.design):
        out.update(prompt_2afc=local_timeline.PROMPT_2AFC, remember=words["remember"], noun=words["noun"])
    return out


def markdown_html(text: str) -> str:
    r"""A consent or debrief text as HTML: a small Markdown subset (``#`` headings,
    paragraphs split by blank lines, ``-``/``*`` lists, ``**bold**``, ``*italic*``),
    everything else escaped (a text file is never HTML).

    >>> markdown_html("# Consent\n\nYou may **stop** at any time.\n\n- a\n- b <i>")
    '<h2>Consent</h2><p>You may <strong>stop</strong> at any time.</p><ul><li>a</li><li>b &lt;i&gt;</li></ul>'
    """
    import html
    import re

    def inline(t):
        t = html.escape(t, quote=False)
        t = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", t)
        return re.sub(r"(?<![*\w])\*(?!\s)(.+?)(?<!\s)\*", r"<em>\1</em>", t)
    out = []
    for block in re.split(r"\n\s*\n", text.strip().replace("\r\n", "\n")):
        lines = [ln.strip() for ln in block.splitlines() if ln.strip()]
        if not lines:
            continue
        if all(re.match(r"[-*]\s", ln) for ln in lines):
            out.append("<ul>" + "".join(f"<li>{inline(ln[2:].strip())}</li>" for ln in lines) + "</ul>")
        elif lines[0].startswith("#"):
            out.append(f"<h2>{inline(lines[0].lstrip('#').strip())}</h2>")
            if lines[1:]:
                out.append(f"<p>{inline(' '.join(lines[1:]))}</p>")
        else:
            out.append(f"<p>{inline(' '.join(lines))}</p>")
    return "".join(out)


def online_config(study) -> dict:
    """The site's ``online`` settings from the design's ``[online]`` table: the recruiter's
    URL parameters, the completion code and redirect, the consent and debrief texts (read
    from their files beside the design, as HTML), the demographics form on or off, the
    screen minimums and preloading."""
    o = study.design.online
    texts = {}
    for key in ("consent", "debrief"):
        name = getattr(o, key)
        if not name:
            texts[key] = ""
            continue
        path = study.dir / name
        try:
            texts[key] = markdown_html(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as e:
            raise SiteError(f"{study.dir / 'design.toml'}: [online].{key} = {name!r}: cannot read {path} "
                            f"({getattr(e, 'strerror', None) or e}); write the text (Markdown) there") from None
        if not texts[key]:
            raise SiteError(f"{path}: empty; [online].{key} names the text shown to participants")
    return {"recruit_params": list(o.recruit_params), "completion_code": o.completion_code,
            "redirect_url": o.redirect_url(), "consent_html": texts["consent"], "debrief_html": texts["debrief"],
            "demographics": o.demographics, "min_refresh_hz": o.min_refresh_hz,
            "min_width": o.min_width, "min_height": o.min_height, "preload": o.preload,
            "block_order": o.block_order, "between": list(o.between)}


def refuse_adaptive(design) -> None:
    """Raise :class:`SiteError` naming the first adaptive (QUEST+) group: the site runs
    constant-stimuli groups only; QUEST+ runs in the local session runner."""
    for g in design.groups:
        if (getattr(g, "method", "constant") or "constant") != "constant":
            raise SiteError(
                f"design.toml: [[groups]] {g.name!r}: method = {g.method!r} is adaptive; QUEST+ "
                f"runs in the local session runner (flipstudy run), not in the exported site. "
                f"Export a design whose groups are all method = \"constant\", or run this study "
                f"with flipstudy run")


def site_config(study, *, host: str = "static", iti_ms: int = 500, max_dropped_pct: float | None = None,
                video_width: int = 640, videos: dict | None = None, n_trials: int | None = None) -> dict:
    """The ``window.FLIPSTUDY`` object of ``config.js`` (``videos``: stimulus →
    :func:`probe_video`; without it the manifest's frames and fps stand in;
    ``max_dropped_pct`` None: the design's ``[session]`` threshold).  With
    ``host="local"`` (the local runner) the trials, their order and every QUEST+ level
    come from the server, so adaptive groups are allowed, ``groups`` is empty and
    ``n_trials`` is the session's."""
    if host not in HOSTS + (LOCAL,):
        raise SiteError(f"host {host!r}: choose one of {', '.join(HOSTS)}")
    design = study.design
    if host == LOCAL:
        groups, n = [], int(n_trials or 0)
    else:
        refuse_adaptive(design)
        groups = order_groups(design, study.manifest)
        n = sum(len(rows) for _, rows in groups) * int(design.repetitions)
    if max_dropped_pct is None:
        max_dropped_pct = design.session.max_dropped_pct
    vids = {}
    for r in study.manifest:
        name = r.stimulus
        v = (videos or {}).get(name) or {"frames": r.frames, "fps": r.fps if r.fps > 0 else 0.0,
                                         "duration_s": 0.0}
        vids[name] = dict(v, video=f"stimuli/{name}.mp4")
    cfg = {
        "format": FORMAT, "host": host, "study": design.name, "manifest_sha256": study.manifest_sha256,
        "design_seed": int(design.seed), "repetitions": int(design.repetitions), "n_trials": n,
        "order_rule": RULE, "groups": groups, "keys": dict(local_timeline.KEYS),
        "replay": bool(design.session.replay), "break_every": int(design.session.break_every), "iti_ms": int(iti_ms),
        "max_dropped_pct": float(max_dropped_pct), "repeat_dropped": bool(design.session.repeat_dropped),
        "video_width": int(video_width),
        "participant_params": list(PARTICIPANT_PARAMS),
        "references": [{"stimulus": r.stimulus, "video": f"stimuli/{r.stimulus}.mp4"}
                       for r in study.references],
        "videos": vids, "demographic_fields": DEMOGRAPHIC_FIELDS, "texts": _texts(study, n),
        "jspsych_version": jsp.PACKAGES["jspsych"],
        "online": online_config(study),
        "sides": sides_config(study),          # which tone is the left side (a sentence, a picture)
    }
    if not local_timeline.is_default(design):
        cfg.update(keys_2afc=dict(local_timeline.KEYS_2AFC), gap_ms=local_timeline.GAP_MS)
    cfg["site_id"] = hashlib.sha256(json.dumps(cfg, sort_keys=True).encode()).hexdigest()[:16]
    return cfg


def site_csp(host: str) -> str:
    """The page's Content-Security-Policy: its own origin only (and, for Pavlovia, its API)."""
    connect = "'self'" + (f" {PAVLOVIA_API}" if host == "pavlovia" else "")
    return (f"default-src 'none'; script-src 'self'; style-src 'self' 'unsafe-inline'; "
            f"connect-src {connect}; media-src 'self' blob:; img-src 'self' data: blob:; font-src data:; "
            f"base-uri 'none'; form-action 'none'")


def lib_files(jspsych_folder: Path) -> dict[str, bytes]:
    """jsPsych's browser bundles and CSS as the site's ``lib/`` files, from the npm
    packages in ``jspsych_folder`` (:func:`flipstudy.study.web.jspsych.fetch`)."""
    files = {f"lib/{dst}": (jspsych_folder / "node_modules" / pkg / src).read_bytes()
             for pkg, (src, dst) in jsp.BUNDLES.items()}
    pkg, src, dst = jsp.CSS
    files[f"lib/{dst}"] = (jspsych_folder / "node_modules" / pkg / src).read_bytes()
    return files


def site_files(cfg: dict, jspsych_folder: Path | None) -> dict[str, bytes]:
    """The site's code as ``{relative path: bytes}``: ``index.html``, ``config.js`` (``cfg``),
    flipstudy's own scripts and CSS, and (unless ``jspsych_folder`` is None) jsPsych's
    :func:`lib_files`.  ``export-web`` writes these files; the local runner serves the
    same bytes from memory."""
    files = lib_files(jspsych_folder) if jspsych_folder is not None else {}
    scripts = [dst for _, dst in jsp.BUNDLES.values()]
    for f in OWN_FILES:
        files[f] = (STATIC / f).read_bytes()
    files["config.js"] = ("// written by flipstudy export-web; the study as data\n"
                          "window.FLIPSTUDY = " + json.dumps(cfg, indent=1) + ";\n").encode()
    files["index.html"] = _index_html(cfg["host"], scripts).encode()
    return files


def _index_html(host: str, scripts: list[str]) -> str:
    csp = site_csp(host)
    tags = ([f'<script src="jatos.js"></script>'] if host == "jatos" else [])
    tags += [f'<script src="lib/{s}"></script>' for s in scripts]
    tags += ['<script src="config.js"></script>', '<script src="flipstudy-order.js"></script>',
             '<script src="flipstudy-2afc.js"></script>', '<script src="flipstudy-web.js"></script>']
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{csp}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        '<meta name="referrer" content="no-referrer">',
        '<link rel="icon" href="data:,">',
        "<title>Motion study</title>",
        '<link rel="stylesheet" href="lib/jspsych.css">',
        '<link rel="stylesheet" href="flipstudy-web.css">',
        *tags, "</head>", "<body>", '<div id="jspsych-target"></div>',
        "<noscript><p>This study needs JavaScript.</p></noscript>", "</body>", "</html>", ""])


def _site_files(out: Path) -> set[str]:
    """What the site at ``out`` was made of: the files its record lists, and the record."""
    try:
        listed = json.loads((out / SITE_RECORD).read_text(encoding="utf-8")).get("files", {})
    except (OSError, ValueError, AttributeError):
        listed = {}
    return ({str(k) for k in listed} if isinstance(listed, dict) else set()) | {SITE_RECORD}


def export_site(study_dir, out, *, host: str = "static", iti_ms: int = 500,
                max_dropped_pct: float | None = None, video_width: int = 640, jspsych_dir=None,
                force: bool = False) -> dict:
    """Write the site of ``study_dir`` to ``out`` (see the module docstring).
    Returns ``{"out", "host", "site_id", "n_trials", "videos", "jspsych", "bytes",
    "max_dropped_pct", "repeat_dropped", "site_map"}`` (``site_map``: the study's
    ``web/site-map.json``, the key and map of the site's opaque names).

    ``out`` must not exist, or be an earlier site (``flipstudy-site.json``) with
    ``force``; the site is built in a hidden folder beside it and renamed into place.
    ``max_dropped_pct`` None takes the design's ``[session] max_dropped_pct``; a number
    overrides it (the site record says which)."""
    from flipstudy.errors import StaleRenderError
    from flipstudy.render.record import check_rendered
    study = load_study(study_dir)
    refuse_adaptive(study.design)
    out = Path(out)
    if host not in HOSTS:
        raise SiteError(f"--host {host!r}: choose one of {', '.join(HOSTS)}")
    if max_dropped_pct is not None and not 0 <= max_dropped_pct <= 100:
        raise SiteError(f"--max-dropped-pct {max_dropped_pct:g}: a percentage, 0 to 100")
    if out.exists():
        if not out.is_dir() or (any(out.iterdir()) and not (force and (out / SITE_RECORD).is_file())):
            raise SiteError(f"{out} exists" + (" and is not an exported site" if not (out / SITE_RECORD).is_file()
                                               else "; pass --force to replace the earlier site"))
    if out.resolve() == study.dir.resolve() or study.dir.resolve() in out.resolve().parents:
        raise SiteError(f"{out}: write the site outside the study folder {study.dir}")
    if out.is_dir():                      # --force replaces only the earlier site's own files
        refuse_not_made(out, _site_files(out), "export-web --force", "the earlier site")
    missing = study.missing_videos()
    if missing:
        raise SiteError(f"{study.render_dir}: no video of {len(missing)} stimuli (e.g. {missing[0]}.mp4); "
                        f"render them first: flipstudy render {study.dir}")
    try:
        check_rendered(study.stimuli, "video")
    except StaleRenderError as e:
        raise SiteError(str(e)) from None
    videos = {r.stimulus: probe_video(study.video_path(r.stimulus)) for r in study.manifest}
    names = site_map(study)                  # opaque names; the map stays in the study (STUDY/web)
    cfg = hide_config(site_config(study, host=host, iti_ms=iti_ms, max_dropped_pct=max_dropped_pct,
                                  video_width=video_width, videos=videos), names)
    folder, packages = jsp.fetch(jspsych_dir)

    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        for rel, data in site_files(cfg, folder).items():
            (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
            (tmp / rel).write_bytes(data)
        (tmp / "stimuli").mkdir()
        for r in study.manifest:
            shutil.copyfile(study.video_path(r.stimulus), tmp / "stimuli" / f"{names.video(r.stimulus)}.mp4")
        from flipstudy import __version__ as fs_version
        files = {p.relative_to(tmp).as_posix(): _sha256(p) for p in sorted(tmp.rglob("*")) if p.is_file()}
        design_path = study.dir / "design.toml"
        record = {"format": FORMAT, "site_id": cfg["site_id"], "host": host, "study": cfg["study"],
                  "design_sha256": _sha256(design_path),
                  "manifest_sha256": study.manifest_sha256, "n_trials": cfg["n_trials"],
                  "order_rule": RULE, "max_dropped_pct": cfg["max_dropped_pct"],
                  "max_dropped_pct_from": "design" if max_dropped_pct is None else "export-web",
                  "repeat_dropped": cfg["repeat_dropped"],
                  "software": {"flipstudy": fs_version},
                  "jspsych": {"version": jsp.PACKAGES["jspsych"], "packages": packages,
                              "fetched_with": "npm", "loaded_from": "lib/ (this folder)"},
                  "files": files}
        (tmp / SITE_RECORD).write_text(json.dumps(record, indent=2) + "\n")
        os.chmod(tmp, 0o755)
        if out.exists():
            refuse_not_made(out, _site_files(out), "export-web --force", "the earlier site")
            old = out.with_name(f".{out.name}.old")
            if old.exists():
                shutil.rmtree(old)
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old)
        else:
            tmp.rename(out)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    from .sites import remember_site           # import-web takes results of this study's sites only
    remember_site(study.dir, cfg["site_id"], host, out, names="opaque")
    size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    return {"out": out, "host": host, "site_id": cfg["site_id"], "n_trials": cfg["n_trials"],
            "videos": len(videos), "jspsych": jsp.PACKAGES["jspsych"], "bytes": size,
            "max_dropped_pct": cfg["max_dropped_pct"], "repeat_dropped": cfg["repeat_dropped"],
            "site_map": names.path}

"""Small study folders whose groups are 2AFC or adaptive (QUEST+), for the page and
site tests: the demo study's placeholder videos (a square of one colour per stimulus,
moving left to right) under a design written here."""
from __future__ import annotations

from pathlib import Path

from flipstudy.study.demo import write_demo_record, write_test_video

#: one colour per manifest row (RGB), far apart so a frame tells which video it is
PALETTE = [(230, 40, 40), (40, 200, 60), (60, 90, 240), (240, 220, 40), (220, 60, 220), (40, 220, 230),
           (250, 140, 30), (150, 90, 250), (150, 240, 150), (250, 170, 200)]


def design_text(groups: list[dict], *, name="kinds", seed=11, repetitions=2, replay=False,
                break_every=40, original="per-group", task=None) -> str:
    """A design of one clip (backflip) and ``groups`` (each ``{"name", "sign", "levels",
    and any other [[groups]] keys}``, angular-momentum, smooth profile)."""
    lines = ["[study]", f'name = "{name}"', f"seed = {seed}", f"repetitions = {repetitions}",
             f'original = "{original}"'] + ([f'task = "{task}"'] if task else []) + [""]
    lines += ["[session]", f"replay = {'true' if replay else 'false'}", f"break_every = {break_every}", ""]
    lines += ["[[clips]]", 'name = "backflip"', 'source = "backflip"', ""]
    lines += ["[reference]", 'clips = ["backflip"]', ""]
    for g in groups:
        lines += ["[[groups]]", f'name = "{g["name"]}"', 'kind = "angular-momentum"', 'profile = "smooth"']
        for k, v in g.items():
            if k == "name":
                continue
            if isinstance(v, str):
                v = f'"{v}"'
            elif isinstance(v, dict):
                v = "{" + ", ".join(f"{a} = {b:g}" for a, b in v.items()) + "}"
            elif isinstance(v, (list, tuple)):
                v = "[" + ", ".join(f"{x:g}" for x in v) + "]"
            elif isinstance(v, bool):
                v = "true" if v else "false"
            lines.append(f"{k} = {v}")
        lines.append("")
    return "\n".join(lines)


def make_study(out, text: str, *, frames: int = 12, fps: float = 30.0, size=(96, 72),
               videos: bool = True) -> Path:
    """``design.toml`` (``text``), ``manifest.csv`` and (``videos``) one placeholder video
    per stimulus (colour ``PALETTE[i]`` for manifest row i) with its ``render.json``."""
    from flipstudy.study.demo import write_placeholder_study
    out = Path(out)
    rows = write_placeholder_study(out, text, frames=frames, fps=fps, sha256=lambda i: f"{i:064x}")
    if not videos:
        return out
    for i, r in enumerate(rows):
        write_test_video(out / "render" / f"{r.stimulus}.mp4", size=size, frames=frames, fps=fps,
                         color=PALETTE[i % len(PALETTE)])
    write_demo_record(out, rows, size=size, fps=fps)
    return out


def colour_of(study_dir, stimulus: str) -> tuple[int, int, int]:
    """The colour of ``stimulus``'s placeholder video."""
    from flipstudy.stimuli.contract import StimulusSet
    names = StimulusSet.read(study_dir, files=False, design=False).names
    return PALETTE[names.index(stimulus) % len(PALETTE)]


#: JavaScript (one argument: the interval, 1 or 2): resolves, polling in the page on every
#: animation frame, to the colour of the brightest saturated pixel of the video on the
#: stage while that motion plays (the local page's stage, or the site's video element);
#: null when none is seen within 10 s
INTERVAL_COLOUR_JS = """(interval) => new Promise((resolve) => {
  const colour = (v) => {
    const c = document.createElement('canvas');
    c.width = v.videoWidth; c.height = v.videoHeight;
    const g = c.getContext('2d');
    g.drawImage(v, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let best = null, bs = -1;
    for (let i = 0; i < d.length; i += 4) {
      const s = Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]);
      if (s > bs) { bs = s; best = [d[i], d[i + 1], d[i + 2]]; }
    }
    return bs > 60 ? best : null;
  };
  const root = document.getElementById('jspsych-target');
  let done = false;
  setTimeout(() => { done = true; resolve(null); }, 10000);      // never hang a test
  const tick = () => {
    if (done) return;
    if (root.dataset.interval === String(interval)) {
      const v = [...root.querySelectorAll('video')].find((x) => !x.classList.contains('hidden')
                                                             && x.style.visibility !== 'hidden');
      const c = v && v.videoWidth && v.currentTime > 0 ? colour(v) : null;
      if (c) { resolve(c); return; }
    }
    requestAnimationFrame(tick);
  };
  tick();
})"""


def nearest(colour, palette=PALETTE) -> tuple[int, int, int]:
    """The palette colour nearest ``colour`` (H.264 shifts colours a little)."""
    return min(palette, key=lambda p: sum((a - b) ** 2 for a, b in zip(p, colour)))

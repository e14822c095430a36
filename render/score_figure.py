"""The figure of ``flipstudy score --figure``: a clip's timeline with its phases and
each error's probability of being noticed, and a strip of the worst moment."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import _mpl

#: The files ``score --figure`` writes (matplotlib's formats by suffix).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
_PHASE_COLORS = {"flight": "#dbe9f6", "ground": "#eeeeee"}
#: the 95 % bands of the scored errors: a faint fill, one hatching each, an outline
BAND_ALPHA = 0.08
BAND_HATCHES = ("////", "\\\\\\\\", "....", "xxxx", "||||", "----")


def score_figure(clip, scored, path, *, strip: bool = True, panel_size=(120, 170)) -> Path:
    """Write a PNG: top, the timeline (phases shaded, each scored error a bar over
    its span, or a dot at its instant, at its probability with the 95 % interval;
    unscored errors of non-zero size as ticks along the bottom); below, the poses
    around the worst moment (``strip``; needs the renderer).  ``scored``: a
    :class:`~flipstudy.stimuli.score.ClipScore` of ``clip``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import builtin
    >>> from flipstudy.stimuli.score import score
    >>> c = builtin("backflip")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     png = score_figure(c, score(c).clips[0], pathlib.Path(tmp) / "s.png", strip=False)
    ...     png.read_bytes()[:4]
    b'\\x89PNG'
    """
    path = Path(path)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        from flipstudy.errors import FlipstudyValueError
        raise FlipstudyValueError(f"--figure {path}: a figure is written as {', '.join(FIGURE_SUFFIXES)}; "
                                  f"got {path.suffix or 'no suffix'!r}")
    plt = _mpl()
    worst = scored.worst
    img = None
    if strip and worst is not None:
        from .figures import strip_image
        T = scored.duration
        ts = np.clip(worst.worst_t + np.array([-2, -1, 0, 1, 2]) * 0.06, 0.0, T)
        img = strip_image(clip, None, times=np.unique(ts), panel_size=panel_size, span=(float(ts[0]), float(ts[-1])),
                          label="t = {t:.2f} s")
    fig = plt.figure(figsize=(9, 6.4 if img is not None else 3.6), dpi=110)
    ax = fig.add_axes([0.08, 0.47 if img is not None else 0.15, 0.6, 0.42 if img is not None else 0.68])
    for name, t0, t1 in scored.phases:
        kind = "flight" if name.startswith("flight") else "ground"
        ax.axvspan(t0, t1, color=_PHASE_COLORS[kind], lw=0)
        ax.text(0.5 * (t0 + t1), 1.02, name, ha="center", va="bottom", fontsize=8,
                transform=ax.get_xaxis_transform())
    cmap = plt.get_cmap("tab10")
    scored_errs = [e for e in scored.errors if e.scored]
    for i, e in enumerate(scored_errs):
        c = cmap(i % 10)
        lab = f"{e.label()}\n{e.phase}: {e.size:+.1f} {e.unit}, p = {100 * e.p:.1f} %"
        if e.t1 - e.t0 > 1e-6:
            # a faint fill, the band's own hatching and an outline in its colour: where
            # bands overlap, each stays readable (no muddy blend of two fills)
            ax.fill_between([e.t0, e.t1], e.p_low, e.p_high, facecolor=(*c[:3], BAND_ALPHA),
                            edgecolor=c, hatch=BAND_HATCHES[i % len(BAND_HATCHES)], lw=1.0)
            ax.plot([e.t0, e.t1], [e.p, e.p], color=c, lw=2.2, label=lab)
        else:
            ax.errorbar([e.t0], [e.p], yerr=[[e.p - e.p_low], [e.p_high - e.p]], fmt="o", color=c,
                        capsize=3, label=lab)
    unscored = [e for e in scored.errors if not e.scored and abs(e.size) > 0]
    for e in unscored:
        ax.plot([e.worst_t], [-0.04], marker="|", color="0.45", ms=9)
    if unscored:
        ax.plot([], [], marker="|", ls="", color="0.45",
                label=f"measured, not scored ({len(unscored)})")
    if worst is not None:
        ax.axvline(worst.worst_t, color="crimson", ls="--", lw=1)
        ax.text(worst.worst_t, 0.97, " worst moment", color="crimson", fontsize=8, va="top",
                transform=ax.get_xaxis_transform())
    ax.set_xlim(0, max(scored.duration, 1e-3))
    ax.set_ylim(-0.08, 1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("P(noticed)")
    ax.set_title(f"{scored.name}: P(anything noticed) = {100 * scored.p_any:.1f} % "
                 f"[{100 * scored.p_any_low:.1f}, {100 * scored.p_any_high:.1f}]", fontsize=10, pad=18)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    if img is not None:
        ax2 = fig.add_axes([0.04, 0.02, 0.92, 0.34])
        ax2.imshow(img)
        ax2.set_xticks([]), ax2.set_yticks([])
        ax2.set_title(f"worst moment: {worst.label()} at {worst.worst_t:.2f} s "
                      f"(p = {100 * worst.p:.1f} %)", fontsize=9)
    fig.savefig(path)
    plt.close(fig)
    return path

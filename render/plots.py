"""Physics plots of a clip (matplotlib, headless): |L|(t), |p|(t) and COM height
with the flight shaded — the view `flipstudy inspect --plot` writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _mpl():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_analysis(a, path, title: str | None = None) -> Path:
    """Write a three-panel PNG (or PDF, by suffix) of an :class:`~flipstudy.stimuli.analyse.Analysis`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import analyse, builtin
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     png = plot_analysis(analyse(builtin("backflip")), pathlib.Path(tmp) / "backflip.png")
    ...     png.name, png.read_bytes()[:4]
    ('backflip.png', b'\x89PNG')
    """
    plt = _mpl()
    clip = a.clip
    t = clip.times
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 7.0), sharex=True, constrained_layout=True)
    panels = [
        (np.linalg.norm(a.L, axis=1), "|L| (kg·m²/s)", "#0072B2"),
        (np.linalg.norm(a.p, axis=1), "|p| (kg·m/s)", "#D55E00"),
        (a.com[:, 1], "COM height (m)", "#009E73"),
    ]
    for ax, (y, label, colour) in zip(axes, panels):
        for k, f in enumerate(a.flights):
            ax.axvspan(t[f.takeoff], t[f.landing], color="0.85" if k else "#F0E442",
                       alpha=0.5 if k else 0.45, lw=0,
                       label=("main flight" if k == 0 else ("other flights" if k == 1 else None)))
        ax.plot(t, y, color=colour, lw=1.6)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    if a.flight is not None:
        fr = a.flight_frames
        path_y = a.path[1, 0] * (t[fr] - t[a.takeoff]) ** 2 + a.path[1, 1] * (t[fr] - t[a.takeoff]) + a.path[1, 2]
        axes[2].plot(t[fr], path_y, "k--", lw=1.0, label=f"parabola, g = {a.apparent_gravity:.2f} m/s²")
        axes[0].axhline(a.L_mean, color="k", lw=0.8, ls=":", label=f"flight mean {a.L_mean:.1f} (CV {a.L_cv_pct:.1f} %)")
        axes[0].legend(loc="upper right", fontsize=8)
        axes[2].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time (s)")
    name = title or clip.meta.get("name", "clip")
    axes[0].set_title(f"{name}: {clip.num_frames} frames at {clip.fps:g} fps")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_compare(stim, original, path, title: str | None = None, label: str = "stimulus") -> Path:
    """|L|(t) of a stimulus over its original, both from take-off (the paper's
    Figure 3 view), with the |L| change below over the span both are in the air
    (:func:`flipstudy.stimuli.compare.l_change`); ``label``: what the stimulus is
    called (``edit``: "edited")."""
    from flipstudy.stimuli.lchange import l_change
    plt = _mpl()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7.5, 5.5), sharex=True, constrained_layout=True,
                                  gridspec_kw={"height_ratios": [2, 1]})
    series = []
    # frames before take-off are the original's, so both clocks start at the
    # original's take-off frame
    t0 = original.takeoff or 0
    for a, name, colour in ((original, "original", "#E69F00"), (stim, label, "#009E9E")):
        t = (np.arange(a.clip.num_frames) - t0) / a.clip.fps
        L = np.linalg.norm(a.L, axis=1)
        ax.plot(t, L, color=colour, lw=1.8, label=name)
        if a.flight is not None:
            ax.axvspan((a.takeoff - t0) / a.clip.fps, (a.landing - t0) / a.clip.fps, color=colour,
                       alpha=0.12, lw=0)
        series.append((t, L))
    ch = l_change(stim, original)
    if ch is not None and ch.pct.size:
        ax2.plot(ch.t, ch.pct, color="#009E9E", lw=1.6)
        ax2.axhline(0, color="k", lw=0.8)
        ax2.set_ylabel(f"|L| {label} vs original\nwhile both fly (%)")
        ax2.grid(alpha=0.3)
    ax.set_ylabel("|L| (kg·m²/s)")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    ax2.set_xlabel("time from take-off (s)")
    ax.set_title(title or f"{stim.clip.meta.get('name', 'stimulus')} over "
                          f"{original.clip.meta.get('name', 'original')}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_repair(repair, path, title: str | None = None) -> Path:
    """The paper's Figure 3: relative |L| error of an animator-edited flight
    against the original, before and after the momentum repair, over the
    flight's normalised time."""
    plt = _mpl()
    fig, ax = plt.subplots(figsize=(7.0, 3.8), constrained_layout=True)
    for err, label, colour in ((repair.error_before, "edited, before retiming", "#D55E00"),
                               (repair.error_after, "after retiming (repaired)", "#0072B2")):
        x = np.linspace(0.0, 1.0, err.size)
        ax.plot(x, 100 * err, color=colour, lw=1.8, label=label)
    ax.axhline(0, color="k", lw=0.8)
    for y in (-20, 20):
        ax.axhline(y, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("flight time (normalised)")
    ax.set_ylabel("|L| error vs original (%)")
    ax.set_title(title or "angular-momentum error of an animator edit")
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def plot_concat(result, body, path, baseline=None, sources=(), title: str | None = None) -> Path:
    """|L|(t) of a concatenation (solid blue) against the motion-graph join of the
    same two motions (dotted green), as in Figure 8 of Shum, Komura & Yadav
    (2009); the blend window shaded; ``sources``: (label, clip, frame offset)
    drawn thin for reference.  ``result`` and ``baseline`` are
    :class:`flipstudy.stimuli.edit.concat.Concatenation` objects.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flipstudy import Body, builtin
    >>> from flipstudy.stimuli.edit.concat import concatenate, motion_graph_join
    >>> a = builtin("backflip")
    >>> body = Body.from_clip(a)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     png = plot_concat(concatenate(a, a, body=body), body, pathlib.Path(tmp) / "L.png",
    ...                       baseline=motion_graph_join(a, a, body=body))
    ...     png.name, png.stat().st_size > 0
    ('L.png', True)
    """
    from flipstudy.stimuli.physics import momentum
    plt = _mpl()
    fig, ax = plt.subplots(figsize=(8.0, 3.6), constrained_layout=True)
    clip = result.clip
    fps = clip.fps
    rep = result.report
    w0, w1 = rep.blend_out
    ax.axvspan(w0 / fps, w1 / fps, color="#F0E442", alpha=0.45, lw=0, label="blend (after smoothing)")
    for label, c, off in sources:
        L = np.linalg.norm(momentum(c, body).L, axis=1)
        ax.plot((np.arange(c.num_frames) + off) / c.fps, L, color="0.6", lw=0.9, label=label)
    if baseline is not None:
        L = np.linalg.norm(momentum(baseline.clip, body).L, axis=1)
        ax.plot(baseline.clip.times, L, ":", color="#009E73", lw=2.0,
                label=f"motion graph ({baseline.clip.duration:.2f} s)")
    L = np.linalg.norm(momentum(clip, body).L, axis=1)
    ax.plot(clip.times, L, color="#0072B2", lw=2.0, label=f"angular-momentum guided ({clip.duration:.2f} s)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|L| (kg·m²/s)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or clip.meta.get("name", "concatenation"), fontsize=10)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

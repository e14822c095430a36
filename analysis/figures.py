"""Publication figures: ratings, d′, psychometric curves, and a figure sheet.

Every figure is written as PDF (vector, TrueType fonts embedded, no creation
date so that the same data give the same bytes) and PNG.  Colours are the
Okabe–Ito palette (distinguishable with the common colour-vision
deficiencies), and each group also has its own marker, so the figures read in
greyscale too.  No pyplot: figures are ``matplotlib.figure.Figure`` objects,
so nothing here touches global state or needs a display.
"""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import matplotlib as mpl
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .io import group_order
from .stats import PsychometricFit
from .units import POSE_RATE, level_label, magnitude_label, magnitudes, pose_rate_of

#: Okabe & Ito (2008), "Color Universal Design"; yellow last (weak on white)
OKABE_ITO = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442"]
MARKERS = ["o", "s", "^", "v", "D", "P", "X", "h"]
STYLE = {
    "font.size": 9, "axes.titlesize": 9.5, "axes.labelsize": 9, "xtick.labelsize": 8,
    "ytick.labelsize": 8, "legend.fontsize": 8, "axes.spines.top": False, "axes.spines.right": False,
    "axes.linewidth": 0.8, "lines.linewidth": 1.4, "lines.markersize": 5, "errorbar.capsize": 2.5,
    "axes.grid": True, "grid.color": "#e6e6e6", "grid.linewidth": 0.6, "axes.axisbelow": True,
    "pdf.fonttype": 42, "ps.fonttype": 42, "savefig.bbox": "tight", "savefig.pad_inches": 0.03,
    "figure.dpi": 100,
}
PNG_DPI = 200


@contextmanager
def style():
    with mpl.rc_context(STYLE):
        yield


def group_styles(groups) -> dict:
    """group → (colour, marker), stable in table order."""
    return {g: (OKABE_ITO[i % len(OKABE_ITO)], MARKERS[i % len(MARKERS)]) for i, g in enumerate(groups)}


def _no_ligatures(fig: Figure) -> None:
    """Set every text of ``fig`` without ligatures ("fi", "ff"): the PDF writer puts a
    ligature glyph in a second subset of its font, and each subset is one more
    fontTools subsetting pass (about a tenth of a second each, most of a PDF's cost)
    for two glyphs that look the same as the letters side by side."""
    from matplotlib.text import Text
    for t in fig.findobj(Text):
        if t.get_fontfeatures() is None:
            t.set_fontfeatures(("-liga",))


def save(fig: Figure, stem: Path, dpi: int = PNG_DPI) -> list[Path]:
    """``stem.pdf`` and ``stem.png``, laid out once for both; returns both paths.

    The figure is drawn twice, not three times: once by Agg at the PNG's
    resolution (which lays it out and measures its tight box), the PNG being
    that drawing cropped to the box, then once by the PDF writer in the same
    layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.image import imsave
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    pdf, png = stem.with_suffix(".pdf"), stem.with_suffix(".png")
    _no_ligatures(fig)
    with style():                         # savefig reads rcParams (font embedding)
        old_dpi, old_canvas = fig.dpi, fig.canvas
        canvas = FigureCanvasAgg(fig)
        fig.dpi = dpi
        try:
            canvas.draw()                 # the constrained layout, and the PNG's pixels
            box = fig.get_tightbbox(canvas.get_renderer()).padded(mpl.rcParams["savefig.pad_inches"])
            H = canvas.get_renderer().height
            x0, x1 = int(np.floor(box.x0 * dpi)), int(np.ceil(box.x1 * dpi))
            y0, y1 = int(np.floor(H - box.y1 * dpi)), int(np.ceil(H - box.y0 * dpi))
            rgba = np.asarray(canvas.buffer_rgba())[max(y0, 0):y1, max(x0, 0):x1]
            imsave(png, rgba, format="png", dpi=dpi, metadata={"Software": "flipstudy analysis"})
        finally:
            fig.dpi = old_dpi
            fig.set_canvas(old_canvas)
        engine = fig.get_layout_engine()
        fig.set_layout_engine(None)       # keep the positions just computed
        try:
            fig.savefig(pdf, bbox_inches=box,
                        metadata={"CreationDate": None, "Creator": "flipstudy analysis", "Producer": None})
        finally:
            fig.set_layout_engine(engine)
    return [pdf, png]


def _dodge(n: int, step: float) -> np.ndarray:
    return (np.arange(n) - (n - 1) / 2) * step


def _level_axis(ax, levels, unit="%"):
    ticks = sorted(set(float(v) for v in levels))
    if unit == "mixed":               # percent and ms on one axis: whole numbers, none crowded
        span = (ticks[-1] - ticks[0]) or 1.0
        kept = [ticks[0]]
        for t in ticks[1:]:
            if t - kept[-1] > 0.04 * span:
                kept.append(t)
        ax.set_xticks(kept)
        ax.set_xticklabels([f"{t:.0f}" for t in kept])
        ax.set_xlim(ticks[0] - 0.06 * span, ticks[-1] + 0.06 * span)
        return
    ax.set_xticks(ticks)
    if unit == "ms":                  # a pose-rate hold: the ms, and the poses/s under it
        ax.set_xticklabels([f"{t:.0f}\n({1000 / t:g}/s)" if t > 0 else "0\n(orig.)" for t in ticks])
    else:
        ax.set_xticklabels([f"{t:g}" for t in ticks])
    span = (max(ticks) - min(ticks)) or 1.0
    ax.set_xlim(min(ticks) - 0.06 * span, max(ticks) + 0.06 * span)


def _panel_grid(n: int):
    ncols = n if n <= 3 else 3
    nrows = int(np.ceil(n / ncols))
    return nrows, ncols


def ratings_figure(table: pd.DataFrame, ci_label: str = "95% CI", kinds: dict | None = None) -> Figure:
    """Mean rating (% judged correct) against the error level with bootstrap
    confidence intervals over participants: one panel per block of groups that
    share their levels (the paper's angular-momentum and take-off blocks), one
    line per group.  ``kinds`` (group → error kind): a pose-rate block's axis is
    in poses/s."""
    from .tables import blocks
    kinds = kinds or {}
    groups = group_order(table["group"].unique())
    sty = group_styles(groups)
    bl = blocks(table, kinds)
    widths = [max(len(g), 1.0) + 1.2 for _, g in bl]
    with style():
        fig = Figure(figsize=(min(2.0 + 1.25 * sum(widths), 7.2), 3.4), layout="constrained")
        axes = fig.subplots(1, len(bl), sharey=True, squeeze=False, width_ratios=widths)[0]
        for ax, (levels, gs) in zip(axes, bl):
            span = (max(levels) - min(levels)) or 1.0
            dx = _dodge(len(gs), 0.022 * span)
            for i, g in enumerate(gs):
                sub = table[table["group"] == g].sort_values("level")
                c, m = sty[g]
                x = sub["level"].to_numpy() + dx[i]
                y = sub["rating_pct"].to_numpy()
                err = _yerr(y, sub["rating_ci_low"], sub["rating_ci_high"])
                ax.errorbar(x, y, yerr=err, color=c, marker=m, ms=5.5, mfc=c, mec="white", mew=0.6,
                            lw=1.5, elinewidth=0.9, label=g, zorder=3)
            ax.axhline(50, color="0.55", lw=0.8, ls=":", zorder=1)
            _level_axis(ax, levels)
            ax.set_xlabel(level_label(kinds.get(gs[0])))
        axes[0].set_ylim(0, 100)
        axes[0].set_yticks(range(0, 101, 20))
        axes[0].set_ylabel("rated correct (%)")
        handles, labels = [], []
        for ax in axes:
            h, lab = ax.get_legend_handles_labels()
            handles += h
            labels += lab
        fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 3), frameon=False,
                   handlelength=2.2, columnspacing=1.6)
        fig.suptitle(f"points: pooled rating; bars: {ci_label} (bootstrap over participants)",
                     fontsize=7.5, color="0.35", x=0.99, ha="right")
    return fig


def _label_panels(axes, n: int, ylabel: str, xlabel: str) -> None:
    """y labels on the first column, x labels on the bottom panel of each column
    of the first ``n`` panels of a grid; the panels after them hidden."""
    nrows, ncols = axes.shape
    for i in range(n):
        if i % ncols == 0:
            axes.flat[i].set_ylabel(ylabel)
        if i >= n - ncols:
            axes.flat[i].set_xlabel(xlabel)
    for j in range(n, nrows * ncols):
        axes.flat[j].set_visible(False)


def _own_xlabels(axes, labels) -> None:
    """Each panel its own x label when the panels' units differ (else as set)."""
    if len(set(labels)) > 1:
        for ax, lab in zip(axes.flat, labels):
            ax.set_xlabel(lab)
    elif labels and labels[0] != "error level (%)" and labels[0] != "error magnitude |level| (%)":
        for ax in axes.flat:
            if ax.get_xlabel():
                ax.set_xlabel(labels[0])


def dprime_figure(table: pd.DataFrame, ci_label: str = "95% CI", kinds: dict | None = None) -> Figure:
    """d′ against the error level, one panel per group: the pooled d′ (filled,
    as in the paper) and the mean of the participants' d′ (open), each with its
    bootstrap interval over participants.  ``kinds`` (group → error kind): a
    pose-rate group's axis is in poses/s."""
    kinds = kinds or {}
    groups = group_order(table["group"].unique())
    sty = group_styles(groups)
    nrows, ncols = _panel_grid(len(groups))
    finite = table[["dprime", "dprime_pooled_ci_low", "dprime_pooled_ci_high", "dprime_ci_low",
                    "dprime_ci_high"]].to_numpy(float)
    finite = finite[np.isfinite(finite)]
    lo = min(-0.5, float(finite.min()) - 0.1) if finite.size else -0.5
    hi = max(1.0, float(finite.max()) + 0.1) if finite.size else 1.0
    with style():
        fig = Figure(figsize=(2.35 * ncols + 0.3, 2.15 * nrows + 0.2), layout="constrained")
        axes = fig.subplots(nrows, ncols, sharey=True, squeeze=False)
        for i, g in enumerate(groups):
            ax = axes.flat[i]
            sub = table[table["group"] == g].sort_values("level")
            c, m = sty[g]
            x = sub["level"].to_numpy(float)
            step = 0.025 * ((x.max() - x.min()) or 1.0)
            d = sub["dprime"].to_numpy(float)
            ax.axhline(0, color="0.45", lw=0.8, ls="--", zorder=1)
            ax.errorbar(x - step, d, yerr=_yerr(d, sub["dprime_pooled_ci_low"], sub["dprime_pooled_ci_high"]),
                        color=c, marker=m, ms=5.5, mec="white", mew=0.6, lw=1.4, elinewidth=0.9,
                        label="pooled d′", zorder=3)
            dm = sub["dprime_mean_participants"].to_numpy(float)
            ax.errorbar(x + step, dm, yerr=_yerr(dm, sub["dprime_ci_low"], sub["dprime_ci_high"]),
                        color=c, marker=m, ms=5, mfc="white", mec=c, mew=1.1, lw=0, elinewidth=0.9,
                        label="mean of participants' d′", zorder=3)
            ax.set_title(g, color=c, fontsize=10.5)
            _level_axis(ax, x)
            ax.set_ylim(lo, hi)
        _label_panels(axes, len(groups), "sensitivity d′", "error level (%)")
        _own_xlabels(axes, [level_label(kinds.get(g)) for g in groups])
        handles = [mpl.lines.Line2D([], [], color="0.2", marker="o", ls="-", mec="white", label="pooled d′ (as in the paper)"),
                   mpl.lines.Line2D([], [], color="0.2", marker="o", ls="none", mfc="white",
                                    label="mean of participants' d′")]
        where = axes.flat[len(groups)] if len(groups) < nrows * ncols else None
        if where is not None:
            where.set_visible(True)
            where.axis("off")
            where.legend(handles=handles, loc="center", frameon=False,
                         title=f"error bars: {ci_label},\nbootstrap over participants", title_fontsize=8)
        else:
            fig.legend(handles=handles, loc="outside lower center", ncols=2, frameon=False)
    return fig


def _yerr(y, lo, hi) -> np.ndarray:
    """(2, n) error-bar lengths below and above ``y``, never negative: an interval edge
    that equals its estimate up to rounding (or a bootstrap percentile interval that
    does not contain the pooled estimate) draws no bar on that side instead of making
    matplotlib refuse the figure.  NaN (no interval) stays NaN: no bar."""
    y, lo, hi = (np.asarray(a, dtype=float) for a in (y, lo, hi))
    with np.errstate(invalid="ignore"):
        below, above = y - lo, hi - y
    return np.vstack([np.where(below < 0, 0.0, below), np.where(above < 0, 0.0, above)])


def _point_intervals(fit: PsychometricFit, table: pd.DataFrame | None):
    """P(incorrect) per magnitude with an interval: the table's bootstrap CI when
    the magnitude is a single level of the table, else a Wilson 95 % interval."""
    p = fit.k / fit.n
    lo, hi = np.empty_like(p), np.empty_like(p)
    z = 1.959963984540054
    sub = None if table is None else table[table["group"] == fit.group]
    kind = POSE_RATE if fit.unit == "ms" else None
    for i, x in enumerate(fit.x):
        rows = None if sub is None else sub[magnitudes(sub["level"].to_numpy(float), kind) == x]
        if rows is not None and len(rows) == 1 and np.isfinite(rows["rating_ci_low"].iloc[0]):
            lo[i] = 1 - rows["rating_ci_high"].iloc[0] / 100
            hi[i] = 1 - rows["rating_ci_low"].iloc[0] / 100
        else:
            n = fit.n[i]
            c = (p[i] + z * z / (2 * n)) / (1 + z * z / n)
            h = z * np.sqrt(p[i] * (1 - p[i]) / n + z * z / (4 * n * n)) / (1 + z * z / n)
            lo[i], hi[i] = c - h, c + h
    return p, lo, hi


def _draw_fit(ax, fit: PsychometricFit, colour, marker, table=None, annotate=True, label=None):
    xmax = float(fit.x.max())
    xs = np.linspace(0, xmax * 1.04, 300)
    ax.plot(xs, fit.curve(xs), color=colour, lw=1.6, zorder=2, label=label)
    if not annotate:                  # the overview: points only, thresholds as open diamonds
        ax.plot(fit.x, fit.k / fit.n, color=colour, marker=marker, ls="none", ms=4.5, mec="white",
                mew=0.5, zorder=3)
        if fit.reached:
            ax.plot([fit.threshold], [0.5 * (1 + fit.params["gamma"])], marker="D", ms=7, mfc="white",
                    mec=colour, mew=1.6, ls="none", zorder=4)
        return
    p, lo, hi = _point_intervals(fit, table)
    ax.errorbar(fit.x, p, yerr=_yerr(p, lo, hi), color=colour, marker=marker, ls="none",
                ms=5, mec="white", mew=0.6, elinewidth=0.9, zorder=3)
    g = fit.params["gamma"]
    ax.axhline(g, color="0.6", lw=0.8, ls=":", zorder=1)
    pt = 0.5 * (1 + g)
    if fit.reached:
        ax.plot([fit.threshold, fit.threshold], [0, pt], color=colour, lw=0.9, ls="--", zorder=2)
        lo_, hi_ = fit.ci_low, fit.ci_high
        hi_draw = hi_ if np.isfinite(hi_) else xmax * 1.04
        ax.plot([max(lo_, 0), min(hi_draw, xmax * 1.04)], [pt, pt], color=colour, lw=2.6, alpha=0.35,
                solid_capstyle="butt", zorder=2)
        ax.plot([fit.threshold], [pt], marker="|", color=colour, ms=9, mew=1.6, zorder=4)
        txt = f"x* = {fit.threshold:.0f} {fit.unit}"
        if fit.unit == "ms":
            txt += f" ({pose_rate_of(fit.threshold):.1f}/s)"
        txt += (f"\n[{fit.ci_low:.0f}, {fit.ci_high:.0f}]" if np.isfinite(fit.ci_high)
                else f"\n[{fit.ci_low:.0f}, open]")
    else:
        txt = "threshold\nnot reached"
        if np.isfinite(fit.threshold_extrapolated) and fit.threshold_extrapolated < 10 * xmax:
            txt += f"\n(≈ {fit.threshold_extrapolated:.0f} {fit.unit} extrapolated)"
    ax.text(0.04, 0.96, txt, transform=ax.transAxes, va="top", ha="left", fontsize=7.8, color="0.15")


def psychometric_figure(fits: list[PsychometricFit], table: pd.DataFrame | None = None,
                        method_note: str = "", ylabel: str = "P(judged incorrect)") -> Figure:
    """One panel per group: P(judged incorrect) (2AFC: ``ylabel`` P(original chosen))
    against |level| with the fitted function, the base rate γ (dotted), the
    detection threshold x* (where P = (1 + γ)/2; dashed) and its interval (shaded bar).
    A pose-rate group's panel (its fit's unit ``ms``) is against the hold time 1000/N."""
    groups = [f.group for f in fits]
    sty = group_styles(group_order(table["group"].unique()) if table is not None else groups)
    nrows, ncols = _panel_grid(max(len(fits), 1))
    with style():
        fig = Figure(figsize=(2.35 * ncols + 0.3, 2.15 * nrows + 0.2), layout="constrained")
        axes = fig.subplots(nrows, ncols, sharey=True, squeeze=False)
        for i, f in enumerate(fits):
            ax = axes.flat[i]
            c, m = sty.get(f.group, (OKABE_ITO[0], "o"))
            _draw_fit(ax, f, c, m, table)
            ax.set_title(f.group, color=c, fontsize=10.5)
            _level_axis(ax, np.r_[0.0, f.x], f.unit)
            ax.set_ylim(0, 1)
        _label_panels(axes, len(fits), ylabel, "error magnitude |level| (%)")
        _own_xlabels(axes, [magnitude_label(POSE_RATE if f.unit == "ms" else None) for f in fits])
        if len(fits) < nrows * ncols:
            ax = axes.flat[len(fits)]
            ax.set_visible(True)
            ax.axis("off")
            handles = [mpl.lines.Line2D([], [], color="0.2", lw=1.6, label="fitted function"),
                       mpl.lines.Line2D([], [], color="0.2", marker="o", ls="none", label="data ± 95 % CI"),
                       mpl.lines.Line2D([], [], color="0.6", ls=":", label="base rate γ"),
                       mpl.lines.Line2D([], [], color="0.2", ls="--", lw=0.9,
                                        label="threshold x*: P = (1 + γ)/2"),
                       mpl.lines.Line2D([], [], color="0.2", lw=2.6, alpha=0.35, label="interval of x*")]
            ax.legend(handles=handles, loc="center", frameon=False,
                      title=method_note or None, title_fontsize=7.5)
        elif not fits:
            axes.flat[0].text(0.5, 0.5, "no psychometric fits", ha="center", va="center",
                              transform=axes.flat[0].transAxes)
    return fig


def thresholds_figure(per_participant: pd.DataFrame, per_group: pd.DataFrame | None = None) -> Figure:
    """Per-participant detection thresholds x* with their 95 % posterior intervals, one
    column of points per group (adaptive and constant alike), the group's median and
    quartiles as a box beside them."""
    groups = group_order(per_participant["group"].unique())
    sty = group_styles(groups)
    with style():
        fig = Figure(figsize=(1.2 * len(groups) + 1.6, 3.2), layout="constrained")
        ax = fig.subplots()
        for i, g in enumerate(groups):
            sub = per_participant[per_participant["group"] == g].sort_values("threshold")
            c, mk = sty[g]
            x = i + _dodge(len(sub), min(0.5 / max(len(sub), 1), 0.06))
            y = sub["threshold"].to_numpy(float)
            ax.errorbar(x, y, yerr=_yerr(y, sub["ci_low"], sub["ci_high"]), color=c, marker=mk, ms=3.5,
                        ls="none", elinewidth=0.7, mec="white", mew=0.4)
            fin = y[np.isfinite(y)]
            if len(fin):
                q1, med, q3 = np.quantile(fin, [0.25, 0.5, 0.75])
                ax.add_patch(mpl.patches.Rectangle((i + 0.32, q1), 0.16, q3 - q1, fc=c, alpha=0.25, ec=c))
                ax.plot([i + 0.32, i + 0.48], [med, med], color=c, lw=1.6)
        labels = []
        for g in groups:
            m = per_participant.loc[per_participant["group"] == g, ["task", "method"]].iloc[0]
            labels.append(f"{g}\n{m['method']}, {m['task']}")
        ax.set_xticks(range(len(groups)), labels, fontsize=7)
        ax.set_xlim(-0.6, len(groups) - 0.3)
        ax.set_ylabel("threshold x* (%), 95 % posterior interval")
        ax.set_title("Per-participant detection thresholds (box: median and quartiles)", fontsize=8.5)
    return fig


def quest_track_figure(quest, truth=None, title: str = "") -> Figure:
    """One participant's QUEST+ run: left, the level of every trial (filled:
    detected) with the posterior mean of x* and its 95 % interval after each trial;
    right, the final posterior of x* (a histogram of the grid cells' x*, weighted by
    their posterior) and the psychometric function at the posterior mean.  ``truth``:
    a simulated observer (:class:`~.adaptive.Observer`) whose x* and curve are drawn."""
    from .adaptive import Quest
    from .stats import psychometric_curve
    model, hist = quest.model, quest.history
    q = Quest.new(model)
    steps = [q.threshold()]
    for lv, d in hist:
        q.update(lv, d)
        steps.append(q.threshold())
    mean = np.array([s["threshold"] for s in steps])
    lo, hi = np.array([s["ci_low"] for s in steps]), np.array([s["ci_high"] for s in steps])
    c0, c1 = OKABE_ITO[0], OKABE_ITO[1]
    with style():
        fig = Figure(figsize=(7.4, 3.0), layout="constrained")
        ax, ax2 = fig.subplots(1, 2, width_ratios=[1.6, 1])
        t = np.arange(len(steps))
        ax.fill_between(t, lo, hi, step="post", color=c0, alpha=0.18, lw=0, label="95 % interval of x*")
        ax.step(t, mean, where="post", color=c0, lw=1.4, label="posterior mean of x*")
        n = np.arange(1, len(hist) + 1)
        lv = np.array([h[0] for h in hist])
        det = np.array([h[1] for h in hist], bool)
        ax.plot(n[det], lv[det], "o", color=c1, ms=4, label="level shown: detected")
        ax.plot(n[~det], lv[~det], "o", mfc="white", mec=c1, ms=4, label="not detected")
        if truth is not None:
            ax.axhline(truth.threshold, color="0.3", ls="--", lw=0.9, label="true x*")
        ax.set_xlabel("trial")
        ax.set_ylabel("error level (%)")
        ax.set_ylim(0, float(model.levels.max()) * 1.05)
        ax.legend(frameon=False, fontsize=6.5, loc="upper right", ncol=2)
        post = quest.posterior
        bins = np.arange(0, float(model.levels.max()) + 2.5, 2.0)
        ax2.hist(model.xstar, bins=bins, weights=post, color=c0, alpha=0.35, label="posterior of x*")
        ax2.set_xlabel("error magnitude (%)")
        ax2.set_ylabel("posterior probability")
        axp = ax2.twinx()
        xs = np.linspace(0, float(model.levels.max()), 200)
        g = model.gamma if model.task == "yes-no" else np.array([0.5])
        M, W, G = np.meshgrid(model.m, model.width, g, indexing="ij")
        curves = psychometric_curve(xs[:, None], M.ravel(), W.ravel(), G.ravel(), model.lapse)
        axp.plot(xs, curves @ post, color=c0, lw=1.4, label="P(detected), posterior mean")
        if truth is not None:
            axp.plot(xs, truth.p_detect(xs), color="0.3", ls="--", lw=0.9, label="true function")
            ax2.axvline(truth.threshold, color="0.3", ls="--", lw=0.9, ymax=0.7)
        axp.set_ylim(0, 1.45)                            # room for the legend above the curves
        axp.set_yticks([0, 0.25, 0.5, 0.75, 1.0])
        ax2.set_ylim(0, ax2.get_ylim()[1] * 1.45)
        axp.set_ylabel("P(detected)")
        axp.grid(False)
        axp.legend(frameon=False, fontsize=6.5, loc="upper left")
        s = steps[-1]
        ax2.set_title(f"x* = {s['threshold']:.1f} % [{s['ci_low']:.1f}, {s['ci_high']:.1f}]", fontsize=8.5)
        if title:
            fig.suptitle(title, fontsize=9)
    return fig


def _load_image(path: Path, max_px: int = 900):
    """An image file as a uint8 RGBA array (OpenImageIO), shrunk to fit ``max_px``."""
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise OSError(buf.geterror())
    nc = buf.spec().nchannels
    order = {1: (0, 0, 0, 1.0), 2: (0, 0, 0, 1), 3: (0, 1, 2, 1.0)}.get(nc, (0, 1, 2, 3))
    buf = oiio.ImageBufAlgo.channels(buf, order)        # grey → RGB, opaque alpha where none
    w, h = buf.spec().width, buf.spec().height
    if max(w, h) > max_px:                              # keep the aspect, only shrink
        s = max_px / max(w, h)
        buf = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, max(1, round(w * s)), 0, max(1, round(h * s)),
                                                         0, 1, 0, 4))
    if buf.has_error:
        raise OSError(buf.geterror())
    return np.asarray(buf.get_pixels(oiio.UINT8))


def sheet_figure(fits: list[PsychometricFit], table: pd.DataFrame, images: dict | None) -> tuple[Figure, list[str]]:
    """A sheet: the images (ghost and marker-trail composites of an original and
    its strongest error) on the left, each titled with its label (name the
    stimulus and its error there: kind, profile, sign, level), the psychometric
    curves of all groups on the right.  Missing image files leave their slot
    out — nothing is printed into the figure in their place; the returned notes
    say which.  Returns (figure, notes)."""
    notes = []
    present = []
    for label, p in (images or {}).items():
        p = Path(p)
        if p.is_file():
            try:
                present.append((label, _load_image(p)))
            except Exception as e:  # noqa: BLE001
                notes.append(f"figure sheet: image {p} could not be read ({type(e).__name__}: {e}); left out")
        else:
            notes.append(f"figure sheet: image {p} ({label}) not found; left out")
    if not images:
        notes.append("figure sheet: no images given (ghost / marker-trail composites: `flipstudy "
                     "render STUDY --what ghost,trail`, then `analyze STUDY`, or --image); "
                     "the sheet shows the curves only")
    groups = group_order(table["group"].unique())
    sty = group_styles(groups)
    with style():
        if present:
            ncol_img = 2 if len(present) > 1 else 1
            nrow_img = int(np.ceil(len(present) / ncol_img))
            # each image at least at its own pixel size in the PNG (PNG_DPI): the legends
            # drawn into the ghosts and trails stay as readable as in the images themselves
            # (issue 33: at 2.3 inches a row, a 640x480 ghost's legend was 7 px high)
            iw = max(img.shape[1] for _, img in present)
            ih = max(img.shape[0] for _, img in present)
            pw = max(3.0, 1.06 * iw / PNG_DPI)                # + the padding around it
            ph = pw * ih / iw + 0.6                           # + a two-line title
            fig = Figure(figsize=(pw * ncol_img + 4.2, max(3.6, ph * nrow_img)), layout="constrained")
            sf_img, sf_curve = fig.subfigures(1, 2, width_ratios=[pw * ncol_img, 4.2])
            axes = sf_img.subplots(nrow_img, ncol_img, squeeze=False)
            for ax in axes.flat:
                ax.axis("off")
            for ax, (label, img) in zip(axes.flat, present):
                ax.imshow(img, interpolation="antialiased")
                ax.set_title(label, fontsize=8.5)
            ax_c = sf_curve.add_subplot()
        else:
            fig = Figure(figsize=(5.2, 3.8), layout="constrained")
            ax_c = fig.add_subplot()
        for f in fits:
            c, m = sty.get(f.group, (OKABE_ITO[0], "o"))
            _draw_fit(ax_c, f, c, m, table, annotate=False, label=f.group)
        ax_c.set_ylim(0, 1)
        units = sorted({f.unit for f in fits})
        if units == ["ms"]:
            ax_c.set_xlabel(magnitude_label(POSE_RATE))
        elif "ms" in units:           # one axis, two units: say which groups are which
            ax_c.set_xlabel("error magnitude: |level| (%); pose-rate groups: hold 1000/N (ms)")
        else:
            ax_c.set_xlabel("error magnitude |level| (%)")
        ax_c.set_ylabel("P(judged incorrect)")
        ax_c.set_title("psychometric functions (◇ threshold x*: P = (1 + γ)/2)", fontsize=9)
        if fits:
            _level_axis(ax_c, np.r_[0.0, np.concatenate([f.x for f in fits])],
                        units[0] if len(units) == 1 else "mixed")
            ax_c.legend(loc="upper left", frameon=False, fontsize=7.5)
        # what is missing is said in the notes (notes.md), never printed into the figure
    return fig, notes

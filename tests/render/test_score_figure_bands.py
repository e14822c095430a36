"""The score figure's 95 % bands stay readable where they overlap: each a faint fill
with its own hatching and an outline in its colour, not two fills blended into one
muddy colour (issue 42)."""
import matplotlib

matplotlib.use("Agg")

import matplotlib.figure  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

from flipstudy import analyse, builtin  # noqa: E402
from flipstudy.render.score_figure import score_figure  # noqa: E402
from flipstudy.stimuli.injection import inject_angular_momentum  # noqa: E402
from flipstudy.stimuli.score import score  # noqa: E402


def test_overlapping_bands_are_hatched_outlined_and_faint(tmp_path, monkeypatch):
    clip = inject_angular_momentum(analyse(builtin("frontflip")), 0.3, "abrupt").clip
    scored = score(clip).clips[0]
    spans = [e for e in scored.errors if e.scored and e.t1 - e.t0 > 1e-6]
    assert len(spans) >= 2 and spans[0].p_high > spans[1].p_low   # two bands that overlap
    bands, save = [], matplotlib.figure.Figure.savefig

    def savefig(fig, path, **kw):
        bands.extend(c for c in fig.axes[0].collections if isinstance(c, PolyCollection))
        return save(fig, path, **kw)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    score_figure(clip, scored, tmp_path / "s.png", strip=False)
    assert len(bands) == len(spans)
    hatches = [b.get_hatch() for b in bands]
    assert all(hatches) and len(set(hatches)) == len(hatches)       # one hatching each
    for b in bands:
        assert b.get_facecolor()[0][3] <= 0.1                       # a faint fill
        assert b.get_linewidth()[0] > 0 and b.get_edgecolor()[0][3] == 1.0   # an outline

"""Issue 33: "N = 19 participants (0 real, 19 simulated)" lay over ratings.png's legend.
Measured on the drawn figure: the label's box overlaps no legend entry."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from flipstudy.analysis.pipeline import _labelled  # noqa: E402

LABEL = "N = 19 participants (0 real, 19 simulated)"


def _boxes_overlap(a, b):
    return not (a.x1 <= b.x0 or b.x1 <= a.x0 or a.y1 <= b.y0 or b.y1 <= a.y0)


def test_the_label_with_a_figure_legend_is_its_title_and_overlaps_no_entry():
    fig, ax = plt.subplots(figsize=(7, 3.5), constrained_layout=True)
    for i in range(5):
        ax.plot([0, 1], [i, i + 1], label=f"group-{i}")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=3)
    _labelled(fig, LABEL)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    leg = fig.legends[0]
    assert leg.get_title().get_text() == LABEL
    title = leg.get_title().get_window_extent(r)
    for t in leg.get_texts():
        assert not _boxes_overlap(title, t.get_window_extent(r))
    plt.close(fig)


def test_without_a_figure_legend_it_goes_under_the_axes():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="a")
    ax.legend()
    _labelled(fig, LABEL)
    assert fig._supxlabel.get_text() == LABEL
    plt.close(fig)

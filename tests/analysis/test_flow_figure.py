"""The participant-flow figure counts whole participants: integer ticks (issue 42)."""
import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from flipstudy.analysis.exclusions import flow_figure  # noqa: E402


def test_the_flow_axis_ticks_are_whole_participants():
    flow = pd.DataFrame({"stage": ["recruited", "completed", "excluded: catch accuracy", "analysed"],
                         "n": [2, 2, 1, 1]})
    fig = flow_figure(flow)
    try:
        ax = fig.axes[0]
        fig.canvas.draw()
        ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
        assert len(ticks) >= 2
        assert all(float(t).is_integer() for t in ticks), ticks
    finally:
        plt.close(fig)

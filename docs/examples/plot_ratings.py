"""
Ratings and d′ of a simulated panel
===================================

The analysis reads a response table (one row per trial).  Here a simulated
panel answers the paper's study (Majkowska & Faloutsos 2007, Section 7) with
the ratings of its Table 2; :func:`~flipstudy.analysis.summarize` pools it per
group and level into the rating (percent of answers "correct") and d′ against
the original, and :func:`~flipstudy.analysis.to_markdown` lays it out as the
paper's table.  ``flipstudy analyze STUDY`` does the same on a study's answers
and adds the psychometric fits.
"""
import matplotlib.pyplot as plt

from flipstudy.analysis import load_responses, summarize, to_markdown
from flipstudy.analysis.simulate import paper_panel

responses = load_responses(paper_panel(19, seed=0))   # checked and typed
table, per_participant, notes = summarize(responses, n_boot=200, seed=0)
print(to_markdown(table))          # the layout of the paper's Table 2

fig, ax = plt.subplots(figsize=(6, 3.5))
for group, sub in table[table["group"] != "original"].groupby("group", sort=False):
    ax.plot(sub["level"], sub["dprime"], "o-", label=group)
ax.axhline(0, color="0.6", lw=0.8)
ax.set_xlabel("error (% of the original)")
ax.set_ylabel("d′ (judged incorrect)")
ax.legend(fontsize=7)
fig.tight_layout()

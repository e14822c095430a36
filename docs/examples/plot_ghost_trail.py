"""
Ghost and marker-trail composites
=================================

The study's figures (as in Ooi 2016, Chapter 4): a *ghost* composite draws the
character at regular instants of its flight in one picture, a *trail* draws the
paths of chosen joints and of the centre of mass.  Both take a
:func:`~flipstudy.render.stage` (the clip, the camera fitted to its travel and
the image size); here at 160x120 pixels so that the documentation builds fast
(``flipstudy figure`` and ``flipstudy render`` make them at full size).
"""
import matplotlib.pyplot as plt

from flipstudy import builtin
from flipstudy.render import ghost_image, stage, trail_image

st = stage([builtin("backflip")], size=(160, 120))
ghost = ghost_image(st, legend=False)     # at this size a legend would hide the body
trail = trail_image(st, legend=False)

fig, axes = plt.subplots(1, 2, figsize=(6.4, 2.6))
for ax, img, title in zip(axes, (ghost, trail), ("ghost", "marker trails")):
    ax.imshow(img)
    ax.set_title(title)
    ax.set_axis_off()
fig.tight_layout()

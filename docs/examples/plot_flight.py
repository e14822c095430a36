"""
Flight phases and angular momentum of a built-in backflip
==========================================================

:func:`flipstudy.analyse` finds the ballistic phase of a clip (take-off and
landing as sub-frame contact instants), its centre of mass and its momenta.
In flight the centre of mass follows a parabola under gravity and the angular
momentum about it is conserved: the two facts the study's errors break.
"""
import matplotlib.pyplot as plt
import numpy as np

import flipstudy

clip = flipstudy.builtin("backflip")
a = flipstudy.analyse(clip)
t = np.arange(clip.num_frames) / clip.fps
flight = slice(a.takeoff, a.landing + 1)

fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(6, 4.5))
ax1.plot(t, a.com[:, 1], color="0.3", label="centre of mass height")
# the flight parabola fitted to the airborne frames: its curvature is -g/2
c2, c1, c0 = np.polyfit(t[flight], a.com[flight, 1], 2)
ax1.plot(t[flight], np.polyval([c2, c1, c0], t[flight]), "--", color="C1",
         label=f"parabola, g = {-2 * c2:.2f} m/s²")
ax1.set_ylabel("height (m)")
ax1.legend(loc="lower center", fontsize=8)
ax2.plot(t, np.linalg.norm(a.L, axis=1), color="C0")
ax2.set_ylabel("|L| (kg·m²/s)")
ax2.set_xlabel("time (s)")
for ax in (ax1, ax2):
    ax.axvspan(a.takeoff_time, a.landing_time, color="0.9", zorder=0)
fig.suptitle(f"backflip: flight {a.landing_time - a.takeoff_time:.2f} s, "
             f"take-off angle {a.takeoff_angle:.0f}°")
fig.tight_layout()

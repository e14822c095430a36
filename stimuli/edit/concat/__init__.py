"""Angular-momentum guided motion concatenation (Shum, Komura & Yadav 2009).

Two full-body motions (flips, cartwheels, kicks, punches) are joined the way
people chain them, with the angular momentum L(t) about the COM as the cue:

1. **Phases** (:func:`phases`, in ``phases``): from t_m (the frame of largest |L|, or given)
   backwards and forwards to the first frame with L(t)·L(t_m) < 0: preparatory,
   main and posterior phases, each possibly absent, borders overridable.
2. **Rule and alignment**: the *forward* rule (L of both motions the same way:
   the first's momentum is kept up to start the second) or the *reverse* rule
   (opposite: the end of the first prepares the second).  Motion 2 is turned
   about the vertical by θ₂ = arg max|min L̄₁·R_y(θ)L̄₂ (eq. 2), in closed form
   (:func:`align_angle`, in ``phases``), then translated so the centres of the feet coincide at
   the first blended frame.  Torso facing directions (projected on the ground)
   more than π/4 apart at the blend are refused.
3. **Blendable periods** from the rule and the phases (forward: latter half of
   main 1, initial half of main 2; reverse: latter half of main 1 with the latter
   half of preparatory 2, or initial half of posterior 1 with initial half of
   main 2), truncated to double support.  When double support leaves nothing
   (a kick lands its foot only at the very end) the period falls back to the
   frames where the same foot supports in both motions, and the report says so
   (:func:`blendable_periods`, in ``periods``).
4. **Optimal timing** (:func:`optimal_timing`, in ``search``): F(T) = F_dm + F_inertia + F_time
   (eqs. 3-7) for every offset T of motion 2, with f_T the frame of least
   ‖L₁(f) − L₂(f − T)‖² (eq. 5): one (n₁ × n₂) array of all frame pairs, every
   T a diagonal of it; :func:`optimal_timing_bruteforce` is the paper's loop,
   kept as the reference.  A threshold refuses motions too different.
5. **Blending**: slerp per joint, linear root, α from 1 to 0 over
   [f_t0, f_t1], traced from f_T outwards while ‖ΔL‖² stays under a threshold
   and inside both blendable periods (eq. 8); then **angular-momentum smoothing**
   (eq. 9): the blended period is played at rate s, the ratio of the mean of
   |L| at its two ends to its mean |L|, and the result is measured again
   (:func:`blend`, :func:`smoothing_factor`, :func:`smooth`, in ``blend``).
6. **Foot sliding**: each support foot in contact over the transition is pinned
   (analytic two-bone IK, foot orientation kept) at where it stood when the
   blend began, the correction faded out after it lifts; nothing goes below the
   floor; the slide left is measured in centimetres (:func:`pin_feet`,
   :func:`two_bone_ik`, in ``feet``).
7. **Motion-graph baseline** (:func:`motion_graph_join`, in ``motion_graph``): the two motions joined
   where their poses are most similar after the first's main phase and before
   the second's (Kovar, Gleicher & Pighin 2002: point-cloud distance over a
   window, minimised over a rotation about the vertical and a ground
   translation, in closed form; a cubic ease over the window).

The steps above are chained by :func:`concatenate` (``method``), which returns
a :class:`Concatenation` (a :class:`~flipstudy.stimuli.result.Result`) with a
typed :class:`ConcatReport` (both in ``result``); what one motion contributes is its :class:`Motion`
(:func:`motion_of`, in ``motion``); :func:`mirror` (``mirror``) turns a right
kick into a left one.  Every public name is importable from this package.

Units are the library's: metres, seconds, kg; L in kg·m²/s.

>>> from flipstudy.stimuli import builtin
>>> from flipstudy.stimuli.edit.concat import concatenate
>>> c = builtin("backflip")
>>> r = concatenate(c, c)
>>> r.report.rule, r.report.feet.foot_slide_cm < 2.0
('forward', True)
"""
from .blend import blend, smooth, smoothing_factor
from .feet import pin_feet, two_bone_ik
from .method import concatenate
from .mirror import mirror, mirror_pairs, rest_asymmetry
from .motion import Motion, foot_contacts, motion_of, suggest_rule, torso_facing, transformed
from .motion_graph import motion_graph_join, point_cloud_distance
from .periods import blendable_periods, support_frames
from flipstudy.errors import ConcatError
from .phases import UP, Phases, align_angle, phases, yaw
from .result import ConcatReport, Concatenation, FeetReport, MotionGraphReport
from .search import Timing, optimal_timing, optimal_timing_bruteforce

__all__ = ["concatenate", "Concatenation", "ConcatReport", "ConcatError",
           "Phases", "phases", "align_angle", "yaw", "UP",
           "Timing", "optimal_timing", "optimal_timing_bruteforce",
           "Motion", "motion_of", "transformed", "suggest_rule", "torso_facing", "foot_contacts",
           "blendable_periods", "support_frames", "blend", "smoothing_factor", "smooth",
           "two_bone_ik", "pin_feet", "FeetReport",
           "motion_graph_join", "point_cloud_distance", "MotionGraphReport",
           "mirror", "mirror_pairs", "rest_asymmetry"]

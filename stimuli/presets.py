"""Ready designs of published studies (``flipstudy init --preset NAME``).

Each preset is a design (TOML text) with comments that say what its paper
specifies and what had to be assumed: the papers' own motion clips are not
distributed, so the built-ins stand in for them, and where a paper's text does
not give a number (levels, repetitions, the quantity a percentage is of) the
comment says which one was chosen.  ``PAPER_DESIGN`` (Majkowska & Faloutsos
2007) stays the default.

>>> sorted(PRESETS)[:2]
['flipping-with-physics-2007', 'gravity']
>>> from flipstudy.stimuli.design import parse_design
>>> [len(parse_design(t).groups) for t in PRESETS.values()]
[5, 8, 12, 2, 4, 1]
"""

from __future__ import annotations

from .design import PAPER_DESIGN

_HEAD = """\
[study]
name = "{name}"
seed = {seed}
fps = {fps}
repetitions = {reps}
total_mass = 70.0
tolerance_pct = 1.0       # refuse a stimulus whose measured error misses the nominal by more

[session]
replay = false
break_every = 40

"""


def _clips(*names: str) -> str:
    return "".join(f'[[clips]]\nname = "{n}"\nsource = "{n}"\n\n' for n in names) + \
        f"[reference]\nclips = {list(names)!r}\n\n".replace("'", '"')


def _group(name: str, kind: str, sign: int, levels, **opts) -> str:
    extra = "".join(f'{k} = "{v}"\n' for k, v in opts.items())
    return (f'[[groups]]\nname = "{name}"\nkind = "{kind}"\n{extra}sign = {sign}\n'
            f"levels = {list(levels)!r}\n\n")


REITSMA_POLLARD_2003 = """\
# Reitsma & Pollard 2003, "Perceptual metrics for character animation: sensitivity to
# errors in ballistic motion" (SIGGRAPH 2003): errors added to the ballistic phase of
# human jumps in horizontal and vertical velocity, and added accelerations and
# decelerations; they found horizontal errors easier to detect than vertical ones and
# accelerations easier than decelerations.
#
# Assumed here (the text used for this preset does not give them):
# - the clips: their captured jumps are not distributed; the built-in standing jump
#   (2.36 m/s up, 0.1 m/s forward) and front flip (0.7 m/s forward) stand in.  A
#   velocity level is a percentage of the clip's own component, so horizontal levels
#   are small in m/s on the jump (the manifest's nominal_value gives them in m/s);
# - velocity errors change the take-off velocity at the take-off instant (flipstudy
#   changes the COM velocity only at a contact), gravity stays, and the rotation is
#   retimed to the new flight time (a vertical change also changes |L|, measured);
# - accelerations are constant over the whole flight, in percent of 9.81 m/s²,
#   "horizontal" along the travel, "vertical" positive upwards;
# - the levels (0-40 % for velocities, 0-30 % of g for accelerations) and two
#   presentations of each motion; every group has its own original.
""" + _HEAD.format(name="reitsma-pollard-2003", seed=20030727, fps=120, reps=2) + \
    _clips("jump", "frontflip") + "".join(
        _group(f"{axis[0]}-velocity-{'increase' if s > 0 else 'decrease'}", f"{axis}-velocity", s,
               [0, 10, 20, 30, 40]) for axis in ("horizontal", "vertical") for s in (1, -1)) + "".join(
        _group(f"{axis[0]}-{'acceleration' if s > 0 else 'deceleration'}", "acceleration", s,
               [0, 5, 10, 20, 30], axis=axis) for axis in ("horizontal", "vertical") for s in (1, -1))

REITSMA_ANDREWS_POLLARD_2008 = """\
# Reitsma, Andrews & Pollard 2008, "Effect of character animacy and preparatory motion on
# perceptual magnitude of errors in ballistic motion" (Eurographics 2008): the errors of
# Reitsma & Pollard 2003 on three characters, from a human-like one to an abstract one;
# sensitivity followed error type and size alike on all three, and was higher for some
# error types on the most human-like character.
#
# Assumed here:
# - the characters: flipstudy's styles "mannequin" (human-like), "stick" and
#   "point-light" (the most abstract it draws) stand in for the paper's three; each
#   group has its own original, drawn in its style;
# - the errors: an increase of horizontal and of vertical take-off velocity and an added
#   horizontal acceleration and deceleration (as in the reitsma-pollard-2003 preset),
#   on the built-in jump, levels 0-40 % (accelerations 0-30 % of 9.81 m/s²);
# - not built: the paper's second experiment without the preparatory motion (the
#   ballistic phase alone); flipstudy's stimuli always show the whole clip.
""" + _HEAD.format(name="reitsma-andrews-pollard-2008", seed=20080414, fps=120, reps=2) + \
    _clips("jump") + "".join(
        _group(f"{name}-{style}", kind, sign, levels, **opts, style=style)
        for style in ("mannequin", "stick", "point-light")
        for name, kind, sign, levels, opts in (
            ("h-velocity", "horizontal-velocity", 1, [0, 10, 20, 30, 40], {}),
            ("v-velocity", "vertical-velocity", 1, [0, 10, 20, 30, 40], {}),
            ("h-acceleration", "acceleration", 1, [0, 5, 10, 20, 30], {"axis": "horizontal"}),
            ("h-deceleration", "acceleration", -1, [0, 5, 10, 20, 30], {"axis": "horizontal"})))

GRAVITY = """\
# Gravity in the air (McManus et al. 2011; La Scaleia et al. 2020): the same motions
# under a lower or higher gravity; lower gravity was detected slightly more easily,
# and Earth's was judged the most natural.
#
# Assumed here:
# - the policy: "takeoff-velocity", the same push under another gravity (flight time,
#   apex and landing distance follow; |L| is retimed to the new flight time and
#   measured).  "apex-height" is the other common construction (the same path played
#   faster or slower, as slowing a video does: it is time-scale by sqrt(1 + e)), and
#   "flight-time" keeps |L|, the flight time and the landing point;
# - the clips (the built-in jump and back flip stand in for the studies' jumpers),
#   the levels (0-50 % either way: 0.5 g to 1.5 g) and two presentations.
""" + _HEAD.format(name="gravity", seed=20110801, fps=120, reps=2) + _clips("jump", "backflip") + \
    _group("lower-gravity", "gravity", -1, [0, 10, 20, 35, 50], policy="takeoff-velocity") + \
    _group("higher-gravity", "gravity", 1, [0, 10, 20, 35, 50], policy="takeoff-velocity")

TIME_SCALE = """\
# Time scale: the flight alone, or the whole clip, played slower or faster.  Over the
# flight a speed k is gravity k² with the path in space unchanged (apex, landing point
# and take-off angle stay; |L| and every velocity scale by k); the whole clip also
# speeds up or slows down the preparation and the landing.
#
# Assumed here: the clips (built-in back flip and jump), the levels (0-40 %) and two
# presentations; every group has its own original.
""" + _HEAD.format(name="time-scale", seed=20240101, fps=120, reps=2) + _clips("backflip", "jump") + \
    "".join(_group(f"{span}-{'faster' if s > 0 else 'slower'}", "time-scale", s, [0, 10, 20, 30, 40],
                   span=span) for span in ("flight", "whole") for s in (1, -1))

POSE_RATE = """\
# Pose update rate (McDonnell, Newell & O'Sullivan 2007, "Smooth movers"): the
# character's pose is updated N times a second while the video runs at the display
# rate; each pose is held for 1/N s.  Levels are poses per second (0 = the original,
# a new pose on every frame).
#
# Assumed here:
# - the display rate: fps = 60 (the default video rate of `flipstudy render`), so the
#   original updates 60 poses per second and every held pose lasts whole frames when
#   N divides 60;
# - the clips (built-in back flip and jump), the levels (10, 15, 20 and 30 poses per
#   second) and two presentations.
""" + _HEAD.format(name="pose-rate", seed=20070801, fps=60, reps=2) + _clips("backflip", "jump") + \
    _group("pose-rate", "pose-rate", 1, [0, 10, 15, 20, 30])

#: preset name → design text (the first is the default of ``flipstudy init``)
PRESETS = {"flipping-with-physics-2007": PAPER_DESIGN,
           "reitsma-pollard-2003": REITSMA_POLLARD_2003,
           "reitsma-andrews-pollard-2008": REITSMA_ANDREWS_POLLARD_2008,
           "gravity": GRAVITY,
           "time-scale": TIME_SCALE,
           "pose-rate": POSE_RATE}

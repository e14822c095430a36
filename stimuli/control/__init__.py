"""The energy-based jump controller of Ooi 2016 (Chapters 3 and 5): standing
jumps to a target generated from physical parameters, written as clips.

>>> from flipstudy.stimuli.control import jump
>>> res = jump((0, 0, 1.3), fps=30)          # 1.3 m forward, a clip at 30 fps
>>> res.report.landing_error_m < 0.05       # the typed report: what was planned and measured
True

Modules: :mod:`.path` (3.5.1 path estimation), :mod:`.muscles` (3.2.3 spring
muscles, Table 5.1 presets), :mod:`.ik` (3.4 CCD), :mod:`.balance` (3.3),
:mod:`.samples` (3.6 the sample field), :mod:`.uneven` (uneven legs: pelvis
roll, balance target), :mod:`.windup` (3.6 choice, PD approach),
:mod:`.assignment` (3.6.2 energy assignment), :mod:`.course` (the courses of
Chapter 5's scenes: start, target, boxes), :mod:`.planning` (the fixed point
that makes the stages meet), :mod:`.stages` (the frames: stand, windup,
thrust, flight, landing), :mod:`.checks` (ray casts, collisions, the landing
point), :mod:`.controller` (:func:`jump`, its result and report).
"""
from flipstudy._lazy import attach

# each public name and the module it is defined in, imported on first use (the
# controller needs scipy; the CLI's parser reads PRESETS, COURSES, STRENGTH only)
attach(__name__, {".controller": ["JumpReport", "JumpResult", "jump"],
                  ".course": ["COURSES", "Box", "Course", "make_course"],
                  ".planning": ["plan"], ".model": ["Jumper"],
                  ".muscles": ["STRENGTH", "MUSCLES", "PRESETS", "parse_k", "spring_displacement",
                               "spring_energy", "spring_force"],
                  ".path": ["JumpPath", "estimate_path", "kinetic_energy"],
                  ".assignment": ["assign_energy"], ".windup": ["choose"], ".samples": ["sample_field"]})


__all__ = ["COURSES", "STRENGTH", "Box", "Course", "JumpReport", "JumpResult", "jump", "make_course", "plan",
           "Jumper", "MUSCLES", "PRESETS", "parse_k", "spring_displacement", "spring_energy", "spring_force",
           "JumpPath", "estimate_path", "kinetic_energy", "assign_energy", "choose", "sample_field"]

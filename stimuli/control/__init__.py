"""The energy-based jump controller of Ooi 2016 (Chapters 3 and 5): standing
jumps to a target generated from physical parameters, written as clips.

>>> from flipstudy.stimuli.control import jump
>>> res = jump((0, 0, 1.3), fps=30)          # 1.3 m forward, a clip at 30 fps
>>> res.clip.meta["landing_error_m"] < 0.05
True

Modules: :mod:`.path` (3.5.1 path estimation), :mod:`.muscles` (3.2.3 spring
muscles, Table 5.1 presets), :mod:`.ik` (3.4 CCD), :mod:`.balance` (3.3),
:mod:`.windup` (3.6 sample field, choice, PD approach, energy assignment),
:mod:`.controller` (thrust, flight, landing, scenes).
"""
from .controller import SCENES, STRENGTH, Box, JumpResult, Scene, jump, make_scene, plan
from .model import Jumper
from .muscles import MUSCLES, PRESETS, parse_k, spring_displacement, spring_energy, spring_force
from .path import JumpPath, estimate_path, kinetic_energy
from .windup import assign_energy, choose, sample_field

__all__ = ["SCENES", "STRENGTH", "Box", "JumpResult", "Scene", "jump", "make_scene", "plan", "Jumper",
           "MUSCLES", "PRESETS", "parse_k", "spring_displacement", "spring_energy", "spring_force",
           "JumpPath", "estimate_path", "kinetic_energy", "assign_energy", "choose", "sample_field"]

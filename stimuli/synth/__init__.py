"""Built-in, physically exact synthetic clips: the embedded default.

>>> from flipstudy.stimuli.synth import builtin, make_skeleton, BUILTIN_NAMES
>>> clip = builtin("backflip")            # 120 fps, 70 kg, 1.75 m
>>> clip.meta["takeoff"] < clip.meta["landing"]
True

See :func:`builtin` for the motions and their parameters, :mod:`.clips` for how
they are constructed and :mod:`.planar` for the sagittal kinematics.
"""
from __future__ import annotations

from ..motion.clip import Clip
from flipstudy.errors import SynthError
from .clips import BUILTIN_NAMES, DESIGNS, PARAMS, build
from .skeleton import make_skeleton


def builtin(name: str, fps: float = 120, total_mass: float = 70.0,
            segment_masses: dict | None = None, **params) -> Clip:
    """A built-in synthetic clip whose flight is physically exact.

    ``name`` is one of :data:`BUILTIN_NAMES`:

    ``"backflip"``   standing backward tucked somersault (one turn backward)
    ``"frontflip"``  standing forward tucked somersault (one turn forward)
    ``"jump"``       standing vertical jump with a slight forward drift

    Each clip stands, crouches (a counter-movement), pushes off, flies, lands,
    absorbs the landing and stands up again (3.1–3.3 s) at ``fps`` frames per
    second (default 120), for a body of ``total_mass`` kg (default 70) whose
    segments are those of ``Body.from_skeleton(clip.skeleton, total_mass)``;
    the skeleton is :func:`make_skeleton` (1.75 m, facing +Z, left at +X, Y up,
    floor y = 0).

    Physics.  In flight the whole-body COM follows the parabola of g = 9.81 m/s²
    exactly, and the angular momentum about the COM is conserved (along X, the
    lateral axis): the root pitch is integrated from that conservation on a grid
    16× finer than the frames, so tucking in speeds the rotation up and opening
    out slows it down.  Take-off is smooth: COM position, velocity and
    acceleration, every joint angle, rate and acceleration, hence L, are
    continuous (the ground force fades to zero as the foot unrolls).  Touch-down
    is an impact: the feet stop (leg joint rates jump) while the COM keeps its
    velocity and then decelerates.  On the ground the toes never move; the heel
    rises about the ball of the foot just before take-off; nothing goes below
    the floor.  Deterministic: the same arguments give the same clip.

    Sign convention.  Rotations are about +X (the body's left); a positive
    pitch tips the head forward (+Z).  A *backward* rotation (the head going
    toward −Z while facing +Z) is negative: the backflip's root pitch goes from
    0 to −360° (L_x < 0), the frontflip's from 0 to +360° (L_x > 0), the jump's
    back to 0.

    Parameters
    ----------
    name : str
        One of :data:`BUILTIN_NAMES`; the others are keywords, optional, with defaults
        per clip.
    fps : frames per second (>= 10).  Take-off and touch-down fall on frames,
        so ``flight_time`` is rounded to whole frames.
    total_mass : kg.
    segment_masses : segment or group name → kg, for a body that is not the de Leva
        table's (the rest keep their table share of ``total_mass``; the total is then
        their sum).  The flight is exact for that body: what a mass estimate must
        recover.  ``meta["segment_masses"]`` records the masses used.
    height : standing height in metres (1.75); all lengths scale with it.
    flight_time : seconds from take-off to touch-down (0.68 flips, 0.50 jump);
        the take-off speed follows from it (COM rise ≈ 0.54 m for the flips).
    shape : the body shape in flight: ``"tuck"`` (default), ``"pike"`` (hips folded,
        knees straight) or ``"layout"`` (body straight, the same as tuck = 0); the
        angular momentum needed for the same turn grows from tuck to layout.
    tuck : 0 (layout, body straight) … 1 (full tuck; the flips' default; 0.3
        for the jump, a slight knee bend).  A shallower tuck needs more angular
        momentum for the same rotation (below ~0.7 the take-off rotation of a
        standing flip becomes unrealistically fast).
    horizontal_speed : take-off COM velocity along +Z in m/s (backflip −0.45,
        frontflip +0.70, jump +0.10).
    crouch_depth : how far the pelvis drops in the counter-movement, metres for
        a 1.75 m body (0.40 flips, 0.32 jump).
    turns : somersaults of the flips, a whole number 1–3 (1); use a longer
        ``flight_time`` for more.

    ``clip.meta`` holds ``name``, ``source`` (``"builtin"``), ``takeoff`` (first
    flight frame: the instant the ground force reaches zero, toes still
    touching), ``landing`` (last flight frame, feet above the floor),
    ``touchdown`` (``landing + 1``: feet on the floor, the impact), ``flight_s``
    (take-off to touch-down, seconds), ``L_flight`` (the conserved angular
    momentum about the COM, kg·m²/s, world axes), ``v0`` (take-off COM
    velocity, m/s), ``g``, ``total_mass``, ``height``, ``heel_off`` (first
    frame of the heel rise), ``params`` and diagnostics
    (``takeoff_pitch_rate``, ``max_pitch_rate``, ``landing_pitch_rate`` in
    rad/s, ``com_rise_m``, ``push_rise_m``, ``rotation_deg``,
    ``flight_rotation_deg``).  They are provenance: what the clip was built
    with and to, exact by construction (the tests use them as ground truth); a
    clip made from it by an edit keeps them as its source's, beside its own
    ``edit``.  Nothing measured or transient is kept (time the call to know
    how long a build takes).

    Raises ``ValueError`` for an unknown name or parameter (listing the valid
    ones) or a value out of range, and :class:`SynthError` (a ``ValueError``)
    for parameters with no consistent motion.

    Examples
    --------
    >>> clip = builtin("frontflip", fps=60, tuck=0.8)
    >>> clip.meta["L_flight"][0] > 0          # forward rotation
    True
    """
    return build(name, fps=fps, total_mass=total_mass, segment_masses=segment_masses, **params)


__all__ = ["BUILTIN_NAMES", "PARAMS", "DESIGNS", "SynthError", "builtin", "make_skeleton"]

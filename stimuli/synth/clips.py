"""Construction of the built-in, physically exact clips (see :func:`builtin`).

The motion is sagittal and left/right symmetric (rotations about X only, see
:mod:`flipstudy.stimuli.synth.planar`).  Phases (times for the defaults, 120 fps):

1. **stand, crouch** (0–1.06 s).  Joint angles are quintics in the DOFs of
   :mod:`.planar`, feet flat.  The crouch is placed by analytic two-bone leg IK
   with the centre of mass over the same point of the feet as when standing;
   it is reached at rest but already pushed upward (COM acceleration
   ``a_bottom``: a counter-movement).
2. **push** (to 1.30 s).  The COM follows a degree-7 piece matching position,
   velocity, acceleration and jerk at both ends: from the crouch to the
   flight's initial position, velocity ``v0`` and acceleration −g with zero
   jerk (the ground force fades to zero tangentially as the foot unrolls).
   Pitch, spine, neck and arms are quintics; the heel rises about the ball of
   the foot (foot pitch ``heel0 τ³``); the shank and thigh pitches are solved
   frame by frame (vectorised Newton) so that the body's COM is on that curve.
3. **flight** (0.68 s for the flips).  Joint angles are quintics take-off →
   tuck → hold → landing pose.  The root pitch rate follows from conservation
   of the angular momentum about the COM, Ω(t) = (L − h(t)) / I(t), with I the
   whole-body inertia about the lateral axis and h the angular momentum of the
   joint motion relative to the root, both exact (analytic rates) on a grid 16×
   finer than the frames; L = (Δθ + ∫h/I dt) / ∫1/I dt makes the flight rotate
   by exactly Δθ, and the pitch is the cumulative Simpson integral of Ω.  The
   root position is the ballistic COM parabola minus the COM offset of the pose
   (forward kinematics + :class:`flipstudy.stimuli.body.Body`, as
   :func:`flipstudy.stimuli.physics.center_of_mass` computes it), so the COM is an exact
   parabola.
4. **touch-down, absorb**.  The feet arrive flat on the floor and stop there
   (the impact: the leg joint rates jump).  The COM keeps its velocity and
   decelerates to rest along c(τ) = c_L + v_L T_a/3 · (1 − (1 − τ)³) (the
   largest ground force at impact, fading to body weight); pitch and upper body
   keep their rates and ease into the absorbed pose; the legs are solved for
   the COM again.
5. **recover, hold**.  Quintics from the absorbed crouch up to the rest pose,
   at the same facing after the whole number of somersaults.

Take-off continuity: at the take-off instant the ball of the foot is pinned and
the ground force is zero, so the shank and thigh rates and accelerations follow
from the COM velocity ``v0`` and acceleration −g (:func:`.poses.contact_rates`, two
2×2 systems).  The flight's angular momentum depends on them, and the push's
pitch rate and acceleration must equal the flight's Ω(0) and Ω̇(0): that fixed
point is solved by a chord-Newton iteration.  Everything (COM, every joint
angle, rate and acceleration, hence L) is continuous across take-off.

Feet: in every ground frame the root position is the pinned ball of the foot
minus the chain's forward kinematics, so the toes never move (to rounding);
the ankle rises only while the heel does, before take-off.

Modules: :mod:`.designs` (the motions' key poses, timings and parameters),
:mod:`.poses` (the key poses, legs solved for the COM, the take-off rates),
:mod:`.phases` (flight, ground before and after), :mod:`.planar` (the
sagittal kinematics); :func:`build` here puts them together.
"""

from __future__ import annotations

import numpy as np

from ..body import Body
from ..motion.clip import Clip
from ..physics import center_of_mass
from flipstudy.errors import SynthError
from .designs import BUILTIN_NAMES, DESIGNS, PARAMS, REF_HEIGHT, SUBSTEPS, G, check_params
from .phases import ground_after, ground_before, solve_flight
from .planar import D, IX, PlanarModel
from .poses import com_from_ball, crouch_pose, landing_pose, takeoff_pose
from .skeleton import make_skeleton


def build(name: str, fps: float = 120.0, total_mass: float = 70.0,
          segment_masses: dict | None = None, **params) -> Clip:
    """See :func:`flipstudy.stimuli.synth.builtin`."""
    d, H = check_params(name, fps, total_mass, params)
    turns = d["turns"]
    scale = H / REF_HEIGHT
    fps = float(fps)
    sk = make_skeleton(H)
    body = Body.from_skeleton(sk, total_mass, segment_masses=segment_masses)
    if segment_masses:
        total_mass = body.total_mass              # the sum, when segment masses are given
    model = PlanarModel(sk, body)

    # take-off and touch-down on the frame grid: the flight lasts whole frames
    snap = lambda x: max(1, int(round(x * fps)))  # noqa: E731
    i_to = snap(d["t_takeoff"])
    n_flight = snap(d["flight_time"])
    i_td = i_to + n_flight
    T = n_flight / fps
    t_to, t_td = i_to / fps, i_td / fps

    # key poses and the ballistic path
    q0 = takeoff_pose(model, d, H)
    qL = landing_pose(d)
    q_crouch = crouch_pose(model, d["crouch"]["pitch"], d["crouch_depth"] * scale,
                            {k: v for k, v in d["crouch"].items() if k != "pitch"})
    rel0, relL = com_from_ball(model, q0), com_from_ball(model, qL)
    v0 = np.array([0.0, (relL[1] - rel0[1] + 0.5 * G * T ** 2) / T, float(d["horizontal_speed"])])
    vL = v0 - np.array([0.0, G * T, 0.0])
    dtheta = (qL[IX["pitch"]] + 2 * np.pi * turns) - q0[IX["pitch"]]

    fl = solve_flight(name, model, d, q0, qL, v0, T, n_flight, dtheta)
    heel_dur = 3.0 * d["heel"] / d["heel_rate"]
    if heel_dur >= t_to - d["t_crouch"]:
        raise SynthError(f"builtin({name!r}): the heel rise ({heel_dur:.2f} s) does not fit in the push")

    # ground before take-off (the left ball of the foot at its rest position)
    ball_rest = model.ball_pos(np.zeros((1, D)))[0]
    B = np.array([ball_rest[0], 0.0, ball_rest[2]])
    tp = np.arange(0, i_to) / fps
    Q_pre, push_rise = ground_before(model, d, tp, q_crouch, q0, fl["qd0"], fl["qdd0"], rel0, v0,
                                      t_to, heel_dur)
    root_pre = B[None] - model.ball_pos(Q_pre)

    # flight: the pitch from L, the root from the parabola and the body's COM
    tf = np.arange(0, n_flight + 1) / fps
    Q_fl = fl["spline"](tf)
    Q_fl[:, IX["pitch"]] = q0[IX["pitch"]] + fl["theta"][::SUBSTEPS // 2]
    c0 = B + rel0
    parab = c0[None] + v0[None] * tf[:, None] - 0.5 * G * np.outer(tf ** 2, [0.0, 1.0, 0.0])
    rel_clip = Clip(sk, fps, np.zeros((len(tf), 3)), model.quaternions(Q_fl))
    root_fl = parab - center_of_mass(rel_clip, body)
    ball_td = root_fl[-1] + model.ball_pos(Q_fl[-1][None])[0]
    B_td = np.array([ball_td[0], 0.0, ball_td[2]])

    # ground after touch-down
    qd_td = fl["spline"](T, 1)[0]
    qd_td[IX["pitch"]] = fl["Om"][-1]
    Q_post = ground_after(model, d, fps, scale, turns, i_td, t_td, qL, qd_td, relL, vL)
    root_post = B_td[None] - model.ball_pos(Q_post)

    Q = np.concatenate([Q_pre, Q_fl, Q_post])
    root = np.concatenate([root_pre, root_fl, root_post])
    meta = {
        "name": name, "source": "builtin",
        "takeoff": int(i_to), "landing": int(i_td - 1), "touchdown": int(i_td),
        "flight_s": float(T),
        "L_flight": [float(fl["L"]), 0.0, 0.0], "v0": [float(v) for v in v0], "g": G,
        "total_mass": float(total_mass), "height": H,
        "segment_masses": body.segment_masses(),
        "rotation_deg": float(np.degrees(2 * np.pi * turns)),
        "flight_rotation_deg": float(np.degrees(dtheta)),
        "takeoff_pitch_rate": float(fl["Om"][0]), "landing_pitch_rate": float(fl["Om"][-1]),
        "max_pitch_rate": float(np.abs(fl["Om"]).max()),
        "com_rise_m": float(v0[1] ** 2 / (2 * G)), "push_rise_m": push_rise,
        "heel_off": int(np.floor((t_to - heel_dur) * fps)) + 1,
        "params": {"height": H, "flight_time": float(T), "tuck": float(d["tuck"]),
                   "horizontal_speed": float(d["horizontal_speed"]),
                   "crouch_depth": float(d["crouch_depth"]), "turns": int(abs(turns))},
        "warnings": [],
    }
    return Clip(sk, fps, root, model.quaternions(Q), meta=meta)


__all__ = ["BUILTIN_NAMES", "DESIGNS", "PARAMS", "SynthError", "build"]

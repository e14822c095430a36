"""Centre of mass, linear and angular momentum of a clip's body.

All functions are vectorised over frames and body pieces (no per-frame loops).
Angular momentum about the whole-body COM:

    L(t) = Σ_i R_i I_i R_iᵀ ω_i + m_i (c_i − c) × (v_i − v_c)

(the paper's printed formula, Section 4.3, drops the ω_i of the first term;
ours keeps it).  The root's velocity is a central finite difference and each
joint frame's ω a central difference on the rotation group, both consistent
with ``clip.fps``; piece velocities are propagated along the chain
(v_joint + ω × r), so a ballistic parabola and a constant spin are
differentiated exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .body import Body
from .motion.clip import Clip


def piece_positions(clip: Clip, body: Body) -> np.ndarray:
    """(F,P,3) world COM of every body piece."""
    return clip.points(body.joint, body.com)


def center_of_mass(clip: Clip, body: Body) -> np.ndarray:
    """(F,3) whole-body centre of mass in metres."""
    c = piece_positions(clip, body)
    return np.einsum("fpa,p->fa", c, body.mass) / body.mass.sum()


@dataclass
class Momentum:
    """Per-frame mass properties of a clip: COM (F,3), its velocity (F,3), linear
    momentum p (F,3), angular momentum about the COM L (F,3) and the whole-body
    inertia about the COM in world axes I (F,3,3)."""

    com: np.ndarray
    v_com: np.ndarray
    p: np.ndarray
    L: np.ndarray
    inertia: np.ndarray


def momentum(clip: Clip, body: Body, breaks=()) -> Momentum:
    """COM, linear momentum and angular momentum about the COM for every frame.

    ``breaks``: frames where a new phase starts (a flight's first and the frame
    after its last frame strictly inside): velocities are then differenced
    within each phase only (one-sided at its ends), so no stencil reaches across
    a contact.  A break leaving a phase of one frame is ignored.

    Examples
    --------
    >>> from flipstudy.stimuli import builtin
    >>> from flipstudy.stimuli.body import Body
    >>> clip = builtin("backflip")
    >>> m = momentum(clip, Body.from_skeleton(clip.skeleton))
    >>> m.L.shape == (clip.num_frames, 3)
    True
    """
    F = clip.num_frames
    cuts = sorted({int(b) for b in breaks if 0 < int(b) < F})
    edges, last = [0], 0
    for b in cuts:
        if b - last >= 2 and F - b >= 2:
            edges.append(b)
            last = b
    if len(edges) > 1:
        edges.append(F)
        parts = [momentum(clip.slice(a, b), body) for a, b in zip(edges[:-1], edges[1:])]
        return Momentum(*(np.concatenate([getattr(p, k) for p in parts])
                          for k in ("com", "v_com", "p", "L", "inertia")))
    R = clip.joint_rotations()[:, body.joint]                 # (F,P,3,3)
    omega = clip.angular_velocities()[:, body.joint]           # (F,P,3)
    c = piece_positions(clip, body)                            # (F,P,3)
    v = clip.point_velocities(body.joint, body.com)            # rigid-body propagation
    m = body.mass
    M = m.sum()
    com = np.einsum("fpa,p->fa", c, m) / M
    v_com = np.einsum("fpa,p->fa", v, m) / M
    Iw = R @ body.inertia[None] @ np.swapaxes(R, -1, -2)       # (F,P,3,3)
    spin = np.einsum("fpab,fpb->fa", Iw, omega)
    r = c - com[:, None]
    orbital = np.einsum("p,fpa->fa", m, np.cross(r, v - v_com[:, None]))
    # whole-body inertia about the COM (parallel-axis theorem), world axes
    rr = np.einsum("fpa,fpb->fpab", r, r)
    r2 = np.einsum("fpa,fpa->fp", r, r)
    I_tot = Iw.sum(1) + np.einsum("p,fpab->fab", m, r2[..., None, None] * np.eye(3) - rr)
    return Momentum(com=com, v_com=v_com, p=M * v_com, L=spin + orbital, inertia=I_tot)


def angular_momentum(clip: Clip, body: Body) -> np.ndarray:
    """(F,3) angular momentum about the COM, kg·m²/s."""
    return momentum(clip, body).L


def linear_momentum(clip: Clip, body: Body) -> np.ndarray:
    """(F,3) linear momentum, kg·m/s."""
    return momentum(clip, body).p

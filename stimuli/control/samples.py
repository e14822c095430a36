"""The sample field of the windup (Ooi 2016, 3.6): every crouch the jumper can
hold, computed once.

**Sample field.**  Pelvis positions on a regular grid over the balanced region
— above the support polygon's bounding rectangle, from low down up to the
standing pelvis height — each with both legs solved by CCD (feet flat where
they stand), its six spring displacements, its COM (the project's de Leva
body, upper body upright) and the balance error.  Equal legs crouch with the
pelvis level; uneven legs (Table 5.1's uneven trials) with the pelvis rolled
down on the stronger side, each leg's compression following its own spring up
to 8° of pelvic obliquity (which crouches deeper than ~6 cm reach), so that
the stronger leg bends more (:func:`.uneven.pelvis_roll` gives the physics).  The
geometry depends on k only
through that roll (the legs' asymmetry): the field is computed once per jumper
(height, mass), grid and asymmetry and cached; the energies E_el = Σ ½ k_i s_i²
are computed once per k and cached on the field.

The field is an array of samples, not a loop over them: :func:`sample_field_naive`
is the per-sample loop it replaced, kept as the baseline of ``benchmarks/bench_jump.py``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .balance import balance_error, inside, lean_limits, polygon_centre, support_polygon
from .ik import solve_legs
from .model import SIDES, Jumper
from .muscles import spring_displacement
from .uneven import balance_target, hip_compression, leg_asymmetry, pelvis_roll

SPACING = (0.02, 0.01, 0.02)   # grid of the field (x, y, z), metres
LOWEST_PELVIS = 0.35           # fraction of the standing pelvis height


@dataclass
class Balanced:
    """The field balanced for one set of spring constants: per sample the
    balance target (N,2) (the centre of pressure of the legs' springs, over
    the stronger leg, see :func:`.uneven.balance_target`), the upright error from it
    (N,2), the best lean within limits (N,2), the COM with it (N,3), the error
    left (N,2) and whether that COM is over the support polygon (2 cm inside)."""

    target: np.ndarray
    balance: np.ndarray
    lean: np.ndarray
    com_bal: np.ndarray
    residual: np.ndarray
    inside: np.ndarray


@dataclass
class SampleField:
    """Pelvis samples relative to the feet (their midpoint on the surface at the
    origin, standing stance).  Arrays (N,...)."""

    jumper: Jumper
    pelvis: np.ndarray      # (N,3)
    ok: np.ndarray          # (N,) legs reach, within joint limits
    s: np.ndarray           # (N,6) spring displacements, m (order of MUSCLES)
    theta: np.ndarray       # (N,6) effective angles between the bones, rad
    com: np.ndarray         # (N,3) COM, upper body upright
    balance: np.ndarray     # (N,2) COM − support-polygon centre (x, z), upper body upright
    polygon: np.ndarray     # (K,2)
    centre: np.ndarray      # (2,)
    spacing: tuple
    lean_table: tuple       # (leans (L,2), COM shifts (L,3)): the upper body's effect
    roll: np.ndarray | None = None        # (N,) pelvis roll, rad (see :func:`pelvis_roll`)
    compression: np.ndarray | None = None  # (N,2) each hip's drop below standing (left, right), m
    asymmetry: float = 0.0                # the legs' c of :func:`leg_asymmetry` the field is for
    seconds: float = 0.0
    _energy: dict = field(default_factory=dict, repr=False)
    _balanced: dict = field(default_factory=dict, repr=False)

    @property
    def size(self) -> int:
        return self.pelvis.shape[0]

    def energy(self, k) -> np.ndarray:
        """(N,) elastic energy Σ ½ k_i s_i² (J) for spring constants k (6,);
        computed once per k."""
        key = _key(k)
        if key not in self._energy:
            self._energy[key] = 0.5 * (self.s ** 2) @ np.asarray(key)
        return self._energy[key]

    def balanced(self, k) -> Balanced:
        """The balance of every sample for spring constants k (computed once per k)."""
        key = _key(k)
        if key not in self._balanced:
            target = balance_target(self.jumper, np.asarray(key), compression=self.compression)
            target = np.broadcast_to(target, (self.size, 2))
            b = self.com[:, [0, 2]] - target
            L, D = self.lean_table
            best = np.empty(b.shape[0], int)
            for a in range(0, b.shape[0], 2048):
                r = b[a:a + 2048, None, :] + D[None, :, [0, 2]]
                cost = np.einsum("nlc,nlc->nl", r, r) + 1e-8 * np.einsum("lc,lc->l", L, L)[None]
                best[a:a + 2048] = np.argmin(cost, axis=1)
            com_bal = self.com + D[best]
            self._balanced[key] = Balanced(target, b, L[best], com_bal, com_bal[:, [0, 2]] - target,
                                           inside(self.polygon, com_bal[:, [0, 2]], margin=0.02))
        return self._balanced[key]

    def max_energy(self, k) -> float:
        E = self.energy(k)
        m = self.ok & self.balanced(k).inside
        return float(E[m].max()) if m.any() else 0.0


def _key(k) -> tuple:
    return tuple(float(v) for v in np.asarray(k, float).reshape(6))


_CACHE: dict = {}


def sample_field(jumper: Jumper, spacing=SPACING, k=None) -> SampleField:
    """The sample field of a jumper (cached per height, mass and spacing, and
    per the legs' asymmetry of ``k``: uneven legs crouch with the pelvis
    rolled, :func:`.uneven.pelvis_roll`; equal legs or no ``k``: upright).

    Parameters
    ----------
    jumper : Jumper
    spacing : tuple of 3 float
        The grid (x, y, z), metres.
    k : sequence of 6 float, optional

    Returns
    -------
    SampleField

    Examples
    --------
    >>> f = sample_field(Jumper(), spacing=(0.03, 0.03, 0.03))
    >>> f.pelvis.shape[1], bool(f.ok.any()), sample_field(Jumper(), spacing=(0.03, 0.03, 0.03)) is f
    (3, True, True)
    """
    c = 0.0 if k is None else round(leg_asymmetry(k), 9)
    key = (round(jumper.height, 9), round(jumper.mass, 9), tuple(spacing)) + ((c,) if c else ())
    if key in _CACHE:
        return _CACHE[key]
    t0 = time.perf_counter()
    feet = jumper.feet()
    corners = np.concatenate([jumper.foot_corners(feet[s]) for s in SIDES])
    poly = support_polygon(corners)
    lo, hi = corners.min(0), corners.max(0)
    dx, dy, dz = spacing
    xs = _axis(lo[0], hi[0], dx)
    zs = _axis(lo[2], hi[2], dz)
    ys = np.arange(jumper.standing_pelvis, LOWEST_PELVIS * jumper.standing_pelvis - 1e-9, -dy)[::-1]
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    P = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    depth = jumper.standing_pelvis - P[:, 1]
    roll = pelvis_roll(jumper, c, depth)
    st = solve_legs(jumper, P, jumper.rest_quats(P.shape[0]), feet, roll=roll)
    pos = jumper.positions(P, st.quats)
    theta = jumper.muscle_angles(pos)
    com = jumper.com(P, st.quats)
    centre = polygon_centre(poly)
    f = SampleField(jumper, P, st.ok, spring_displacement(theta), theta, com,
                    balance_error(com, centre), poly, centre, tuple(spacing), _lean_table(jumper),
                    roll, depth[:, None] + hip_compression(jumper, roll), c)
    f.seconds = time.perf_counter() - t0
    _CACHE[key] = f
    return f


def _lean_table(jumper: Jumper, step: float = np.radians(2.0)):
    """Leans on a grid within the limits and the COM shift each causes.  The
    upper body hangs from the pelvis, so the shift of a lean is the same for
    every leg pose: one table, one FK batch."""
    lo, hi = lean_limits()
    gx = np.arange(lo[0], hi[0] + 1e-9, step)
    gz = np.arange(lo[1], hi[1] + 1e-9, step)
    L = np.stack(np.meshgrid(gx, gz, indexing="ij"), -1).reshape(-1, 2)
    Q = jumper.rest_quats(L.shape[0])
    lq = jumper.lean_quats(L)
    Q[:, jumper.idx["spine"]] = lq
    Q[:, jumper.idx["spine1"]] = lq
    root = np.zeros((L.shape[0], 3))
    D = jumper.com(root, Q) - jumper.com(root[:1], jumper.rest_quats(1))
    return L, D


def _axis(a: float, b: float, d: float) -> np.ndarray:
    """Samples every ``d`` over [a, b], symmetric about the middle, which is one."""
    half = int(np.floor((b - a) / (2 * d) + 1e-9))
    return 0.5 * (a + b) + d * np.arange(-half, half + 1)


def sample_field_naive(jumper: Jumper, spacing=SPACING, limit: int | None = None) -> dict:
    """The same field one sample at a time (the baseline of the benchmark): a
    Python loop over pelvis positions, CCD, FK and COM per sample, on the first
    ``limit`` samples (all by default).  Returns ``pelvis``, ``ok``, ``s``, ``com``."""
    f = sample_field(jumper, spacing)
    feet = jumper.feet()
    ok, S, C = [], [], []
    P = f.pelvis if limit is None else f.pelvis[:limit]
    for p in P:
        st = solve_legs(jumper, p[None], jumper.rest_quats(1), feet)
        pos = jumper.positions(p[None], st.quats)
        S.append(spring_displacement(jumper.muscle_angles(pos))[0])
        C.append(jumper.com(p[None], st.quats)[0])
        ok.append(bool(st.ok[0]))
    return {"pelvis": P, "ok": np.array(ok), "s": np.array(S), "com": np.array(C)}


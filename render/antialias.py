"""FXAA on the read-back frame, in numpy: the anti-aliasing of ``Style.anti_aliasing = "fxaa"``.

Every frame is read back into a numpy array anyway (:meth:`Scene.grab
<flipstudy.render.scene.Scene.grab>`), so the anti-aliasing runs there instead
of in VTK's FXAA filter, whose full-screen pass on Mesa llvmpipe costs about
twice the rest of the frame (``benchmarks/bench_render_ceiling.py --aa``).
The algorithm is the one VTK's filter runs, Lottes' FXAA 3.11 (the "quality"
form, with VTK's default options, :data:`OPTIONS`): a pixel is an edge when
the luma range of it and its four neighbours exceeds a hard and a relative
threshold; its edge runs along the axis of the smaller luma curvature; the
edge is followed both ways (unit steps, at most ``endpoint_search_iterations``)
to where the luma leaves the edge's; the pixel is blended towards its neighbour
across the edge by its distance to the nearer end (the coverage of a straight
edge through the span), or by the sub-pixel estimate (luma of the 3x3
neighbourhood against the pixel's) when that is larger.  Only the edge
pixels, a few per cent of a stimulus frame, are computed; every other pixel is
returned as it is, as the shader returns it.
"""
from __future__ import annotations

import threading

import numpy as np

#: VTK's ``vtkFXAAOptions`` defaults (the filter the project used before)
OPTIONS = {"relative_contrast_threshold": 1 / 8, "hard_contrast_threshold": 1 / 16,
           "subpixel_blend_limit": 3 / 4, "subpixel_contrast_threshold": 1 / 4,
           "endpoint_search_iterations": 12}

_W8 = np.array([77, 150, 29], np.uint16)        # Rec. 601 luma in 1/256 steps (sums to 256)
_LUMA = np.arange(256, dtype=np.float32) / np.float32(255)   # a luma byte in [0, 1]


def fxaa(img: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The frame ``img`` ((H, W, 3) uint8 RGB) anti-aliased by FXAA 3.11,
    written to ``out`` (may be ``img`` itself; a new array when ``None``) and
    returned.

    >>> img = np.zeros((16, 16, 3), np.uint8)
    >>> img[np.arange(16)[:, None] > np.arange(16)[None, :] // 4] = 255   # a staircase edge
    >>> sm = fxaa(img)
    >>> bool(((sm > 0) & (sm < 255)).any()), np.array_equal(sm[12:, :4], img[12:, :4])
    (True, True)
    """
    H, W = img.shape[:2]
    if out is None:
        out = img.copy()
    elif out is not img:
        np.copyto(out, img)
    if H < 3 or W < 3:
        return out
    R = int(OPTIONS["endpoint_search_iterations"]) + 1
    px = img.reshape(-1, 3) if img.flags.c_contiguous else np.ascontiguousarray(img).reshape(-1, 3)
    Lp, k = _edges(px, H, W, R)
    if not len(k):
        return out
    ys, xs, qy, qx, off = _offsets(Lp, k, W, R)
    # blend towards the neighbour across the edge (a bilinear tap off the pixel centre)
    c0 = px.take(k, axis=0).astype(np.float32)
    c1 = px.take(np.clip(ys + qy, 0, H - 1) * W + np.clip(xs + qx, 0, W - 1), axis=0).astype(np.float32)
    out[ys, xs] = np.rint(c0 + (c1 - c0) * off).astype(np.uint8)
    return out


def _edges(px: np.ndarray, H: int, W: int, R: int) -> tuple[np.ndarray, np.ndarray]:
    """The whole-frame passes of :func:`fxaa`: the luma padded by ``R`` and the edge
    pixels (flat indices in the frame)."""
    o = OPTIONS
    # luma of every pixel in 1/255 (uint8: the whole-frame work stays on bytes), written
    # straight into a frame padded by the longest endpoint search (edge mode) so no index
    # leaves it: Lp[y + R, x + R] is pixel (y, x).  The whole-frame passes are the cost of
    # a frame with few edges: a handful of byte operations, no float copy of the frame.
    # every whole-frame array is a scratch buffer kept for the next frame of the same size:
    # a fresh 300 kB array costs more in page faults than the byte operation filling it
    Lp, acc, tmp, hi, lo, thr_hi, edge = _scratch(H, W, R)
    np.multiply(px[:, 0], _W8[0], out=acc)
    np.multiply(px[:, 1], _W8[1], out=tmp)
    acc += tmp
    np.multiply(px[:, 2], _W8[2], out=tmp)
    acc += tmp
    acc >>= 8
    M = Lp[R:R + H, R:R + W]
    M[...] = acc.reshape(H, W)
    Lp[R:R + H, :R] = M[:, :1]
    Lp[R:R + H, R + W:] = M[:, -1:]
    Lp[:R] = Lp[R]
    Lp[R + H:] = Lp[R + H - 1]
    N, S = Lp[R - 1:R - 1 + H, R:R + W], Lp[R + 1:R + 1 + H, R:R + W]
    Wl, E = Lp[R:R + H, R - 1:R - 1 + W], Lp[R:R + H, R + 1:R + 1 + W]
    np.maximum(N, S, out=hi)
    np.maximum(hi, Wl, out=hi)
    np.maximum(hi, E, out=hi)
    np.maximum(hi, M, out=hi)
    np.minimum(N, S, out=lo)
    np.minimum(lo, Wl, out=lo)
    np.minimum(lo, E, out=lo)
    np.minimum(lo, M, out=lo)
    if o["relative_contrast_threshold"] == 1 / 8:
        np.right_shift(hi, 3, out=thr_hi)
    else:
        thr_hi[...] = hi * o["relative_contrast_threshold"]
    np.maximum(thr_hi, np.uint8(round(255 * o["hard_contrast_threshold"])), out=thr_hi)
    np.subtract(hi, lo, out=hi)
    np.greater_equal(hi, thr_hi, out=edge)
    return Lp, np.flatnonzero(edge)


def _offsets(Lp: np.ndarray, k: np.ndarray, W: int, R: int):
    """Per edge pixel ``k`` (flat in the frame): its row and column, the step to the
    neighbour across the edge (rows, columns) and the blend weight towards it (P, 1)."""
    o = OPTIONS
    Wp = W + 2 * R
    ys = k // W
    xs = k - ys * W
    c = k + ys * (2 * R) + (R * Wp + R)                        # flat index in Lp
    # the luma in [0, 1] only where it is read: the bytes gathered, then a 256-entry table
    Lb = Lp.ravel()

    def lum_at(i):
        return _LUMA.take(Lb.take(i))
    m, n, s, w, e = lum_at(c), lum_at(c - Wp), lum_at(c + Wp), lum_at(c - 1), lum_at(c + 1)
    nw, ne, sw, se = lum_at(c - Wp - 1), lum_at(c - Wp + 1), lum_at(c + Wp - 1), lum_at(c + Wp + 1)
    r = np.maximum(np.maximum(np.maximum(n, s), np.maximum(w, e)), m) - \
        np.minimum(np.minimum(np.minimum(n, s), np.minimum(w, e)), m)
    # sub-pixel aliasing: the 3x3 low-pass against the pixel, over the local range
    ll = (2 * (n + s + w + e) + (nw + ne + sw + se)) / 12
    sub = np.clip(np.abs(ll - m) / np.maximum(r, 1e-6), 0, 1)
    sub_f = np.where(sub >= o["subpixel_contrast_threshold"],
                     ((-2 * sub + 3) * sub * sub) ** 2 * o["subpixel_blend_limit"], 0)
    # the edge's direction: horizontal when the luma curves more across rows than columns
    horz = (np.abs(nw - 2 * w + sw) + 2 * np.abs(n - 2 * m + s) + np.abs(ne - 2 * e + se)) >= \
           (np.abs(nw - 2 * n + ne) + 2 * np.abs(w - 2 * m + e) + np.abs(sw - 2 * s + se))
    a = np.where(horz, n, w)                                   # the two neighbours across the edge
    b = np.where(horz, s, e)
    pair_a = np.abs(a - m) >= np.abs(b - m)
    grad = np.maximum(np.abs(a - m), np.abs(b - m))
    side = np.where(pair_a, a, b)
    sign = np.where(pair_a, -1, 1)                             # towards the steeper neighbour
    # unit step along the edge and one to the chosen side, as flat offsets (and as rows, columns)
    qy, qx = np.where(horz, sign, 0), np.where(horz, 0, sign)
    along = np.where(horz, 1, Wp)
    across = qy * Wp + qx
    half = 0.5 * (side + m)                                    # the edge's mid luma
    thr = 0.25 * grad
    m_below = (m - half) < 0
    edge = (c, along, across, half, thr)
    dn, en = _search(lum_at, edge, -1, R - 1)                  # distances to the two ends
    dp, ep = _search(lum_at, edge, 1, R - 1)
    nearer_n = dn < dp
    good = np.where(nearer_n, (en < 0) != m_below, (ep < 0) != m_below)
    off = np.where(good, 0.5 - np.minimum(dn, dp) / (dn + dp), 0.0)
    return ys, xs, qy, qx, np.maximum(off, sub_f)[:, None].astype(np.float32)


def _search(lum_at, edge: tuple, direction: int, K: int):
    """Follow the edge one way (``direction`` ±1), every step at once: the luma half a
    pixel to the chosen side at 1..K steps along it; the way ends at its first step whose
    luma left the edge's (or at K): FXAA's search loop, as (pixels, K) arrays.  Returns
    (distance, luma there minus the edge's mid luma)."""
    c, along, across, half, thr = edge
    steps = np.arange(1, K + 1)
    i = c + direction * along                              # the first step, every pixel
    lum_e = 0.5 * (lum_at(i) + lum_at(i + across)) - half
    dist = np.ones(len(c), np.int64)
    todo = np.nonzero(np.abs(lum_e) < thr)[0]              # still on the edge: steps 2..K
    step = direction * along
    # steps 2..4 for every such pixel, then 5..K for those still on it: most edges end
    # within a few steps, the rest run the whole way (same values as all steps at once)
    for first, last in _chunks(K):
        if not len(todo):
            break
        st = steps[first - 1:last]
        i = c[todo, None] + st[None, :] * step[todo, None]
        far = 0.5 * (lum_at(i) + lum_at(i + across[todo, None])) - half[todo, None]
        done = np.abs(far) >= thr[todo, None]
        ended = done.any(1)
        j = done.argmax(1)
        if last == K:                                      # never left it: ends at step K
            j[~ended] = K - first
            ended[:] = True
        got = todo[ended]
        dist[got] = j[ended] + first
        lum_e[got] = far[np.nonzero(ended)[0], j[ended]]
        todo = todo[~ended]
    return dist, lum_e


#: how far (pixels, either axis) a pixel's FXAA result reads from it: the endpoint
#: search's steps along the edge, one pixel across it, and the 3x3 neighbourhood
REACH = int(OPTIONS["endpoint_search_iterations"]) + 1


def fxaa_update(smooth: np.ndarray, raw: np.ndarray, box) -> np.ndarray:
    """``smooth`` (the FXAA of a frame) made the FXAA of ``raw``, a frame that
    differs from that one only inside ``box`` (row and column slices): only
    the pixels within :data:`REACH` of the box are recomputed, from the pixels
    within twice that; every other pixel reads nothing that changed.

    >>> rng = np.random.default_rng(1)
    >>> a = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    >>> b = a.copy(); b[10:20, 5:15] = 255
    >>> sm = fxaa_update(fxaa(a), b, (slice(10, 20), slice(5, 15)))
    >>> np.array_equal(sm, fxaa(b))
    True
    """
    H, W = raw.shape[:2]
    ys, xs = box
    m = REACH + 1
    cy, cx = slice(max(0, ys.start - 2 * m), min(H, ys.stop + 2 * m)), \
        slice(max(0, xs.start - 2 * m), min(W, xs.stop + 2 * m))
    iy, ix = slice(max(0, ys.start - m), min(H, ys.stop + m)), slice(max(0, xs.start - m), min(W, xs.stop + m))
    part = fxaa(raw[cy, cx])
    smooth[iy, ix] = part[iy.start - cy.start:iy.stop - cy.start, ix.start - cx.start:ix.stop - cx.start]
    return smooth


_SCRATCH = threading.local()


def _scratch(H: int, W: int, R: int):
    """This thread's whole-frame buffers for (H, W) frames padded by R: the padded luma,
    two uint16 accumulators, high, low, threshold (uint8) and the edge mask; views of
    buffers kept between calls and grown when a frame needs more (frames of one video
    are one size; the parts :func:`fxaa_update` redoes vary)."""
    n, npad = H * W, (H + 2 * R) * (W + 2 * R)
    got = getattr(_SCRATCH, "bufs", None)
    if got is None or got[0] < n or got[1] < npad:
        n_, npad_ = max(n, got[0] if got else 0), max(npad, got[1] if got else 0)
        got = _SCRATCH.bufs = (n_, npad_, np.empty(npad_, np.uint8), np.empty(n_, np.uint16),
                               np.empty(n_, np.uint16), np.empty(n_, np.uint8), np.empty(n_, np.uint8),
                               np.empty(n_, np.uint8), np.empty(n_, bool))
    lp, acc, tmp, hi, lo, thr, edge = got[2:]
    return (lp[:npad].reshape(H + 2 * R, W + 2 * R), acc[:n], tmp[:n], hi[:n].reshape(H, W),
            lo[:n].reshape(H, W), thr[:n].reshape(H, W), edge[:n].reshape(H, W))


def _chunks(K: int):
    """The endpoint search's steps in two runs, (first, last) inclusive: 2..4, 5..K."""
    return ((2, 4), (5, K)) if K > 4 else ((2, K),) if K >= 2 else ()


__all__ = ["fxaa", "fxaa_update", "OPTIONS", "REACH"]

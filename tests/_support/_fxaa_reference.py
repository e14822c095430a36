"""A test's reference copy, kept on purpose: the plain FXAA of
``render/antialias.py`` as it was first written (every whole-frame array fresh, the
luma of the whole padded frame as floats, the endpoint search over all K steps at
once), which ``tests/render/test_antialias.py`` compares the tuned module with, byte for
byte.  It repeats that module by design; the package never imports it.
"""
from __future__ import annotations

import numpy as np

#: VTK's ``vtkFXAAOptions`` defaults (the filter the project used before)
OPTIONS = {"relative_contrast_threshold": 1 / 8, "hard_contrast_threshold": 1 / 16,
           "subpixel_blend_limit": 3 / 4, "subpixel_contrast_threshold": 1 / 4,
           "endpoint_search_iterations": 12}

_W8 = np.array([77, 150, 29], np.uint16)        # Rec. 601 luma in 1/256 steps (sums to 256)


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
    o = OPTIONS
    H, W = img.shape[:2]
    if out is None:
        out = img.copy()
    elif out is not img:
        np.copyto(out, img)
    if H < 3 or W < 3:
        return out
    # luma of every pixel in 1/255 (uint8: the whole-frame work stays on bytes), padded by
    # the longest endpoint search so no index leaves it: Lp[y + R, x + R] is pixel (y, x)
    R = int(o["endpoint_search_iterations"]) + 1
    lum = ((img[..., 0] * _W8[0] + img[..., 1] * _W8[1] + img[..., 2] * _W8[2]) >> 8).astype(np.uint8)
    Lp = np.pad(lum, R, mode="edge")
    Wp = W + 2 * R
    M = lum
    N, S = Lp[R - 1:R - 1 + H, R:R + W], Lp[R + 1:R + 1 + H, R:R + W]
    Wl, E = Lp[R:R + H, R - 1:R - 1 + W], Lp[R:R + H, R + 1:R + 1 + W]
    hi = np.maximum(np.maximum(np.maximum(N, S), np.maximum(Wl, E)), M)
    lo = np.minimum(np.minimum(np.minimum(N, S), np.minimum(Wl, E)), M)
    thr_hi = np.maximum(hi >> 3, np.uint8(round(255 * o["hard_contrast_threshold"]))) \
        if o["relative_contrast_threshold"] == 1 / 8 else \
        np.maximum((hi * o["relative_contrast_threshold"]).astype(np.uint8),
                   np.uint8(round(255 * o["hard_contrast_threshold"])))
    ys, xs = np.nonzero(hi - lo >= thr_hi)
    if not len(ys):
        return out
    flat = Lp.ravel().astype(np.float32) / np.float32(255)
    c = (ys + R) * Wp + (xs + R)                               # flat index in Lp
    m, n, s, w, e = flat[c], flat[c - Wp], flat[c + Wp], flat[c - 1], flat[c + 1]
    nw, ne, sw, se = flat[c - Wp - 1], flat[c - Wp + 1], flat[c + Wp - 1], flat[c + Wp + 1]
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

    # follow the edge both ways, every step at once: the luma half a pixel to the chosen
    # side at 1..K steps along it; each way ends at its first step whose luma left the
    # edge's (or at K): FXAA's search loop, as (pixels, K) arrays
    K = R - 1
    steps = np.arange(1, K + 1)

    def search(direction: int):
        i = c + direction * along                              # the first step, every pixel
        lum_e = 0.5 * (flat[i] + flat[i + across]) - half
        dist = np.ones(len(ys), np.int64)
        todo = np.nonzero(np.abs(lum_e) < thr)[0]              # still on the edge: steps 2..K
        if len(todo):
            i = c[todo, None] + direction * steps[None, 1:] * along[todo, None]
            far = 0.5 * (flat[i] + flat[i + across[todo, None]]) - half[todo, None]
            done = np.abs(far) >= thr[todo, None]
            j = np.where(done.any(1), done.argmax(1), K - 2)
            dist[todo] = j + 2
            lum_e[todo] = far[np.arange(len(todo)), j]
        return dist, lum_e

    dn, en = search(-1)                                        # distances to the two ends
    dp, ep = search(1)
    nearer_n = dn < dp
    good = np.where(nearer_n, (en < 0) != m_below, (ep < 0) != m_below)
    off = np.where(good, 0.5 - np.minimum(dn, dp) / (dn + dp), 0.0)
    off = np.maximum(off, sub_f)[:, None].astype(np.float32)
    # blend towards the neighbour across the edge (a bilinear tap off the pixel centre)
    c0 = img[ys, xs].astype(np.float32)
    c1 = img[np.clip(ys + qy, 0, H - 1), np.clip(xs + qx, 0, W - 1)].astype(np.float32)
    out[ys, xs] = np.rint(c0 + (c1 - c0) * off).astype(np.uint8)
    return out

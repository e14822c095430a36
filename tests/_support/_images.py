"""Image comparison for the render tests: SSIM (Wang, Bovik, Sheikh & Simoncelli 2004)."""
from __future__ import annotations

import numpy as np
from scipy import ndimage


def ssim(a: np.ndarray, b: np.ndarray, sigma: float = 1.5) -> float:
    """Mean SSIM of two uint8 images ((H, W) or (H, W, C), the channels
    averaged), Gaussian window of ``sigma`` pixels, K1 = 0.01, K2 = 0.03, L = 255:
    the definition of the paper and of scikit-image's ``gaussian_weights=True``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        raise ValueError(f"ssim: shapes differ, {a.shape} and {b.shape}")
    if a.ndim == 3:
        return float(np.mean([ssim(a[..., c], b[..., c], sigma) for c in range(a.shape[2])]))
    c1, c2 = (0.01 * 255) ** 2, (0.03 * 255) ** 2
    g = lambda x: ndimage.gaussian_filter(x, sigma, truncate=3.5)  # noqa: E731
    ma, mb = g(a), g(b)
    va, vb, cov = g(a * a) - ma * ma, g(b * b) - mb * mb, g(a * b) - ma * mb
    s = ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2))
    return float(s.mean())

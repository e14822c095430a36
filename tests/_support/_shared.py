"""Where the shared test data lives, and a skip when it is absent."""
from pathlib import Path

import pytest

SHARED = Path(__file__).resolve().parents[3] / "shared"
MOCAP = SHARED / "mocap"
PEER = SHARED / "peer-bvh"

ALL_BVH = ["88_01.bvh", "87_03.bvh", "88_05.bvh", "90_11.bvh", "88_01_mass-retarget.bvh",
           "mass_cartwheel.bvh", "mass_kick.bvh", "02_04_iclone-retarget.bvh",
           "01_01_iclone-retarget.bvh", "02_05_iclone-retarget.bvh",
           "test_freebvh.bvh", "test_mocapbank.bvh"]


def shared_file(name: str) -> Path:
    """Path of a shared BVH file; skips the test with a clear reason when absent."""
    for folder in (MOCAP, PEER):
        p = folder / name
        if p.exists():
            return p
    pytest.skip(f"needs ../shared/ test data ({name} not found under {SHARED}); "
                f"the shared folder sits beside the checkout in CI")

"""Shared fixtures: where the ../shared/ test data lives, and skipping when it is absent.

The data folder (motion-capture clips, papers) sits beside the checkout:
``<checkout>/../shared``.  Tests that need it say so in one of three ways, and
skip with a reason naming the missing path when it is absent:

* ``@pytest.mark.shared`` (the whole folder) or ``@pytest.mark.shared("mocap/88_01.bvh")``
  (particular files, relative to the folder);
* the ``SHARED`` fixture (the folder's path) or ``shared_path("mocap/88_01.bvh")``;
* the ``shared_bvh`` argument: the test runs once per BVH file in ``mocap/`` and
  ``peer-bvh/`` (ids are the file names).
"""
from __future__ import annotations

import signal
from pathlib import Path

import pytest

# A suite started with SIGINT ignored (a background job of a non-interactive shell,
# `nohup`) would hand that on to the commands the tests stop with ctrl-c (they would
# run on); a handled signal is reset to the default in a child, so handle it here.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

SHARED_DIR = Path(__file__).resolve().parents[2] / "shared"
BVH_FOLDERS = ("mocap", "peer-bvh")


def missing_reason(what: Path | str | None = None) -> str:
    """The skip reason for absent shared data."""
    target = SHARED_DIR if what is None else SHARED_DIR / what
    return (f"needs the shared test data: {target} not found (the 'shared' data folder "
            f"sits beside the checkout, at ../shared)")


def shared_bvh_files() -> list[Path]:
    """Every BVH file of the shared data (empty when the folder is absent)."""
    return sorted(p for folder in BVH_FOLDERS for p in (SHARED_DIR / folder).glob("*.bvh"))


@pytest.fixture(scope="session")
def SHARED() -> Path:  # noqa: N802 (the name the tests and docs use)
    """Path of the shared data folder; skips the test when it is absent."""
    if not SHARED_DIR.is_dir():
        pytest.skip(missing_reason())
    return SHARED_DIR


@pytest.fixture(scope="session")
def shared_path():
    """``shared_path("mocap/88_01.bvh")``: the path of a shared file; skips when absent."""
    def get(relative: str) -> Path:
        p = SHARED_DIR / relative
        if not p.exists():
            pytest.skip(missing_reason(relative))
        return p
    return get


def pytest_runtest_setup(item):
    marker = item.get_closest_marker("shared")
    if marker is None:
        return
    for relative in marker.args or (None,):
        target = SHARED_DIR if relative is None else SHARED_DIR / relative
        if not target.exists():
            pytest.skip(missing_reason(relative))


def pytest_generate_tests(metafunc):
    if "shared_bvh" in metafunc.fixturenames:
        files = shared_bvh_files()
        if files:
            metafunc.parametrize("shared_bvh", files, ids=[p.name for p in files])
        else:
            metafunc.parametrize("shared_bvh", [pytest.param(
                None, marks=pytest.mark.skip(reason=missing_reason()))], ids=["no-shared-data"])


# tests/_support holds the tests' shared builders (on the path, see pyproject.toml), not
# tests: not collected (--doctest-modules would import them, and _mujoco_model.py needs
# the optional mujoco, which the one test using it skips without)
collect_ignore = ["_support"]

"""PyVista/VTK import in offscreen EGL mode (no X server).

Import pyvista through this module so the EGL render window is selected
before VTK creates its first window::

    from ._pv import pv
"""
from __future__ import annotations

import os

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pyvista as pv  # noqa: E402

pv.OFF_SCREEN = True

__all__ = ["pv"]

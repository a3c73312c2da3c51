"""pyvista for off-screen pictures without an X server.

VTK's default render window on Linux is X11: without a display it prints "bad X server connection"
(with raw ANSI colour codes) before falling back. Where no ``DISPLAY`` is set and the user has not
chosen a window class, femcheck asks VTK (>= 9.4 picks the window class at run time) for its EGL window,
which renders headless on the GPU driver or Mesa's software EGL; the callers fall back to matplotlib
when pyvista cannot render at all.
"""
from __future__ import annotations

import os


def import_pyvista():
    """The ``pyvista`` module, set up to render off screen without touching X when there is no display."""
    if not os.environ.get("DISPLAY") and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ:
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
    import pyvista as pv
    pv.OFF_SCREEN = True
    return pv

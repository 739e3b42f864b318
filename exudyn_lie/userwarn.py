"""Warnings that point at the user's line, not at the package's internals."""
import os
import sys
import warnings

_PACKAGE = os.path.dirname(os.path.realpath(__file__)) + os.sep


_INSIDE = {}     # code file name -> inside the package (realpath costs about 10 us a call)


def _inside_package(frame):
    name = frame.f_code.co_filename
    inside = _INSIDE.get(name)
    if inside is None:
        inside = _INSIDE[name] = os.path.realpath(name).startswith(_PACKAGE)
    return inside


def warn_user(message, category=RuntimeWarning):
    """``warnings.warn`` with the ``stacklevel`` of the first caller outside exudyn_lie
    (the user's script or test), however deep in the package the warning arises (also in
    the hook Exudyn's time loop calls)."""
    level, frame = 2, sys._getframe(1)
    while frame.f_back is not None and _inside_package(frame):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)

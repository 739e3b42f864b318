"""The examples of Müller & Terze as Exudyn model builders.

Every module has ``NAME`` and ``build(mbs=None, nodeType=..., endTime=...) -> (mbs, info)``
(:class:`exudyn_lie.models._common.ModelInfo`): an ordinary Exudyn model, built with Exudyn's own
``Create*`` helpers, plus the data needed to judge it (bodies, joints ``joint1``...,
springs, time span, exact solutions for the free bodies, the paper's numbers and
claims, and every choice made where the paper leaves a gap).

>>> from exudyn_lie import models
>>> mbs, info = models.build("heavy_top")
>>> res = models.run_native(info, "GeneralizedAlpha", stepSize=1e-3)

``MODELS`` lists them in the paper's order.
"""
import importlib

from ._common import (GROUND, BodyData, Claim, JointData, ModelInfo, NativeResult,  # noqa: F401
                      SpringData, check_initial_consistency, native_solvers_for, run_native,
                      run_native_default_steps)

__all__ = ["MODELS", "build", "module", "run_native", "run_native_default_steps", "native_solvers_for", "check_initial_consistency",
           "ModelInfo", "BodyData", "JointData", "SpringData", "Claim", "NativeResult", "GROUND"]

MODELS = [
    "free_body_com_rotation",
    "free_body_com_translation",
    "free_body_offset_rotation",
    "free_body_offset_screw",
    "heavy_top",
    "spherical_double_pendulum",
    "planar_four_bar",
    "rp_mechanism",
    "cardan_shaft",
    "spherical_three_bar",
    "spherical_four_bar",
]


def module(name):
    if name not in MODELS:
        raise KeyError(f"unknown model {name!r}; available: {', '.join(MODELS)}")
    return importlib.import_module(f"{__name__}.{name}")


def build(name, mbs=None, **kwargs):
    """Build the named model; returns (mbs, info)."""
    return module(name).build(mbs=mbs, **kwargs)

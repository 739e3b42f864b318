"""Free body, body frame at the COM: spatial rotation (paper: Unconstrained Rigid Body -
Reference Frame at COM, 'Spatial Rotation').

omega0 = (10 pi, 2 pi, 0) rad/s, v0 = 0, 10 s, no gravity.  The COM must stay at r = 0;
both groups keep it exactly and rotate identically (pure rotation about the frame
origin is a subgroup of both SE(3) and SO(3)xR3).

Data and the filled gaps: see :mod:`exudyn_lie.models._free_body` and ``info.choices``.
"""
import exudyn as exu

from ._free_body import build_free_body

NAME = "free_body_com_rotation"


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=10.0):
    """Create the model in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, info = build_free_body("com_rotation", mbs=mbs, nodeType=nodeType, endTime=endTime)
    info.builder = build
    info.buildArgs = dict(nodeType=nodeType, endTime=endTime)
    return mbs, info

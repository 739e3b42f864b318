"""Free body, body frame off the COM (COM at r0 = (0.4, 0, 0)): spatial rotation (paper:
Unconstrained Rigid Body - Arbitrary Body-Fixed Reference Frame, 'Spatial Rotation').

omega0 = (10 pi, 2 pi, 0) rad/s, COM at rest, so the frame origin starts with
v0 = r0 x omega0; 10 s.  The frame rotates about the fixed COM: an SO(3) subgroup of
SE(3) (exact), only a submanifold of SO(3)xR3 (step-size dependent COM drift).
Kinetic energy T0 = 696.399 J (paper).

Data and the filled gaps: see :mod:`exudyn_lie.models._free_body` and ``info.choices``.
"""
import exudyn as exu

from ._free_body import build_free_body

NAME = "free_body_offset_rotation"


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=10.0):
    """Create the model in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, info = build_free_body("offset_rotation", mbs=mbs, nodeType=nodeType, endTime=endTime)
    info.builder = build
    info.buildArgs = dict(nodeType=nodeType, endTime=endTime)
    return mbs, info

"""Free body, body frame off the COM: spatial rotation plus COM translation (paper:
'Rotation about fixed axis plus linear translation' of the off-COM section).

omega0 = (10 pi, 2 pi, 0) rad/s, v0 = r0 x omega0 + (10, 0, 0) m/s, 10 s.  The motion of
the frame is a subgroup of neither group; both updates are step-size dependent, the
paper reports SO(3)xR3 as the more accurate.

Data and the filled gaps: see :mod:`exudyn_lie.models._free_body` and ``info.choices``.
"""
import exudyn as exu

from ._free_body import build_free_body

NAME = "free_body_offset_screw"


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=10.0):
    """Create the model in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, info = build_free_body("offset_screw", mbs=mbs, nodeType=nodeType, endTime=endTime)
    info.builder = build
    info.buildArgs = dict(nodeType=nodeType, endTime=endTime)
    return mbs, info

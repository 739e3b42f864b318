"""Free body, body frame at the COM: rotation about a fixed axis plus translation (paper:
'Rotation about fixed axis plus linear translation').

omega0 = (0, 0, 2 pi) rad/s, v0 = (10, 0, 0) m/s, 10 s.  Exact: r(t) = (10 t, 0, 0),
R(t) = Rz(2 pi t) (the paper prints r(t) = (t, 0, 0); see choices).  Decoupled rotation
and translation is a subgroup of SO(3)xR3 but not of SE(3): SO(3)xR3 is exact, SE(3)
converges with 4th order.

Data and the filled gaps: see :mod:`exudyn_lie.models._free_body` and ``info.choices``.
"""
import exudyn as exu

from ._free_body import build_free_body

NAME = "free_body_com_translation"


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=10.0):
    """Create the model in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, info = build_free_body("com_translation", mbs=mbs, nodeType=nodeType, endTime=endTime)
    info.builder = build
    info.buildArgs = dict(nodeType=nodeType, endTime=endTime)
    return mbs, info

"""Spherical double pendulum in the gravity field: 2 aluminium boxes 0.2 x 0.1 x 0.05 m connected by
spherical joints, joint 1 to the ground (the paper's example).

Data, initial conditions and the filled gaps: :mod:`exudyn_lie.models._spherical_chain` and
``info.choices``.  Claims: joint 1 exact with SE(3) (corollary 1); the other joints
the same order with both groups (corollary 3).
"""
import exudyn as exu

from ._spherical_chain import build_chain

NAME = "spherical_double_pendulum"


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=5.0):
    """Create the model in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, info = build_chain(2, NAME, "Spherical double pendulum", mbs=mbs, nodeType=nodeType, endTime=endTime)
    info.builder = build
    info.buildArgs = dict(nodeType=nodeType, endTime=endTime)
    return mbs, info

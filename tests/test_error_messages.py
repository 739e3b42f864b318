"""Errors as an Exudyn user meets them: raised at the package boundary, so the traceback
ends at the user's call (two frames: the call and the boundary), and naming Exudyn's own
object and node numbers, never the kernel's body indices."""
import traceback

import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import InertiaCuboid, MarkerBodyRigid, ObjectJointGeneric

import exudyn_lie as exl


def joint_on_one_body():
    """A ground first (object 0) and a body (object 1, node 0), so that the kernel's body
    index 0 differs from Exudyn's object number; a joint with both markers on the body."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    mbs.CreateGround()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [1, 0.1, 0.1]), referencePosition=[1, 0, 0])
    m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0, 0, 0]))
    m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.1, 0, 0]))
    mbs.AddObject(ObjectJointGeneric(markerNumbers=[m0, m1], constrainedAxes=[1, 1, 1, 0, 0, 0]))
    mbs.Assemble()
    return SC, mbs


def test_refusal_names_exudyns_items_and_ends_at_the_users_call():
    SC, mbs = joint_on_one_body()
    with pytest.raises(exl.BridgeError) as info:
        exl.SolveDynamic(mbs, exu.SimulationSettings(), showProgress=False)
    msg = str(info.value)
    assert "object 2 " in msg and "ObjectJointGeneric" in msg
    assert "on the same body, object 1 ('object1', node 0 RigidBodyEP)" in msg and "body 0" not in msg
    frames = traceback.extract_tb(info.value.__traceback__)
    assert [f.name for f in frames] == ["test_refusal_names_exudyns_items_and_ends_at_the_users_call", "entry"]
    assert info.value.__suppress_context__


def test_the_whole_traceback_on_request(monkeypatch):
    """EXUDYN_LIE_TRACEBACK=1 keeps the traceback into the package (for a bug report)."""
    monkeypatch.setenv("EXUDYN_LIE_TRACEBACK", "1")
    SC, mbs = joint_on_one_body()
    with pytest.raises(exl.BridgeError) as info:
        exl.SolveDynamic(mbs, exu.SimulationSettings(), showProgress=False)
    assert len(traceback.extract_tb(info.value.__traceback__)) > 3


def test_a_user_functions_own_error_keeps_its_traceback():
    """An exception of the user's own function is not exudyn_lie's to shorten: its frame is in
    the traceback."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [1, 0.1, 0.1]), referencePosition=[0, 0, 0])

    def PreStepUserFunction(mbs, t):
        raise KeyError("the user's own bug")
    mbs.SetPreStepUserFunction(PreStepUserFunction)
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = 10
    ss.timeIntegration.endTime = 0.01
    with pytest.raises(Exception) as info:
        exl.SolveDynamic(mbs, ss, showProgress=False)
    names = [f.name for f in traceback.extract_tb(info.value.__traceback__)]
    assert "entry" not in names[-1:] and len(names) > 2

"""Every registered compiled force element with its live parameters changed during a solve.

One case per registration of ``exudyn_lie/mbs/force_elements.py`` (a new element fails
``test_every_registered_element_has_a_case`` until it has one): an Exudyn model with the
element's item between the ground and a spinning body, two sets of values ``A`` and ``B`` of
*every* field its item registration (``bridge/items.py``) calls live, and the switch
``activeConnector = False``.  A pre-step function changes the item from A to B
(``mbs.SetObjectParameter``), and the bridge rewrites the element's compiled row from its
registration (``bridge/params.py`` -> ``force_elements.write_row``).  Two truths:

* changed before the first step = the model built with B from the start (the reader and the
  row builders give the same rows);
* changed in the middle of the run = the run stopped there and restarted from the state it
  reached (nodes, velocities and data coordinates copied to the initial configuration) with B
  set before ``Assemble``: what the element carries across the change - the torsional
  spring's tracked turns, the penalty rolling disc's data coordinates - must carry on as in a
  run that re-reads the model from the state.

The torsional spring starts with its data node two turns on (Exudyn's continuous angle), and
B turns its marker frame by -2.8 rad: the principal angle then jumps to the other side of
+-pi, so a re-read that re-derived the turns from the initial state would be one turn off.
"""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (InertiaCuboid, MarkerBodyRigid, MarkerNodeCoordinate, NodeGenericData, NodePointGround,
                              ObjectConnectorCartesianSpringDamper, ObjectConnectorCoordinateSpringDamper,
                              ObjectConnectorLinearSpringDamper, ObjectConnectorRigidBodySpringDamper,
                              ObjectConnectorRollingDiscPenalty, ObjectConnectorSpringDamper,
                              ObjectConnectorTorsionalSpringDamper, RotationMatrixX, RotationMatrixY,
                              RotationMatrixZ)

import exudyn_lie as exl
from exudyn_lie.bridge.items import ITEMS, LIVE
from exudyn_lie.mbs.force_elements import ELEMENTS

# rotationMarker0/1 are deprecated in Exudyn (still live fields of the registered items)
pytestmark = pytest.mark.filterwarnings("ignore:ObjectConnector:DeprecationWarning")

H = 1e-3
T = 0.06
N_CHANGE = 30                  # the mid-run change: before step N_CHANGE + 1 (t = N_CHANGE h)
_KEEP = []                     # SystemContainers alive until the end


def _pair(offset=0.0):
    """A ground and a spinning free rigid body (RotVecLG node, gravity), with rotated and
    shifted markers on both."""
    SC = exu.SystemContainer()
    _KEEP.append(SC)
    mbs = SC.AddSystem()
    g = mbs.CreateGround(referencePosition=[0.1, -0.2, 0.05], referenceRotationMatrix=RotationMatrixY(0.1))
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.4, 0.2, 0.1]), referencePosition=[0.3, 0.1, 0.2 + offset],
                            referenceRotationMatrix=RotationMatrixZ(0.4), initialAngularVelocity=[0.3, -0.2, 2.0],
                            initialVelocity=[0.1, 0.05, 0.0], gravity=[0, 0, -9.81])
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=RotationMatrixX(0.2),
                                                                    translation=[0.2, 0.0, 0.1])))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localHT=exu.HT(rotation=RotationMatrixY(-0.3),
                                                                    translation=[0.05, 0.02, -0.03])))
    return mbs, g, b, mG, mB


def spring(v):
    mbs, g, b, mG, mB = _pair()
    return mbs, mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mG, mB], **v))


def cartesian(v):
    mbs, g, b, mG, mB = _pair()
    return mbs, mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[mG, mB], **v))


def torsional(v):
    """Ground marker frame I, body frame Rz(0.4): principal angle 0.4, data node 0.4 + 4 pi."""
    mbs, g, b, _, _ = _pair()
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=RotationMatrixY(-0.1),
                                                                    translation=[0.2, 0.1, 0.0])))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.1, 0.0, 0.0]))
    nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0.4 + 4 * np.pi], numberOfDataCoordinates=1))
    return mbs, mbs.AddObject(ObjectConnectorTorsionalSpringDamper(markerNumbers=[mG, mB], nodeNumber=nd, **v))


def coordinate(v):
    mbs, g, b, _, _ = _pair()
    n0 = mbs.AddNode(NodePointGround(referenceCoordinates=[0.1, 0.2, 0.0]))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n0, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.GetObject(b)["nodeNumber"], coordinate=0))
    return mbs, mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[m0, m1], **v))


def linear(v):
    mbs, g, b, mG, mB = _pair()
    return mbs, mbs.AddObject(ObjectConnectorLinearSpringDamper(markerNumbers=[mG, mB], **v))


def rigid(v):
    mbs, g, b, mG, mB = _pair()
    return mbs, mbs.AddObject(ObjectConnectorRigidBodySpringDamper(markerNumbers=[mG, mB], **v))


def rolling_disc_penalty(v):
    """A disc (axis x, radius 0.2, its centre 0.199 above the ground: in contact) rolling."""
    SC = exu.SystemContainer()
    _KEEP.append(SC)
    mbs = SC.AddSystem()
    g = mbs.CreateGround()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.05, 0.4, 0.4]), referencePosition=[0, 0, 0.199],
                            initialAngularVelocity=[4.0, 0, 0.3], initialVelocity=[0, -0.79, 0],
                            gravity=[0, 0, -9.81])
    nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0.01, -0.02, -0.001], numberOfDataCoordinates=3))
    return mbs, mbs.AddObject(ObjectConnectorRollingDiscPenalty(
        markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)), mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))],
        nodeNumber=nd, **v))


def _unit(v):
    return list(np.asarray(v, float) / np.linalg.norm(v))       # Exudyn's Assemble wants unit vectors


def _k6(a, b):
    K = np.diag([a, 1.5 * a, 2 * a, b, 2 * b, 3 * b])
    K[0, 4] = K[4, 0] = 0.1 * b
    return K


# element name -> (builder, values A, values B): every live field of the item (user functions
# and activeConnector apart) changes from A to B
CASES = {
    "spring": (spring, dict(stiffness=200.0, damping=2.0, referenceLength=0.3, force=1.0, velocityOffset=0.1),
               dict(stiffness=500.0, damping=5.0, referenceLength=0.2, force=-2.0, velocityOffset=-0.3)),
    "cartesian": (cartesian, dict(stiffness=[100.0, 200.0, 300.0], damping=[1.0, 2.0, 3.0], offset=[0.1, 0, 0]),
                  dict(stiffness=[400.0, 50.0, 20.0], damping=[3.0, 1.0, 0.5], offset=[0, -0.1, 0.05])),
    "torsional": (torsional, dict(stiffness=20.0, damping=0.2, offset=0.1, torque=0.5, velocityOffset=0.3,
                                  rotationMarker0=np.eye(3), rotationMarker1=np.eye(3)),
                  dict(stiffness=50.0, damping=0.1, offset=-0.2, torque=-0.4, velocityOffset=-0.5,
                       rotationMarker0=RotationMatrixZ(-2.8), rotationMarker1=RotationMatrixZ(0.05))),
    "coordinate": (coordinate, dict(stiffness=300.0, damping=3.0, offset=0.1),
                   dict(stiffness=800.0, damping=1.0, offset=-0.2)),
    "linear": (linear, dict(stiffness=300.0, damping=2.0, axisMarker0=[1.0, 0, 0], offset=0.1, velocityOffset=0.2,
                            force=0.5),
               dict(stiffness=700.0, damping=4.0, axisMarker0=[0.6, 0.8, 0], offset=-0.1, velocityOffset=-0.1,
                    force=-1.0)),
    "rigid": (rigid, dict(stiffness=_k6(500.0, 10.0), damping=0.01 * _k6(500.0, 10.0), offset=[0.1, 0, 0, 0, 0.2, 0],
                          rotationMarker0=np.eye(3), rotationMarker1=np.eye(3), useIntrinsicFormulation=False),
              dict(stiffness=_k6(900.0, 4.0), damping=0.02 * _k6(900.0, 4.0), offset=[0, -0.1, 0.05, 0.1, 0, 0.3],
                   rotationMarker0=RotationMatrixX(0.3), rotationMarker1=RotationMatrixZ(-0.6),
                   useIntrinsicFormulation=True)),
    "rollingDiscPenalty": (rolling_disc_penalty, dict(
        discRadius=0.2, discAxis=[1.0, 0, 0], planeNormal=[0, 0, 1.0], dryFrictionAngle=0.0, contactStiffness=1e5,
        contactDamping=100.0, dryFriction=[0.5, 0.4], dryFrictionProportionalZone=0.02, viscousFriction=[0.0, 0.0],
        rollingViscousFriction=0.0, useLinearProportionalZone=False), dict(
        discRadius=0.201, discAxis=_unit([1.0, 0.05, 0]), planeNormal=_unit([0, 0.02, 1.0]), dryFrictionAngle=0.3,
        contactStiffness=2e5, contactDamping=50.0, dryFriction=[0.3, 0.6], dryFrictionProportionalZone=0.05,
        viscousFriction=[0.1, 0.2], rollingViscousFriction=0.05, useLinearProportionalZone=True)),
}
NAMES = [e.name for e in ELEMENTS]


def _settings(n):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = n * H
    ss.timeIntegration.numberOfSteps = n
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.show.statistics = False
    ss.show.computationTime = False
    return ss


def _state(mbs):
    sd = mbs.systemData
    return np.concatenate([sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(), sd.GetDataCoordinates()])


def _run(build, values, n, change=None, at=0):
    """Build with ``values``, solve ``n`` steps with exl; ``change`` (field -> value) is set by a
    pre-step function before step ``at + 1``."""
    mbs, o = build(values)
    if change is not None:
        def pre_step(mbs, t):
            if abs(t - (at + 1) * H) < 0.5 * H:
                for key, v in change.items():
                    mbs.SetObjectParameter(o, key, v)
            return True
        mbs.SetPreStepUserFunction(pre_step)
    mbs.Assemble()
    exl.SolveDynamic(mbs, _settings(n), showProgress=False)
    return mbs, o


def _live_fields(mbs, o):
    it = ITEMS[("object", mbs.GetObject(o)["objectType"])]
    return {k for k, (status, _) in it.fields.items()
            if status == LIVE and not k.endswith("UserFunction") and k != "activeConnector"}


def test_every_registered_element_has_a_case():
    assert set(CASES) == set(NAMES), "add a case for each registered force element: " + str(set(NAMES) ^ set(CASES))


def _variant(name, variant):
    build, A, B = CASES[name]
    return build, A, (B if variant == "values" else {"activeConnector": False})


@pytest.mark.parametrize("variant", ["values", "switched off"])
@pytest.mark.parametrize("name", NAMES)
def test_changed_before_the_first_step_equals_the_model_built_with_the_new_values(name, variant):
    build, A, B = _variant(name, variant)
    mbs, o = _run(build, A, int(round(T / H)), change=B, at=0)
    solver = mbs.sys["lieGroupSolver"]
    assert solver.scene.itemRows[("object", int(o))][0] == name         # the case exercises its element
    assert variant != "values" or set(B) == _live_fields(mbs, o)   # every live field changes
    assert solver._params.updates >= 1
    got = _state(mbs)
    ref = _state(_run(build, dict(A, **B), int(round(T / H)))[0])
    err = np.max(np.abs(got - ref))
    print(f"{name} {variant}: max |changed - built with the new values| = {err:.3g}")
    # the same rows from the same reader: the same arithmetic (the torsional spring: the same
    # continuous angle from another start of the kernel's tracking, to round-off)
    assert err <= (1e-12 if name == "torsional" else 0.0) * max(1.0, np.max(np.abs(ref)))
    unchanged = _state(_run(build, A, int(round(T / H)))[0])
    assert np.max(np.abs(unchanged - ref)) > 1e-4          # the change matters


@pytest.mark.parametrize("variant", ["values", "switched off"])
@pytest.mark.parametrize("name", NAMES)
def test_changed_mid_run_equals_a_restart_from_the_state_with_the_new_values(name, variant):
    build, A, B = _variant(name, variant)
    n = int(round(T / H))
    got = _state(_run(build, A, n, change=B, at=N_CHANGE)[0])
    mbs, o = _run(build, A, N_CHANGE)
    state = mbs.systemData.GetSystemState()
    for key, v in B.items():
        mbs.SetObjectParameter(o, key, v)
    mbs.Assemble()
    mbs.systemData.SetSystemState(state, configuration=exu.ConfigurationType.Initial)
    exl.SolveDynamic(mbs, _settings(n - N_CHANGE), showProgress=False)
    ref = _state(mbs)
    err = np.max(np.abs(got - ref))
    print(f"{name} {variant}: max |changed mid-run - restarted| = {err:.3g}")
    # the restart reads the nodes' coordinates back into rotation matrices: round-off
    assert err <= 1e-11 * max(1.0, np.max(np.abs(ref)))


@pytest.mark.filterwarnings("ignore:exudyn_lie. the initial state:RuntimeWarning")   # the spin breaks J V = 0
def test_a_moved_marker_of_a_constraint_connector_stops_the_solve():
    """The markers of every item with the joint role (bridge/items.py) are fixed during a run,
    ConnectorDistance's too (its row would need the marker's velocity and acceleration)."""
    from exudyn.utilities import MarkerBodyPosition, ObjectConnectorDistance
    from exudyn_lie.bridge import BridgeError
    mbs, g, b, _, _ = _pair()
    mG = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0.0, 0.0, 0.6]))
    mB = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0.1, 0.0, 0.0]))
    o = mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mG, mB], distance=0.5))
    mbs.Assemble()
    p0, p1 = (np.asarray(mbs.GetMarkerOutput(m, exu.OutputVariableType.Position)) for m in (mG, mB))
    mbs.SetObjectParameter(o, "distance", float(np.linalg.norm(p1 - p0)))      # the initial state satisfies it

    def pre_step(mbs, t):
        if t > 0.0105:
            mbs.SetMarkerParameter(mG, "localPosition", [0.0, 0.01, 0.6])
        return True

    mbs.SetPreStepUserFunction(pre_step)
    mbs.Assemble()
    with pytest.raises(BridgeError) as e:
        exl.SolveDynamic(mbs, _settings(20), showProgress=False)
    assert "ObjectConnectorDistance" in str(e.value) and "moved during the solve" in str(e.value), str(e.value)

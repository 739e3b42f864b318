"""The kinematics of Python items computed by the compiled stage (mbs/external_probes.py).

A torsional spring with a ``springTorqueUserFunction`` reads its angle, rate and axis from
``Work.probe``, filled by the compiled stage before the one Python call per stage
(``TorsionalSpringDamperUF.add_stage``), a spring-damper with a ``springForceUserFunction``
its length, rate, direction and arms (``SpringDamperUF.add_stage``).  The reference is the
same item evaluated in Python from the body states (``add``, the path taken without ``add_stage``):
the two must integrate to the same bits (the compiled arithmetic is the Python item's, in its
order), in every configuration of the markers, with the angle tracked over turns, next to
other Python items acting on the same bodies, and after the spring's frames are changed
during a solve.
"""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import InertiaCuboid, RotationMatrixX, RotationMatrixZ, SensorBody

import exudyn_lie as exl
from exudyn_lie.bridge import SceneFromExudyn, pyforces, pyforces_coordinates
from exudyn_lie.mbs import Simulator

ii = exu.itemInterface


def uf_torque(mbs, t, itemNumber, rotation, angularVelocity, stiffness, damping, offset):
    return stiffness * (rotation - offset) + damping * angularVelocity + 0.1 * np.sin(3 * t)


def spinning_pair(config):
    """Two bodies spinning about their z axes, both along the tilted world axis ``a`` (body 0
    on a spherical joint), Python items: a torsional spring with a user function about ``a``
    in the marker configuration ``config`` (marker frames turned about ``a``: the spring's law
    then has a potential and the motion stays bounded), a second one between the ground and
    body 1, and a torque load with a ``loadVectorUserFunction`` on body 1."""
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.AddObject(ii.ObjectGround())
    iner = InertiaCuboid(1000, [0.1, 0.2, 0.3])
    tilt = RotationMatrixX(0.2)
    b0 = mbs.CreateRigidBody(inertia=iner, referencePosition=[0, 0, 0], referenceRotationMatrix=tilt,
                             initialAngularVelocity=tilt @ [0, 0, 4.0] + [0.02, 0.01, 0])
    b1 = mbs.CreateRigidBody(inertia=iner, referencePosition=[0, 0, 0.5], referenceRotationMatrix=tilt,
                             initialAngularVelocity=tilt @ [0, 0, -6.0])
    mg = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=g))
    m0 = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=b0))
    m1 = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=b1))
    mbs.AddObject(ii.SphericalJoint(markerNumbers=[mg, m0]))
    markers = {"groundA": [mg, m1], "groundB": [m1, mg], "bodies": [m0, m1]}[config]
    kw = {}
    if config == "bodies":          # with a data node: the angle is tracked over turns
        kw["nodeNumber"] = mbs.AddNode(ii.NodeGenericData(initialCoordinates=[0.0], numberOfDataCoordinates=1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)     # rotationMarker*: Exudyn prefers marker localHT
        mbs.AddObject(ii.TorsionalSpringDamper(markerNumbers=markers, stiffness=0.002, damping=2e-5, offset=0.1,
                                               rotationMarker0=RotationMatrixZ(0.4) if config == "bodies" else tilt,
                                               rotationMarker1=RotationMatrixZ(-0.3),
                                               springTorqueUserFunction=uf_torque, **kw))
        mbs.AddObject(ii.TorsionalSpringDamper(markerNumbers=[mg, m1], stiffness=0.005, damping=1e-4,
                                               rotationMarker0=tilt,
                                               springTorqueUserFunction=uf_torque))
    mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m1, loadVector=[0, 0, 1.0],
                                    loadVectorUserFunction=lambda mbs, t, lv: [0.0, 0.002 * np.cos(t), 0.01 * t]))
    mbs.Assemble()
    return mbs


def uf_spring(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
    return stiffness * deltaL * (1.0 + deltaL * deltaL) + damping * deltaL_t + force


def spring_pair(config):
    """Body 0 hanging from a spherical joint off its centre of mass, body 1 free, under
    gravity; Python items: a spring-damper with a ``springForceUserFunction`` between points
    off the frame origins in the marker configuration ``config``, and a second one between
    the ground and body 0."""
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.AddObject(ii.ObjectGround())
    iner = InertiaCuboid(1000, [0.1, 0.2, 0.3])
    b0 = mbs.CreateRigidBody(inertia=iner, referencePosition=[0.3, 0, 0], referenceRotationMatrix=RotationMatrixX(0.2),
                             initialVelocity=[0, 0.6, 0.3], initialAngularVelocity=[0.5, -1.0, 2.0],
                             gravity=[0, 0, -9.81])
    b1 = mbs.CreateRigidBody(inertia=iner, referencePosition=[0.2, 0.3, -0.8], initialVelocity=[0.1, 0, 0.3],
                             initialAngularVelocity=[1.0, 0.5, -3.0], gravity=[0, 0, -9.81])
    mbs.CreateSphericalJoint(itemNumbers=[g, b0], position=[0, 0, 0])
    mg = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=g, localPosition=[0.2, 0.4, 0.5]))
    m0 = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=b0, localPosition=[0.05, -0.1, 0.15]))
    m1 = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=b1, localPosition=[-0.05, 0.1, 0.1]))
    markers = {"groundA": [mg, m1], "groundB": [m1, mg], "bodies": [m0, m1]}[config]
    mbs.AddObject(ii.SpringDamper(markerNumbers=markers, stiffness=800.0, damping=8.0, referenceLength=0.9,
                                  force=2.0, springForceUserFunction=uf_spring))
    mbs.AddObject(ii.SpringDamper(markerNumbers=[mg, m0], stiffness=300.0, damping=3.0, referenceLength=0.5,
                                  springForceUserFunction=uf_spring))
    # loads with a loadVectorUserFunction: a force off the frame origin, a mass-proportional one
    r1 = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=b1, localPosition=[0.04, -0.03, 0.1]))
    mbs.AddLoad(ii.LoadForceVector(markerNumber=r1, loadVector=[1.0, 0, 0],
                                   loadVectorUserFunction=lambda mbs, t, lv: [lv[0] * np.cos(5 * t), 0.5, -0.2 * t]))
    mm = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=b0))
    mbs.AddLoad(ii.LoadMassProportional(markerNumber=mm, loadVector=[0, 0, 0],
                                        loadVectorUserFunction=lambda mbs, t, lv: [0.3 * np.sin(2 * t), 0.1, 0.0]))
    mbs.Assemble()
    return mbs


def python_path(monkeypatch):
    """From now on the items run as Python items (the stage adder then calls ``add``)."""
    for cls in (pyforces.TorsionalSpringDamperUF, pyforces.SpringDamperUF, pyforces.LoadUF,
                pyforces_coordinates.CoordinateSpringDamperUF, pyforces_coordinates.CoordinateLoadUF):
        monkeypatch.delattr(cls, "add_stage")


def integrate(mbs, steps=3000, h=1e-3):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulator(SceneFromExudyn(mbs), "RK4", "SE3")
    sim.SetInitialState()
    sim.Advance(steps, h)
    items = sim.scene.pythonForces[0].fn.items
    return np.concatenate([sim.R.ravel(), sim.r.ravel(), sim.V.ravel()]), items


@pytest.mark.parametrize("config", ["groundA", "groundB", "bodies"])
def test_probed_spring_integrates_as_the_python_item(config, monkeypatch):
    probed, items = integrate(spinning_pair(config))
    assert sum(getattr(it, "probeIndex", None) is not None for it in items) == 2
    if config == "bodies":
        assert abs(items[0].prev) > 4 * np.pi          # tracked over more than two turns
    python_path(monkeypatch)
    python, _ = integrate(spinning_pair(config))
    assert np.all(np.isfinite(probed))
    np.testing.assert_array_equal(probed, python)


@pytest.mark.parametrize("config", ["groundA", "groundB", "bodies"])
def test_probed_spring_damper_integrates_as_the_python_item(config, monkeypatch):
    probed, items = integrate(spring_pair(config))
    assert sum(getattr(it, "probeIndex", None) is not None for it in items) == 4
    python_path(monkeypatch)
    python, _ = integrate(spring_pair(config))
    assert np.all(np.isfinite(probed))
    np.testing.assert_array_equal(probed, python)


def frames_moved(move):
    """A body spinning on a spherical joint, a torsional spring with a user function to the
    ground whose marker-0 frame a pre-step function turns (``move``) during the solve, and a
    force with a user function whose load vector it sets."""
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.CreateGround()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.1, 0.2, 0.3]), referencePosition=[0, 0, 0],
                            initialAngularVelocity=[0.5, 0.3, 2.0])
    mbs.CreateSphericalJoint(itemNumbers=[g, b], position=[0, 0, 0])
    mg = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=g))
    mb = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=b))
    tsd = mbs.AddObject(ii.TorsionalSpringDamper(markerNumbers=[mg, mb], stiffness=20.0, damping=0.5,
                                                 springTorqueUserFunction=uf_torque))
    mf = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=b, localPosition=[0.1, 0, 0.05]))
    load = mbs.AddLoad(ii.LoadForceVector(markerNumber=mf, loadVector=[0, 0, 0],
                                          loadVectorUserFunction=lambda mbs, t, lv: [lv[0], lv[1], 0.1]))

    def pre_step(mbs, t):
        mbs.SetLoadParameter(load, "loadVector", [0.2 * np.sin(30 * t), 0.1, 0])
        if move:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                mbs.SetObjectParameter(tsd, "rotationMarker0", RotationMatrixX(0.5 * np.floor(t / 0.02)))
        return True

    mbs.SetPreStepUserFunction(pre_step)
    sens = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, localPosition=[0.1, 0.05, 0.02],
                                    outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = 0.2
    ss.timeIntegration.numberOfSteps = 200
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.01
    exl.SolveDynamic(mbs, ss, showProgress=False)
    return mbs.GetSensorStoredData(sens)


def test_frames_changed_during_a_solve_reach_the_probe(monkeypatch):
    probed = frames_moved(True)
    assert np.max(np.abs(probed - frames_moved(False))) > 1e-3      # the change matters
    python_path(monkeypatch)
    np.testing.assert_array_equal(probed, frames_moved(True))


def uf_coordinate_spring(mbs, t, itemNumber, u, v, k, d, offset):
    return k * (u - offset) * (1.0 + u * u) + d * v


def coordinate_items():
    """Coordinate items with user functions, probed by the compiled stage (``PROBE_COORD``): a
    mass point on a cubic spring to a ground coordinate and a load on another of its
    coordinates; two planar bodies spinning (over turns) with springs between their angles and
    between a position coordinate of each; a spring on a rotation parameter of an Rxyz node,
    which has no probe (it runs ``add``) next to them."""
    mbs = exu.SystemContainer().AddSystem()
    ng = mbs.AddNode(ii.NodePointGround())
    n1 = mbs.AddNode(ii.NodePoint(referenceCoordinates=[0.5, 0, 0], initialVelocities=[0.3, -0.2, 0.1]))
    mbs.AddObject(ii.MassPoint(mass=1.6, nodeNumber=n1))
    mg = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    m10 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=n1, coordinate=0))
    m11 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=n1, coordinate=1))
    mbs.AddObject(ii.CoordinateSpringDamper(markerNumbers=[mg, m10], stiffness=400.0, damping=0.4, offset=0.1,
                                            springForceUserFunction=uf_coordinate_spring))
    mbs.AddLoad(ii.LoadCoordinate(markerNumber=m11, load=2.0,
                                  loadUserFunction=lambda mbs, t, load: load * np.sin(7 * t)))
    coords = []
    for x, w in ((1.0, 9.0), (2.0, 11.0)):
        n = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[x, 0, 0.3], initialVelocities=[0, 0.1, w]))
        mbs.AddObject(ii.ObjectRigidBody2D(mass=2.0, inertia=0.05, nodeNumber=n))
        coords.append([mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=n, coordinate=c)) for c in range(3)])
    mbs.AddObject(ii.CoordinateSpringDamper(markerNumbers=[coords[0][2], coords[1][2]], stiffness=1e-3, damping=1e-4,
                                            springForceUserFunction=uf_coordinate_spring))
    mbs.AddObject(ii.CoordinateSpringDamper(markerNumbers=[coords[0][0], coords[1][1]], stiffness=50.0, damping=0.1,
                                            offset=-1.0, springForceUserFunction=uf_coordinate_spring))
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.1, 0.2, 0.3]), referencePosition=[0, 2, 0],
                            nodeType=exu.NodeType.RotationRxyz, initialAngularVelocity=[0.4, 0.2, 1.0])
    nb = mbs.GetObject(b)["nodeNumber"]
    mr = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=nb, coordinate=5))
    mbs.AddObject(ii.CoordinateSpringDamper(markerNumbers=[mg, mr], stiffness=0.5, damping=0.01,
                                            springForceUserFunction=uf_coordinate_spring))
    mbs.Assemble()
    return mbs


def test_probed_coordinate_items_integrate_as_the_python_items(monkeypatch):
    probed, items = integrate(coordinate_items(), steps=2000)
    springs = [it for it in items if isinstance(it, pyforces_coordinates.CoordinateSpringDamperUF)]
    assert [it.probeIndex is not None for it in springs] == [True, True, True, False]     # the last: Rxyz
    assert abs(springs[1].A.prev) > 4 * np.pi and abs(springs[1].B.prev) > 4 * np.pi     # tracked over turns
    python_path(monkeypatch)
    python, _ = integrate(coordinate_items(), steps=2000)
    assert np.all(np.isfinite(probed))
    np.testing.assert_array_equal(probed, python)

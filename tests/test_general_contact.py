"""``GeneralContact`` on the Exudyn-evaluated path (bridge/general_contact.py): the contact law of
Exudyn's explicit solvers (a full contact search at every evaluation), against Exudyn's own RK44 at
the same step (the same tableau: the same law gives the same run) and against generalized-alpha
at a fine step; a distance sensor that casts its ray into the contact's search tree gives native's
values."""
import warnings

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import InertiaSphere, MarkerBodyRigid

import exudyn_lie as exl

T = 0.3


def ball_on_sphere(mu=0.3, sensor=False):
    """A ball (r = 0.1, 1 kg) dropped off-centre onto a fixed sphere (r = 0.2) of a GeneralContact,
    with friction and spin: it bounces and slides off, so contacts close and open during steps."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    b = mbs.CreateRigidBody(inertia=InertiaSphere(1.0, 0.1), referencePosition=[0.05, 0, 0.35],
                            initialVelocity=[0.3, 0.1, 0], initialAngularVelocity=[0, 2.0, 1.0],
                            gravity=[0, 0, -9.81], nodeType=exu.NodeType.RotationRotationVector)
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))
    gc = mbs.AddGeneralContact()
    gc.SetFrictionPairings(mu * np.eye(1))
    gc.SetSearchTreeCellSize(numberOfCells=[4, 4, 4])
    gc.SetSearchTreeBox([-1, -1, -1], [1, 1, 1])
    gc.AddSphereWithMarker(mG, radius=0.2, contactStiffness=1e5, contactDamping=10.0, frictionMaterialIndex=0)
    gc.AddSphereWithMarker(mB, radius=0.1, contactStiffness=1e5, contactDamping=10.0, frictionMaterialIndex=0)
    s = None
    if sensor:      # a ray from above the ball downwards: it hits the ball, which moves along x
        s = mbs.CreateDistanceSensor(mbs.NumberOfGeneralContacts() - 1, positionOrMarker=[0.1, 0.0, 1.0],
                                     dirSensor=[0, 0, -1], minDistance=0,
                                     maxDistance=2.0, measureVelocity=True, storeInternal=True)
    mbs.Assemble()
    return mbs, s


def settings(h):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.01
    return ss


def run(h, solver, sensor=False, **kw):
    mbs, s = ball_on_sphere(sensor=sensor)
    ss = settings(h)
    if solver == "exl":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
    else:
        exu.SolveDynamic(mbs, ss, solverType=solver)
    q = np.array(mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Current))
    return q, (mbs.GetSensorStoredData(s) if sensor else None), mbs


@pytest.fixture(scope="module")
def reference():
    return run(1e-6, exu.DynamicSolverType.GeneralizedAlpha)[0]


def test_the_compiled_path_refuses_general_contact_and_auto_takes_the_evaluated_path():
    mbs, _ = ball_on_sphere()
    with pytest.raises(exl.BridgeError, match=r"GeneralContact.*evaluation='auto'"):
        exl.SolveDynamic(mbs, settings(1e-4), showProgress=False, evaluation="compiled")
    with pytest.warns(RuntimeWarning, match=r"GeneralContact"):
        exl.SolveDynamic(mbs, settings(1e-4), showProgress=False)
    assert mbs.sys["lieGroupSolver"].pathName == "evaluated"


def test_ball_on_a_sphere_is_exudyn_rk44s_run_and_converges(reference):
    """MK-RK4 at h = 1e-4 is Exudyn's RK44 at the same step (the same tableau on a node whose
    rotation is a Lie group coordinate: the same stages; the law of the explicit solvers): agreement
    to 1e-8 asserted (the difference is printed; the contact's on/off switches could amplify
    round-off).  Both are within 2e-4 of generalized-alpha at 1e-6 s, as is exudyn_lie's default (no
    method named)."""
    q, _, mbs = run(1e-4, "exl", method="RK4")
    qn, _, _ = run(1e-4, exu.DynamicSolverType.RK44)
    assert mbs.sys["lieGroupSolver"].pathName == "evaluated"
    print(f"ball on a sphere, h = 1e-4: exudyn_lie RK4 - Exudyn RK44 {np.abs(q - qn).max():.2e}; "
          f"against generalized-alpha at 1e-6 s: {np.abs(q - reference).max():.2e} and "
          f"{np.abs(qn - reference).max():.2e}")
    assert np.abs(q - qn).max() < 1e-8, np.abs(q - qn).max()
    assert np.abs(q - reference).max() < 2e-4
    assert np.abs(qn - reference).max() < 2e-4
    qd, _, _ = run(1e-4, "exl")
    assert np.abs(qd - reference).max() < 2e-4


def test_a_distance_sensor_reads_the_contact_geometry_as_natively():
    """CreateDistanceSensor casts a ray into the GeneralContact's search tree (its sensor user
    function, ShortestDistanceAlongLine): the distance and its rate at the outputs as Exudyn's RK44
    records them at the same step."""
    _, d, _ = run(1e-4, "exl", sensor=True, method="RK4")
    _, dn, _ = run(1e-4, exu.DynamicSolverType.RK44, sensor=True)
    assert d.shape == dn.shape and d.shape[0] == 31
    assert np.ptp(dn[:, 1]) > 0.1                    # the ball passes below the ray and leaves it
    np.testing.assert_allclose(d, dn, rtol=0, atol=1e-8)

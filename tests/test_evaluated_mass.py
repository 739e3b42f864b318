"""The Exudyn-evaluated path evaluates a constant mass matrix once (bridge/evaluated.py,
``mass_force_jacobian``), as Exudyn's own solvers do with ``timeIntegration.reuseConstantMassMatrix``:
which bodies declare a constant one (evaluated_items.constant_mass_matrix, Exudyn's
``HasConstantMassMatrix``), and that the run is the same bit for bit as with M at every stage."""
import warnings

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import InertiaSphere, NodeGenericODE2, ObjectGenericODE2

import exudyn_lie as exl
from exudyn_lie.bridge.evaluated_items import constant_mass_matrix


def model(node=exu.NodeType.RotationRotationVector, com=(0, 0, 0), generic=True):
    """A rigid body hanging on a spring-damper from the ground, and a GenericODE2 oscillator (the
    foreign item that makes Exudyn evaluate the model)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    inertia = InertiaSphere(1.0, 0.1)
    inertia.com = np.array(com, float)
    b = mbs.CreateRigidBody(inertia=inertia, referencePosition=[0.3, 0, 0], initialAngularVelocity=[1, 2, 3],
                            gravity=[0, -9.81, 0], nodeType=node)
    mbs.CreateSpringDamper(bodyNumbers=[ground, b], localPosition1=[0.05, 0, 0], stiffness=1e3, damping=1.0)
    if generic:
        n = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=2, referenceCoordinates=[0, 0],
                                        initialCoordinates=[0.1, 0], initialCoordinates_t=[0, 0]))
        mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=np.diag([1.0, 2.0]),
                                        stiffnessMatrix=np.array([[100.0, -10.0], [-10.0, 50.0]]),
                                        dampingMatrix=np.zeros((2, 2))))
    mbs.Assemble()
    return mbs


def test_which_mass_matrices_are_constant():
    assert constant_mass_matrix(model())
    assert not constant_mass_matrix(model(com=(0.01, 0, 0)))                 # COM off the node
    assert not constant_mass_matrix(model(node=exu.NodeType.RotationEulerParameters))


@pytest.mark.parametrize("node", [exu.NodeType.RotationRotationVector, exu.NodeType.RotationEulerParameters])
def test_the_run_is_the_same_with_m_once_and_m_at_every_stage(node):
    out = []
    for reuse in (True, False):
        mbs = model(node=node)
        ss = exu.SimulationSettings()
        ss.timeIntegration.endTime = 0.2
        ss.timeIntegration.numberOfSteps = 200
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.timeIntegration.reuseConstantMassMatrix = reuse
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, showProgress=False, method="RK4")
        m = mbs.sys["lieGroupSolver"].model
        assert m.constantMass == (reuse and node == exu.NodeType.RotationRotationVector)
        out.append(np.array(mbs.systemData.GetODE2Coordinates()))
    assert np.array_equal(out[0], out[1])


def test_a_model_too_large_for_exudyns_dense_interface_is_refused_clearly():
    """150,000 coordinates (Exudyn's particlesTest3D2.py): the dense copies of M would take 168 GiB."""
    from exudyn_lie.bridge.evaluated import check_dense_size
    with pytest.raises(exl.BridgeError, match=r"150000 ODE2 coordinates.*densely, 168 GiB"):
        check_dense_size(150000, 0)
    check_dense_size(1200, 0)

"""Shared pieces of the bridge tests: Exudyn model builders and the Exudyn oracle.

(No tests here; the other ``test_bridge_*`` files import it.)

``oracle(mbs, q, q_t, t)`` returns Exudyn's own M, f (ODE2 RHS = applied - gyroscopic
forces), g and C_q at a state; ``package(mbs, groups, q, q_t, t)`` the package's M, Q,
h, J at the same state, and ``P`` / ``PdotV`` such that Exudyn's velocity coordinates
are ``q_t = P V`` (V the package's group velocities).  Then, exactly,

    M_pkg = P^T M_exu P,   Q_pkg = P^T (f_exu - M_exu PdotV),   J_pkg = C_exu P.
"""
import warnings

import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaCuboid, MarkerBodyPosition, MarkerBodyRigid, MarkerNodePosition, MarkerNodeRigid

from exudyn_lie.bridge import SceneFromExudyn
from exudyn_lie.mbs import Simulator, kernel
from exudyn_lie.mbs.state import BodyStates
from exudyn_lie.mbs.codes import BODY_TWIST

warnings.simplefilter("ignore", DeprecationWarning)

NODE_TYPES = {"RotVecLG": exu.NodeType.RotationRotationVector, "EP": exu.NodeType.RotationEulerParameters,
              "Rxyz": exu.NodeType.RotationRxyz}
CUR = exu.ConfigurationType.Current
INI = exu.ConfigurationType.Initial


def quiet_settings(endTime=1.0, nsteps=10):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = endTime
    ss.timeIntegration.numberOfSteps = nsteps
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.active = False
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    return ss


_CONTAINERS = []


def new_mbs():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _CONTAINERS.append(SC)          # keep the container alive with mbs
    del _CONTAINERS[:-20]
    return mbs


def double_pendulum(swinging=False):
    """The README's double pendulum (two 1 m bars on revolute joints about z, gravity -y; Exudyn's
    default EP nodes), at rest or ``swinging`` (2 rad/s, the tips at 1 and 3 m/s)."""
    mbs = new_mbs()
    ground = mbs.CreateGround()
    inertia = InertiaCuboid(density=1000, sideLengths=[1, 0.1, 0.1])
    prev = ground
    for i in range(2):
        kw = dict(initialAngularVelocity=[0, 0, 2.0], initialVelocity=[0, 1.0 + 2 * i, 0]) if swinging else {}
        b = mbs.CreateRigidBody(inertia=inertia, referencePosition=[0.5 + i, 0, 0], gravity=[0, -9.81, 0], **kw)
        mbs.CreateRevoluteJoint(itemNumbers=[prev, b], position=[i, 0, 0], axis=[0, 0, 1])
        prev = b
    mbs.Assemble()
    return mbs


def add_body(mbs, nodeType, position, R0, omega=(0.3, -0.2, 0.5), vel=(0.1, 0.2, -0.1), com=(0.1, 0.02, -0.03),
             sides=(0.4, 0.1, 0.2), gravity=None):
    inert = InertiaCuboid(density=1000, sideLengths=list(sides)).Translated(list(com))
    kw = dict(gravity=list(gravity)) if gravity is not None else {}
    return mbs.CreateRigidBody(inertia=inert, referencePosition=list(position), referenceRotationMatrix=R0,
                               nodeType=NODE_TYPES[nodeType], initialAngularVelocity=list(omega),
                               initialVelocity=list(vel), **kw)


def body_frame(mbs, obj):
    """(r, R) of a rigid body or ground object in the current configuration."""
    d = mbs.GetObject(obj)
    if d["objectType"] == "Ground":
        return np.asarray(d["referencePosition"], float), np.asarray(d["referenceRotation"], float)
    n = d["nodeNumber"]
    O = exu.OutputVariableType
    return (np.asarray(mbs.GetNodeOutput(n, O.Position, configuration=exu.ConfigurationType.Reference)),
            np.asarray(mbs.GetNodeOutput(n, O.RotationMatrix, configuration=exu.ConfigurationType.Reference)).reshape(3, 3))


def rigid_marker(mbs, obj, p_world, R_world, markerRot=np.eye(3), node=False):
    """A rigid marker on obj at world point p_world; returns (marker, rotationMarker) so
    that (body rotation) @ markerRot @ rotationMarker = R_world initially."""
    r, R = body_frame(mbs, obj)
    local = R.T @ (np.asarray(p_world, float) - r)
    if node:
        n = mbs.GetObject(obj)["nodeNumber"]
        assert np.allclose(local, 0), "node markers sit at the node"
        m = mbs.AddMarker(MarkerNodeRigid(nodeNumber=n, localHT=exu.HT(rotation=markerRot, translation=[0, 0, 0])))
    else:
        m = mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localHT=exu.HT(rotation=markerRot, translation=local)))
    return m, (R @ markerRot).T @ R_world


def position_marker(mbs, obj, p_world, node=False):
    r, R = body_frame(mbs, obj)
    if node:
        return mbs.AddMarker(MarkerNodePosition(nodeNumber=mbs.GetObject(obj)["nodeNumber"]))
    return mbs.AddMarker(MarkerBodyPosition(bodyNumber=obj, localPosition=list(R.T @ (np.asarray(p_world) - r))))


def box_on_spherical_joint(mbs, nodeType, R0, omega, com, sides=(0.4, 0.1, 0.2)):
    """TestModels style: a box (offset COM, gravity -z, no initial translation) on a spherical joint
    at its node to the ground, and a NodePointGround for coordinate items; returns (its node, the
    ground node)."""
    from exudyn.utilities import NodePointGround, ObjectGround, ObjectJointSpherical
    b = add_body(mbs, nodeType, [0, 0, 0], R0, omega=omega, vel=(0, 0, 0), com=com, sides=sides,
                 gravity=(0, 0, -9.81))
    n = mbs.GetObject(b)["nodeNumber"]
    g = mbs.AddObject(ObjectGround())
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                                      mbs.AddMarker(MarkerNodeRigid(nodeNumber=n))]))
    return n, mbs.AddNode(NodePointGround())


def random_state(mbs, rng, scale=0.4):
    """Random current coordinates/velocities: unit Euler parameters, tangent ep_t."""
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates(configuration=INI))
    qt = np.array(sd.GetODE2Coordinates_t(configuration=INI))
    q = q + scale * rng.standard_normal(q.shape)
    qt = rng.standard_normal(qt.shape)
    for n in range(sd.NumberOfNodes()):
        d = mbs.GetNode(n)
        if d["nodeType"] == "RigidBodyEP":
            idx = np.asarray(sd.GetNodeLTGODE2(n))[3:]
            ref = np.asarray(d["referenceCoordinates"])[3:]
            ep = ref + q[idx]
            ep /= np.linalg.norm(ep)
            q[idx] = ep - ref
            qt[idx] -= ep * (ep @ qt[idx])
    return q, qt


# ---------------------------------------------------------------------------- oracle
def oracle(mbs, q, qt, t=0.0):
    sd = mbs.systemData
    ss = quiet_settings()
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, ss)
    n2 = solver.GetODE2size()
    nae = solver.GetAEsize()
    sd.SetODE2Coordinates(q, configuration=CUR)
    sd.SetODE2Coordinates_t(qt, configuration=CUR)
    if nae:
        sd.SetAECoordinates(np.zeros(nae), configuration=CUR)
    sd.SetTime(t)
    solver.ComputeMassMatrix(mbs)
    M = np.array(solver.GetSystemMassMatrix())[:n2, :n2].copy()
    solver.ComputeODE2RHS(mbs)
    f = np.array(solver.GetSystemResidual())[:n2].copy()
    g = np.zeros(0)
    C = np.zeros((0, n2))
    if nae:
        solver.ComputeAlgebraicEquations(mbs)
        g = np.array(solver.GetSystemResidual())[n2:n2 + nae].copy()
        # ComputeJacobianAE adds into the system Jacobian: zero it first
        solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=0., scalarFactor_ODE1=0.)
        solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=1., scalarFactor_ODE2_t=0., scalarFactor_ODE1=1.,
                                 velocityLevel=False)
        C = np.array(solver.GetSystemJacobian())[n2:n2 + nae, :n2].copy()
    solver.FinalizeSolver(mbs, ss)
    return M, f, g, C


def package(mbs, groups, q, qt, t=0.0):
    """Package M, Q, h, J at the Exudyn state (q, qt) and the maps P, PdotV."""
    sc = SceneFromExudyn(mbs, "initial")
    sim = Simulator(sc, "RK4", groups, projectInitial=True)
    nb = sc.nBodies
    n2 = len(q)
    R = np.zeros((nb, 3, 3))
    r = np.zeros((nb, 3))
    om = np.zeros((nb, 3))
    vel = np.zeros((nb, 3))
    P = np.zeros((n2, 6 * nb))
    PdV = np.zeros(n2)
    for kind, bodies in zip(sc.nodeKinds, sc.kindBodies):
        R[bodies], r[bodies], om[bodies], vel[bodies] = kind.read(q, qt)
        T = kind.velocity_map(q)
        Td = kind.velocity_map_dot(q, qt)
        for k, b in enumerate(bodies):
            D = np.eye(6)
            if BODY_TWIST[sim.gid[b]]:
                D[3:, 3:] = R[b]
            P[np.ix_(kind.idx[k], range(6 * b, 6 * b + 6))] = T[k] @ D
            PdV[kind.idx[k]] = Td[k]
    sim.SetInitialState(R, r, om, vel, t0=t)
    V = sim.V
    for b in range(nb):
        if BODY_TWIST[sim.gid[b]]:
            vb = V[b, 3:]
            kind_i = [(kd, list(bs).index(b)) for kd, bs in zip(sc.nodeKinds, sc.kindBodies) if b in bs][0]
            kd, k = kind_i
            PdV[kd.idx[k]] += kd.velocity_map(q)[k] @ np.r_[np.zeros(3), R[b] @ np.cross(V[b, :3], vb)]
    # mass matrix
    M = np.zeros((6 * nb, 6 * nb))
    for b in range(nb):
        Mb = sim.sd.M[b]
        if not BODY_TWIST[sim.gid[b]]:
            D = np.eye(6)
            D[3:, 3:] = R[b]
            Mb = D @ Mb @ D.T
        M[6 * b:6 * b + 6, 6 * b:6 * b + 6] = Mb
    # forces (compiled + Python callbacks)
    Q = np.zeros((nb, 6))
    kernel.compute_forces(sim.sd, sim.wk, t, sim.R, sim.r, sim.V, Q)
    st = BodyStates(t, sim.R.copy(), sim.r.copy(), om, vel)
    for pf in sc.pythonForces:
        F, T = pf.fn(t, st)
        for b in range(nb):
            kernel.add_point_force(int(sim.gid[b]), sim.R[b], np.zeros(3), np.asarray(F[b], float), Q[b])
            kernel.add_world_torque(sim.R[b], np.asarray(T[b], float), Q[b])
    for b in range(nb):
        if sc.bodies[b].isPoint:        # a point mass: only its free translations are coordinates
            Q[b, :3] = 0.0
            Q[b, 3:] = sc.bodies[b].freeDirections @ Q[b, 3:]
    h, J, eta = sim.jacobian()
    for b in range(nb):
        if sc.bodies[b].isPoint:        # only the free directions of a point mass are velocity coordinates
            J[:, 6 * b + 3:6 * b + 6] = J[:, 6 * b + 3:6 * b + 6] @ sc.bodies[b].freeDirections
    return dict(M=M, Q=Q.reshape(-1), h=h, J=J, P=P, PdV=PdV, sim=sim, scene=sc)


def compare(mbs, groups, q, qt, t=0.0):
    """Max relative deviations (M, f, g, J) between package and Exudyn at (q, qt)."""
    Me, fe, ge, Ce = oracle(mbs, q, qt, t)
    pk = package(mbs, groups, q, qt, t)
    P, PdV = pk["P"], pk["PdV"]
    Mx = P.T @ Me @ P
    fx = P.T @ (fe - Me @ PdV)

    def rel(a, b):
        return float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))) if np.size(b) else 0.0

    # Exudyn's coordinates span the package's velocity axes that P reaches: all six for a 3D
    # body, (omega_z, v_x, v_y) for a 2D body (whose off-plane entries never act)
    ax = np.nonzero(np.any(P != 0, axis=0))[0]
    Mx, fx, P = Mx[np.ix_(ax, ax)], fx[ax], P[:, ax]
    pk = dict(pk, M=pk["M"][np.ix_(ax, ax)], Q=pk["Q"][ax], J=pk["J"][:, ax])
    out = dict(M=rel(pk["M"], Mx), f=rel(pk["Q"], fx), g=0.0, J=0.0, nrows=0)
    sim, sc = pk["sim"], pk["scene"]
    for ji in sc.joints_info:
        r0, n = (int(x) for x in sim.sd.jointIndex[ji.sceneJoint, 2:4])
        rows = np.arange(r0, r0 + n)
        out["g"] = max(out["g"], rel(pk["h"][rows], ge[ji.aeRows]))
        out["J"] = max(out["J"], rel(pk["J"][rows], Ce[ji.aeRows] @ P))
        out["nrows"] += n
    out["fvals"] = (pk["Q"], fx)
    return out

"""Node registry: rotation parametrisations, read / write both ways, continuity, and
Exudyn's own outputs of the written coordinates."""
import numpy as np
import pytest

import exudyn as exu
from exudyn import rigidBodyUtilities as rbu

from exudyn_lie.bridge import NODE_KINDS, EPNode, RotVecLGNode, RxyzNode
from exudyn_lie.bridge import rotations as rot
from exudyn_lie.groups import so3

from node_writer import write
from test_bridge_common import NODE_TYPES, add_body, new_mbs

O = exu.OutputVariableType
CUR = exu.ConfigurationType.Current


def rand_rot(rng, scale=1.5):
    return so3.exp(rng.normal(size=3) * scale)


# ---------------------------------------------------------------------------- parametrisations
def test_rotation_parametrisations_match_exudyn(rng):
    for _ in range(20):
        th = rng.normal(size=3) * 1.2
        np.testing.assert_allclose(rot.rotvec_to_matrix(th)[0], rbu.RotationVector2RotationMatrix(th), atol=1e-14)
        R = rot.rotvec_to_matrix(th)[0]
        ep = rot.matrix_to_quaternion(R)[0]
        ep_exu = rbu.RotationMatrix2EulerParameters(R)
        assert min(np.abs(ep - ep_exu).max(), np.abs(ep + ep_exu).max()) < 1e-14
        np.testing.assert_allclose(rot.ep_to_matrix(ep)[0], rbu.EulerParameters2RotationMatrix(ep), atol=1e-14)
        np.testing.assert_allclose(rot.ep_glocal(ep)[0], rbu.EulerParameters2GLocal(ep), atol=1e-14)
        a = rng.uniform(-3, 3, 3)
        np.testing.assert_allclose(rot.rxyz_to_matrix(a)[0], rbu.RotXYZ2RotationMatrix(a), atol=1e-14)
        np.testing.assert_allclose(rot.rxyz_glocal(a)[0], rbu.RotXYZ2GLocal(a), atol=1e-14)
        cand = rot.matrix_to_rxyz_candidates(rot.rxyz_to_matrix(a))[0]
        for c in cand:
            np.testing.assert_allclose(rot.rxyz_to_matrix(c)[0], rot.rxyz_to_matrix(a)[0], atol=1e-14)
        np.testing.assert_allclose(cand[0], rbu.RotationMatrix2RotXYZ(rot.rxyz_to_matrix(a)[0]), atol=1e-12)
        # log: exact at and near pi and 0
        for t in (np.pi, np.pi - 1e-9, 1e-9, 0.0):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            th2 = rot.matrix_to_rotvec(rot.rotvec_to_matrix(t * n))[0]
            np.testing.assert_allclose(rot.rotvec_to_matrix(th2)[0], rot.rotvec_to_matrix(t * n)[0], atol=1e-14)
    # GRdot by central differences
    a, at = rng.normal(size=3), rng.normal(size=3)
    e = 1e-6
    fd = (rot.rxyz_glocal(a + e * at) - rot.rxyz_glocal(a - e * at)) / (2 * e)
    np.testing.assert_allclose(rot.rxyz_glocal_dot(a, at), fd, atol=1e-9)


# ---------------------------------------------------------------------------- write -> Exudyn outputs
def one_body(nodeType, R0=np.eye(3), omega=(0.1, 0.2, 0.3)):
    mbs = new_mbs()
    b = add_body(mbs, nodeType, [1, 2, 3], R0, omega=omega)
    mbs.Assemble()
    n = mbs.GetObject(b)["nodeNumber"]
    sd = mbs.systemData
    kind = NODE_KINDS[mbs.GetNode(n)["nodeType"]]([n], [sd.GetNodeLTGODE2(n)], [mbs.GetNode(n)["referenceCoordinates"]])
    return mbs, b, n, kind


@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_written_coordinates_give_the_same_exudyn_outputs(node, rng):
    """write (R, r, omega, vel, omegadot, acc) -> Exudyn's Position, RotationMatrix, Velocity,
    AngularVelocity(Local), Acceleration, AngularAcceleration(Local) and body outputs."""
    mbs, b, n, kind = one_body(node, R0=rand_rot(rng))
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates())
    qt = np.array(sd.GetODE2Coordinates_t())
    qtt = np.array(sd.GetODE2Coordinates_tt())
    kind.read(q, qt)
    for _ in range(10):
        R = rand_rot(rng, 0.8)
        r, om, vel, omd, acc = (rng.normal(size=3) for _ in range(5))
        write(kind, R[None], r[None], om[None], vel[None], omd[None], acc[None], q=q, q_t=qt, q_tt=qtt)
        sd.SetODE2Coordinates(q, configuration=CUR)
        sd.SetODE2Coordinates_t(qt, configuration=CUR)
        sd.SetODE2Coordinates_tt(qtt, configuration=CUR)
        g = lambda v: np.asarray(mbs.GetNodeOutput(n, v))
        np.testing.assert_allclose(g(O.Position), r, atol=1e-13)
        np.testing.assert_allclose(g(O.RotationMatrix).reshape(3, 3), R, atol=1e-13)
        np.testing.assert_allclose(g(O.Velocity), vel, atol=1e-13)
        np.testing.assert_allclose(g(O.AngularVelocityLocal), om, atol=1e-12)
        np.testing.assert_allclose(g(O.AngularVelocity), R @ om, atol=1e-12)
        np.testing.assert_allclose(g(O.Acceleration), acc, atol=1e-12)
        gb = lambda v: np.asarray(mbs.GetObjectOutputBody(b, v, localPosition=[0, 0, 0]))
        np.testing.assert_allclose(gb(O.AngularAccelerationLocal), omd, atol=1e-11)
        np.testing.assert_allclose(gb(O.AngularAcceleration), R @ omd, atol=1e-11)
        # a body point
        s = np.array([0.2, -0.1, 0.05])
        np.testing.assert_allclose(mbs.GetObjectOutputBody(b, O.Position, localPosition=s), r + R @ s, atol=1e-13)
        np.testing.assert_allclose(mbs.GetObjectOutputBody(b, O.Velocity, localPosition=s),
                                   vel + R @ np.cross(om, s), atol=1e-12)
        # and back
        R2, r2, om2, vel2 = kind.read(q, qt)
        np.testing.assert_allclose(R2[0], R, atol=1e-13)
        np.testing.assert_allclose(om2[0], om, atol=1e-12)


@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_read_matches_exudyn_outputs_of_initial_values(node, rng):
    mbs, b, n, kind = one_body(node, R0=rand_rot(rng), omega=rng.normal(size=3))
    sd = mbs.systemData
    R, r, om, vel = kind.read(np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t()))
    g = lambda v: np.asarray(mbs.GetNodeOutput(n, v))
    np.testing.assert_allclose(R[0], g(O.RotationMatrix).reshape(3, 3), atol=1e-14)
    np.testing.assert_allclose(r[0], g(O.Position), atol=1e-14)
    np.testing.assert_allclose(om[0], g(O.AngularVelocityLocal), atol=1e-13)
    np.testing.assert_allclose(vel[0], g(O.Velocity), atol=1e-14)


@pytest.mark.parametrize("cls", [RotVecLGNode, EPNode, RxyzNode])
def test_compiled_rates_equal_numpy_maps(cls, rng):
    """The compiled writer's p_t, p_tt equal the numpy maps (independent code), and
    p_tt is the time derivative of p_t along a motion (finite differences)."""
    nq = 3 + cls.nrot
    kind = cls([0], [np.arange(nq)], [np.zeros(nq)])
    q, qt, qtt = np.zeros(nq), np.zeros(nq), np.zeros(nq)
    w0, w1 = rng.normal(size=3), rng.normal(size=3)

    def motion(t):          # R(t) = exp(t w0 + t^2 w1 / 2) R0 -> omega via finite differences
        return so3.exp(t * w0 + 0.5 * t * t * w1) @ so3.exp(np.array([0.3, 0.2, 0.1]))

    def omega(t, e=1e-6):
        Rd = (motion(t + e) - motion(t - e)) / (2 * e)
        W = motion(t).T @ Rd
        return np.array([W[2, 1], W[0, 2], W[1, 0]])

    t0, e = 0.4, 1e-4
    kind.first = True
    write(kind, motion(t0 - e)[None], np.zeros((1, 3)), omega(t0 - e)[None], np.zeros((1, 3)), q=q, q_t=qt)
    pt_m = qt[3:].copy()
    omd = (omega(t0 + 1e-5) - omega(t0 - 1e-5)) / 2e-5
    write(kind, motion(t0)[None], np.zeros((1, 3)), omega(t0)[None], np.zeros((1, 3)), omd[None],
               np.zeros((1, 3)), q=q, q_t=qt, q_tt=qtt)
    p, pt, ptt = q[3:].copy(), qt[3:].copy(), qtt[3:].copy()
    write(kind, motion(t0 + e)[None], np.zeros((1, 3)), omega(t0 + e)[None], np.zeros((1, 3)), q=q, q_t=qt)
    pt_p = qt[3:].copy()
    np.testing.assert_allclose(pt, kind.rate_from_omega(p[None], omega(t0)[None])[0], atol=1e-12)
    np.testing.assert_allclose(ptt, kind.rate2_from_omega(p[None], pt[None], omega(t0)[None], omd[None])[0],
                               atol=1e-10)
    np.testing.assert_allclose(ptt, (pt_p - pt_m) / (2 * e), atol=2e-5)


# ---------------------------------------------------------------------------- continuity
def _spin(kind, axis, angles, R0=np.eye(3)):
    q, qt = np.zeros(kind.idx.max() + 1), np.zeros(kind.idx.max() + 1)
    out = []
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    for a in angles:
        R = so3.exp(a * axis) @ R0
        p = write(kind, R[None], np.zeros((1, 3)), (axis * 1.0)[None], np.zeros((1, 3)), q=q, q_t=qt)
        out.append(p[0].copy())
        np.testing.assert_allclose(kind.rotation(p)[0], R, atol=1e-13)
    return np.array(out)


def test_rotvec_continuous_past_pi_and_bounded_below_2pi():
    kind = RotVecLGNode([0], [np.arange(6)], [np.zeros(6)])
    kind.first = True
    # oscillation about pi: no jump at all (Exudyn's principal vector would flip)
    ang = np.pi - 0.1 + 0.4 * np.sin(np.linspace(0, 20, 2001))
    p = _spin(kind, [1, 2, -1], ang)
    assert np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)) < 0.01
    assert np.max(np.abs(np.linalg.norm(p, axis=1) - ang)) < 1e-12
    # continuous spin over 3 turns: Exudyn's Lie group update (CompositionRotationVector)
    # composes quaternions and returns 2 acos(q0) qv / |qv| of the sign-continuous quaternion:
    # the vector is the angle wrapped to [-2 pi, 2 pi] along the axis, |theta| <= 2 pi, a jump
    # (of 4 pi, |theta| continuous) where it reaches 2 pi (tests/test_node_parameter_tracking:
    # against native runs)
    kind = RotVecLGNode([0], [np.arange(6)], [np.zeros(6)])
    kind.first = True
    ang = np.linspace(0, 5.9 * np.pi, 5901)
    axis = np.array([0.3, -1, 0.5]) / np.linalg.norm([0.3, -1, 0.5])
    p = _spin(kind, axis, ang)
    nrm = np.linalg.norm(p, axis=1)
    assert nrm.max() <= 2 * np.pi + 1e-12
    wrapped = ang - 4 * np.pi * np.round(ang / (4 * np.pi))
    inside = np.abs(np.abs(wrapped) - 2 * np.pi) > 1e-6
    np.testing.assert_allclose(p[inside], wrapped[inside, None] * axis, atol=1e-9)
    # at exactly 2 pi (sample 2000) the short vector ~0 is written (Exudyn 1.13.6 evaluates
    # |theta| > 2 pi wrongly, even by a rounding error; node_writers.ROTVEC_TURNOVER)
    assert np.linalg.norm(p[2000]) < 1e-8
    jumps = np.nonzero(np.linalg.norm(np.diff(p, axis=0), axis=1) > 0.01)[0]
    assert jumps.tolist() == [1999, 2000]


def test_rotvec_reference_plus_current():
    """Total = reference + current: the written current part is total - reference."""
    ref = np.array([1, 2, 3, 0.5, -0.4, 1.0])
    kind = RotVecLGNode([0], [np.arange(6)], [ref])
    q, qt = np.zeros(6), np.zeros(6)
    kind.read(q, qt)
    R = rot.rotvec_to_matrix(ref[3:] + np.array([0.1, 0.2, -0.1]))[0]
    write(kind, R[None], np.array([[1, 2, 3.5]]), np.zeros((1, 3)), np.zeros((1, 3)), q=q, q_t=qt)
    np.testing.assert_allclose(q, [0, 0, 0.5, 0.1, 0.2, -0.1], atol=1e-13)


def test_ep_sign_is_continuous():
    kind = EPNode([0], [np.arange(7)], [np.zeros(7)])
    kind.first = True
    p = _spin(kind, [1, 1, 0], np.linspace(0, 8 * np.pi, 4001))
    assert np.min(np.einsum("ij,ij->i", p[1:], p[:-1])) > 0.99
    # ep = -ep0 after one turn (2 pi), +ep0 after two: not reset to e0 >= 0
    assert p[1000, 0] < -0.99 and p[2000, 0] > 0.99


def test_rxyz_continuous_and_warns_near_singularity():
    kind = RxyzNode([0], [np.arange(6)], [np.zeros(6)])
    kind.first = True
    p = _spin(kind, [1, 0, 0], np.linspace(0, 6 * np.pi, 3001), R0=rot.rxyz_to_matrix([0.0, 0.4, 0.2])[0])
    assert np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)) < 0.02
    assert p[-1, 0] == pytest.approx(6 * np.pi, abs=1e-9)            # unwrapped, not reset to (-pi, pi]
    # a rotation about y through 90 deg: warning once, angles still continuous, R exact
    kind = RxyzNode([0], [np.arange(6)], [np.zeros(6)])
    kind.first = True
    with pytest.warns(RuntimeWarning, match="singularity of Rxyz") as rec:
        p = _spin(kind, [0, 1, 0], np.linspace(0, 2.5, 1001), R0=rot.rxyz_to_matrix([0.0, 0.0, -0.2])[0])
    assert sum("singularity" in str(w.message) for w in rec) == 1
    jumps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert np.sum(jumps > 0.1) <= 2          # at most the pass through the singular point itself


def test_ep_read_rejects_non_unit_parameters():
    from exudyn_lie.bridge import BridgeError
    kind = EPNode([5], [np.arange(7)], [np.array([0, 0, 0, 1.1, 0, 0, 0])])
    with pytest.raises(BridgeError, match="NodeRigidBodyEP 5.*norm 1.1"):
        kind.read(np.zeros(7), np.zeros(7))


def test_write_back_compiles_only_the_row_writers_of_its_nodes():
    """present_writers marks the row writers the nodes' codes need (the others are None, so
    the write-back compiles none of their code), and the per-node writer of the tests has all of them."""
    from exudyn_lie.bridge import node_writers as nodes
    from node_writer import ALL_WRITERS
    p = nodes.present_writers([nodes.CODE_EP, nodes.CODE_POINT, nodes.CODE_EP])
    assert [x is not None for x in p] == [c == nodes.CODE_EP for c in nodes.WRITER_CODES]
    assert all(x is not None for x in ALL_WRITERS)
    assert all(x is None for x in nodes.present_writers([nodes.CODE_POINT, nodes.CODE_1D]))

"""The implicit method's Newton Jacobian on the Exudyn-evaluated path from Exudyn's own Jacobians
(bridge/evaluated_jacobian.py) against the kernel's difference Jacobian of the stage right-hand side
(mbs/implicit.newton_jacobian) at the same state, and the run it gives against the run with
difference Jacobians only."""
import warnings

import exudyn as exu
import numpy as np

import exudyn_lie as exl
from exudyn_lie.apps.bench_stiff import build_cable
from exudyn_lie.bridge import evaluated_problem
from exudyn_lie.mbs.implicit import newton_arrays, newton_jacobian


def cable_run(h=1e-3, T=0.1, exudynJacobian=True, monkeypatch=None):
    """The ANCF cable with a pinned rigid 2D body of ``bench --sections stiff`` (RK4 is unstable at
    h = 1e-3: the drop-in takes ESDIRK3)."""
    if not exudynJacobian:
        monkeypatch.setattr(evaluated_problem, "jacobian_applies", lambda model: False)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    build_cable(mbs)
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, showProgress=False, constraintCheck=False)
    return mbs


def test_exudyns_jacobian_is_the_difference_jacobian_without_the_constraint_curvature(monkeypatch):
    """At the end state of a run: D_Theta from Exudyn's K agrees with the kernel's differences to
    1e-5 of its largest entry (3.5e9: the cable's axial stiffness over its mass) but for the
    columns the revolute joint's curvature and eta add to (left out by design); D_V is the
    differences' without eta's velocity terms (no damping in this model: zero)."""
    mbs = cable_run(monkeypatch=monkeypatch)
    pb = mbs.sys["lieGroupSolver"].problem
    assert pb.tableau.name == "ESDIRK3" and pb.jacobian is not None and pb.jacobian.evaluations > 0
    sim = pb.sim
    ours = newton_arrays(sim.gid)
    pb.jacobian.fill(ours, sim.t)
    fd = newton_arrays(sim.gid)
    st = newton_jacobian(sim.sd, sim.wk, fd, sim.t, sim.R, sim.r, sim.V, _rates(sim))
    assert st == 0
    Dth, Dth_fd = ours.Dth, fd.Dth
    scale = np.abs(Dth_fd).max()
    assert scale > 1e9
    err = np.abs(Dth - Dth_fd)
    cols = np.nonzero(err.max(axis=0) > 1e-5 * scale)[0]
    # the columns with larger differences: the coordinates at the joint (the cable's tip node and the body)
    assert len(cols) <= 6, cols
    assert np.abs(ours.Dv).max() == 0.0


def _rates(sim):
    """The stage right-hand side at the simulator's state (what newton_jacobian differences from)."""
    from exudyn_lie.mbs.stepper import copy_state, stage_rhs_at
    out = np.zeros_like(sim.V)
    copy_state(sim.R, sim.r, sim.V, sim.wk.Rs, sim.wk.rs, sim.wk.Vs)
    assert stage_rhs_at(sim.sd, sim.wk, sim.t, out) == 0
    return out


def test_the_run_is_the_run_with_difference_jacobians_at_fewer_evaluations(monkeypatch):
    """The Newton iteration converges to the stage's solution whatever its matrix: the end state is
    the one with the kernel's difference Jacobians to the Newton tolerance's accumulation, with fewer
    evaluations by Exudyn."""
    a = cable_run(monkeypatch=monkeypatch)
    pa = a.sys["lieGroupSolver"]
    na = pa.model.evaluations + 0
    qa = np.array(a.systemData.GetODE2Coordinates())
    with monkeypatch.context() as m:
        b = cable_run(exudynJacobian=False, monkeypatch=m)
    pbb = b.sys["lieGroupSolver"]
    assert pbb.problem.jacobian is None
    qb = np.array(b.systemData.GetODE2Coordinates())
    assert np.abs(qa - qb).max() < 1e-8, np.abs(qa - qb).max()
    print(f"evaluations: {na} with Exudyn's Jacobian, {pbb.model.evaluations} with differences")
    assert na < 0.8 * pbb.model.evaluations


def test_the_constrained_inverse_with_a_regular_and_a_singular_mass_matrix():
    """P = M^-1 - M^-1 C^T (C M^-1 C^T)^-1 C M^-1 for a regular M; a coordinate without mass that a
    row fixes (Exudyn's ballBearingTest.py, objectFFRFTest.py) gives P from the KKT matrix, and P
    maps any force to accelerations the rows allow (C P = 0)."""
    from exudyn_lie.bridge.evaluated_jacobian import ExudynNewtonJacobian
    rng = np.random.default_rng(1)
    n, m = 8, 3
    A = rng.standard_normal((n, n))
    M = A @ A.T + n * np.eye(n)
    C = rng.standard_normal((m, n))
    Mi = np.linalg.inv(M)
    P = ExudynNewtonJacobian._projector(M, C)
    assert np.allclose(P, Mi - Mi @ C.T @ np.linalg.solve(C @ Mi @ C.T, C @ Mi), rtol=0, atol=1e-14)
    M[0, :] = M[:, 0] = 0.0
    C2 = np.vstack([C, np.eye(n)[0]])
    P2 = ExudynNewtonJacobian._projector(M, C2)
    assert P2 is not None and np.abs(C2 @ P2).max() < 1e-12
    C[:, 0] = 0.0
    assert ExudynNewtonJacobian._projector(M, C) is None       # the massless coordinate held by nothing

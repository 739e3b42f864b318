"""Stability of an explicit step on the Exudyn-evaluated path (stiff items such as ANCF
cables at the script's step).

The equations linearised at a state, on the constraint manifold, are
``M_r x'' + D_r x' + K_r x = 0`` with ``K = -df/dq`` and ``D = -df/dv`` (Exudyn's
``ComputeJacobianODE2RHS``, loads included) reduced by ``N``, a basis of the null space of
``C_q`` (the motions the constraints allow): ``M_r = N^T M N`` etc.  Their eigenvalues
``lambda`` (of the first-order matrix ``[[0, I], [-M_r^-1 K_r, -M_r^-1 D_r]]``) must satisfy
``|R(h lambda)| <= 1`` with the method's stability polynomial ``R``
(:func:`~exudyn_lie.integrators.stability.stability_coefficients`, from the tableau's
coefficients); :func:`check_step` raises the StepSizeError of
:func:`~exudyn_lie.mbs.stiffness.check_linear_stability` before a run whose step is beyond the
largest such ``h`` (a blow-up during the run is the stepper's error, with the simulator's
suggestion).  With no or proportional damping the eigenvalues come from those of ``M_r^-1 K_r``
(:func:`modal_eigenvalues`); for the drop-in's own choice of its method (:func:`choice_step`, no
error) the largest modes by Arnoldi's iteration may decide first (:func:`dominant_eigenvalues`).  A mode whose stiffness appears only later (a contact that closes,
a regularised friction zone that is entered) is not seen at the initial state: the stages'
watch sees it in the ODE2 coordinates, :func:`ode1_rate` in the ODE1 coordinates
(docs/EVALUATED.md, Stiffness).
"""
from __future__ import annotations

import numpy as np

from ..integrators.partitioned import first_order_part
from ..integrators.stability import stability_radius
from ..mbs.stiffness import check_linear_stability, largest_stable_step
from .general_contact import general_contacts


def linear_eigenvalues(model, split=False):
    """Eigenvalues of the linearised, constrained equations at the state in mbs (with ``split``: those
    of the ODE2 coordinates and those of the ODE1 coordinates apart)."""
    MK, MD, ev1 = _linearised(model)
    ev = _second_order_eigenvalues(MK, MD)
    return (ev, ev1) if split else np.concatenate([ev, ev1])


def _linearised(model):
    """``(MK, MD, ev1)`` at the state in mbs: ``M_r^-1 K_r`` and ``M_r^-1 D_r`` on the motions the
    constraints allow (both None where there is no such motion, no stiffness nor damping, or M_r is
    singular), and the eigenvalues of the ODE1 coordinates' own Jacobian."""
    n = model.n
    M, f, Cq = model.mass_force_jacobian(model.sd.GetTime())
    M = np.array(M)
    Cq = None if Cq is None else np.array(Cq)
    K, D = model.force_jacobians(model.sd.GetTime())
    K, D = -K, -D                       # (the linearisation M q'' + D q' + K q = 0)
    ev1 = np.zeros(0, complex)
    n1 = model.n1
    if n1:
        # ODE1 coordinates: the eigenvalues of d(ydot)/dy by central differences of
        # ComputeODE1RHS (its analytic Jacobian is zero for ObjectGenericODE1 in Exudyn
        # 1.13.6); their coupling to the ODE2 coordinates is neglected here
        ev1 = np.linalg.eigvals(_ode1_jacobian(model))
        ev1 = ev1[np.isfinite(ev1)]
    if Cq is not None and Cq.shape[0]:
        Cq = Cq[np.any(Cq != 0.0, axis=1)]
    if Cq is not None and Cq.shape[0]:
        _, sv, vt = np.linalg.svd(Cq)
        rank = int(np.sum(sv > 1e-10 * max(sv.max(), 1e-300)))
        N = vt[rank:].T
    else:
        N = np.eye(n)
    k = N.shape[1]
    if k == 0 or not (np.any(K) or np.any(D)):
        return None, None, ev1
    Mr = N.T @ M @ N
    try:
        return np.linalg.solve(Mr, N.T @ K @ N), np.linalg.solve(Mr, N.T @ D @ N), ev1
    except np.linalg.LinAlgError:
        return None, None, ev1


def _second_order_eigenvalues(MK, MD, ev=None):
    """The finite eigenvalues of ``[[0, I], [-MK, -MD]]`` (none without MK): ``ev`` where given (those
    of :func:`modal_eigenvalues`), else those of :func:`modal_eigenvalues`, else numpy's of the whole
    matrix."""
    if MK is None:
        return np.zeros(0, complex)
    if ev is None:
        ev = modal_eigenvalues(MK, MD)
    if ev is None:
        k = MK.shape[0]
        A = np.zeros((2 * k, 2 * k))
        A[:k, k:] = np.eye(k)
        A[k:, :k] = -MK
        A[k:, k:] = -MD
        ev = np.linalg.eigvals(A)
    return ev[np.isfinite(ev)]


#: from this size of the first-order matrix on (2 k, k the motions the constraints allow), the choice of
#: the method tries the largest modes first: numpy's eigenvalues of all of them cost 0.23 to 0.33 s in
#: Exudyn's objectFFRFTest2.py, objectGenericODE2Test.py and linearFEMgenericODE2Test.py (2 k = 1,044)
KRYLOV_FROM = 200
#: what the drop-in's line adds when the largest modes alone decided (:func:`choice_step`)
KRYLOV_NOTE = ", its largest modes by Arnoldi's iteration (the stable step an upper bound)"


def dominant_eigenvalues(MK, MD, m=40, rtol=1e-8, seed=0):
    """Converged Ritz values of ``[[0, I], [-MK, -MD]]`` after ``m`` steps of Arnoldi's iteration
    (twice orthogonalised, a fixed random start): those whose residual, Arnoldi's ``|H[m, m-1] y_m|``
    plus that of the small eigenproblem itself, is at most ``rtol |theta|``.  Krylov spaces find the
    eigenvalues of largest modulus first, the ones that limit an explicit step.

    The iteration runs on the similar matrix ``[[0, s I], [-MK / s, -MD]]``, ``s = sqrt(|MK|)``: the
    matrix itself has a norm of omega^2 for eigenvalues of omega, and its rounding (eps omega^3 at
    the fast modes) had put accepted Ritz values 10 to 70 % off at omega = 1e9 (a helper's review,
    random models against numpy's eigenvalues); scaled, 1e-13."""
    k = MK.shape[0]
    n = 2 * k
    m = min(m, n)
    s = float(np.sqrt(np.abs(MK).sum(axis=1).max())) or 1.0
    V = np.zeros((n, m + 1))
    H = np.zeros((m + 1, m))
    z = np.random.default_rng(seed).standard_normal(n)
    V[:, 0] = z / np.linalg.norm(z)
    for j in range(m):
        x, v = V[:k, j], V[k:, j]
        w = np.concatenate([s * v, -(MK @ x) / s - (MD @ v)])
        for _ in range(2):
            c = V[:, :j + 1].T @ w
            w -= V[:, :j + 1] @ c
            H[:j + 1, j] += c
        H[j + 1, j] = np.linalg.norm(w)
        if not H[j + 1, j] > 1e-14 * np.linalg.norm(H[:j + 2, :j + 1]):
            m = j + 1                      # an invariant subspace (H[m, m-1] kept: the residual stays honest)
            break
        V[:, j + 1] = w / H[j + 1, j]
    theta, Y = np.linalg.eig(H[:m, :m])
    Y = Y / np.linalg.norm(Y, axis=0)
    res = np.abs(H[m, m - 1]) * np.abs(Y[m - 1, :]) + np.linalg.norm(H[:m, :m] @ Y - Y * theta, axis=0)
    ok = np.isfinite(theta) & (res <= rtol * np.abs(theta))
    return theta[ok]


def modal_eigenvalues(MK, MD, rtol=1e-6):
    """The eigenvalues of ``[[0, I], [-MK, -MD]]`` from those of ``MK`` alone where the damping is
    proportional, ``MD = a I + b MK`` (none, or Rayleigh's, as FEM models and Exudyn's GenericODE2
    objects give it), else None.  Checked entry by entry to ``rtol`` of MD's largest: Exudyn
    differentiates many items' forces numerically (an ObjectGenericODE2's Rayleigh damping came out
    5e-7 off, relative), so an exactly proportional damping shows only to about that; the
    eigenvalues then move by about the Jacobian's own error.  Each eigenvalue ``w2`` of MK
    gives the roots of ``lambda^2 + (a + b w2) lambda + w2 = 0``: one eigenvalue problem of size k
    instead of 2k, eight times less work (0.33 s of a 528-coordinate model's start in Exudyn's
    ``linearFEMgenericODE2Test.py``, its whole stability check but the set-up of MK)."""
    k = MK.shape[0]
    a = b = 0.0
    if np.any(MD):
        X = np.stack([np.eye(k).ravel(), MK.ravel()], axis=1)
        (a, b), *_ = np.linalg.lstsq(X, MD.ravel(), rcond=None)
        # relative to MD itself: near a multiple of I, MK lets a and b grow large and cancel
        if not np.max(np.abs(MD - a * np.eye(k) - b * MK)) <= rtol * float(np.max(np.abs(MD))):
            return None
    w2 = np.linalg.eigvals(MK).astype(complex)
    c = a + b * w2
    disc = np.sqrt(c * c - 4.0 * w2)
    disc = np.where((np.conj(c) * disc).real < 0.0, -disc, disc)     # |c + disc| the larger: no cancellation
    l1 = -0.5 * (c + disc)
    l2 = np.divide(w2, l1, out=np.zeros_like(l1), where=l1 != 0)      # (l1 = 0 only where c = w2 = 0)
    return np.concatenate([l1, l2])


def _ode1_jacobian(model, central=True):
    """d(ydot)/dy at the state in mbs by central differences of ComputeODE1RHS (2 n1 evaluations),
    or forward ones (n1 + 1: the watch during a run, evaluated_problem.EvaluatedProblem._ode1_rate)."""
    import exudyn as exu
    s, mbs, sd, n, n1 = model.solver, model.mbs, model.sd, model.n, model.n1
    cur = exu.ConfigurationType.Current
    y0 = np.array(sd.GetODE1Coordinates(configuration=cur), float)

    def rates(y):
        sd.SetODE1Coordinates(y, configuration=cur)
        s.ComputeODE1RHS(mbs)
        return np.array(s.GetSystemResidual()[n:n + n1])
    J = np.zeros((n1, n1))
    base = None if central else rates(y0)
    for k in range(n1):
        d = 1e-6 * max(1.0, abs(y0[k]))
        y = y0.copy()
        y[k] += d
        plus = rates(y)
        if central:
            y[k] -= 2 * d
            J[:, k] = (plus - rates(y)) / (2 * d)
        else:
            J[:, k] = (plus - base) / d
    sd.SetODE1Coordinates(y0, configuration=cur)
    return J


def ode1_rate(model, tableau, h, radius):
    """The rate of the ODE1 coordinates' own modes (the eigenvalues ``lambda`` of d(ydot)/dy at the
    state in mbs, the mechanical state held) for ``tableau``'s stability ``radius`` at the step ``h``:
    ``max |lambda|`` where ``h max |lambda|`` is inside the radius (the half-disk lies in the
    stability region), else ``radius / largest stable step`` (the region itself, for modes beyond the
    half-disk that it still contains: a pure damping inside RK4's real interval).  A regularised
    friction state (Exudyn's ``lugreFrictionTest.py``: ``Zdot = V - Z |V| / G``, G ~ 1e-5) is stiff
    only while it slides, which the check at the initial state (at rest) cannot see."""
    J = _ode1_jacobian(model, central=False)
    if not np.all(np.isfinite(J)):
        return np.inf                  # (the rates are not finite near this state: stop or switch)
    ev = np.linalg.eigvals(J)
    ev = np.minimum(ev.real, 0.0) + 1j * ev.imag        # (largest_stable_step's physical growth)
    rho = float(np.max(np.abs(ev))) if ev.size else 0.0
    # a partitioned method (velocity Verlet) advances first-order coordinates with its (A, b) alone, whose
    # own half-disk decides; the rate is scaled to the watch's radius (stable iff h rate <= radius)
    first = first_order_part(tableau)
    own = radius if first is tableau else stability_radius(first)
    if h * rho <= own:
        return rho * radius / own
    hmax = largest_stable_step(first, ev)
    return radius / hmax if 0.0 < hmax < np.inf else 0.0


def check_step(model, tableau, h, refuse=True, nsteps=None):
    """The stability check before a run (:func:`~exudyn_lie.mbs.stiffness.check_linear_stability`)
    with the eigenvalues of Exudyn's linearisation at the state in mbs; returns (fastest rate,
    largest stable step).

    Not with a GeneralContact: its Jacobian (``JacobianODE2LHS``) is that of the active-set law
    for the implicit solvers' Newton iteration, not the derivative of the law this path evaluates
    (bridge/general_contact.py); in Exudyn's ``particleClusters.py`` it gave |lambda| = 7.7e11 1/s
    (the StepSizeError of ``python -m exudyn_lie corpus`` at be95a49) where Exudyn's explicit Euler
    runs at the script's step.  The stepper's blow-up check and the stage-stiffness watch during the
    run remain."""
    if general_contacts(model.mbs):
        return 0.0, float("inf")
    source = "Exudyn's stiffness, damping and mass matrices on the constraint manifold at this state"
    if not tableau.partitioned:
        return check_linear_stability(tableau, h, model.sd.GetTime(), linear_eigenvalues(model), source, refuse,
                                      nsteps)
    # a partitioned method: the second-order modes by its pair growth, the ODE1 modes by its (A, b)
    ev2, ev1 = linear_eigenvalues(model, split=True)
    rate2, h2 = check_linear_stability(tableau, h, model.sd.GetTime(), ev2, source, refuse, nsteps)
    rate1, h1 = check_linear_stability(first_order_part(tableau), h, model.sd.GetTime(), ev1,
                                       "the eigenvalues of d(ydot)/dy of the first-order coordinates", refuse, nsteps)
    return max(rate1, rate2), min(h1, h2)


def choice_step(model, tableau, h, nsteps=None):
    """:func:`check_step` for the drop-in's own choice of its method (no StepSizeError): ``(fastest rate,
    largest stable step, exact)``.  Where the damping is not proportional and the system is large,
    the converged Ritz values of the largest modes (:func:`dominant_eigenvalues`) decide alone when
    they put ``h`` beyond the stable step (fewer eigenvalues can only raise it): ``exact`` False, the
    stable step an upper bound of the true one; else every eigenvalue."""
    if general_contacts(model.mbs) or tableau.partitioned:
        return (*check_step(model, tableau, h, False, nsteps), True)
    t = model.sd.GetTime()
    MK, MD, ev1 = _linearised(model)
    modal = None if MK is None else modal_eigenvalues(MK, MD)
    if MK is not None and modal is None and 2 * MK.shape[0] >= KRYLOV_FROM:
        ritz = dominant_eigenvalues(MK, MD)
        if ritz.size:
            rate, hmax = check_linear_stability(tableau, h, t, np.concatenate([ritz, ev1]), "", False, nsteps)
            if h > hmax:
                return rate, hmax, False
    ev = np.concatenate([_second_order_eigenvalues(MK, MD, modal), ev1])
    return (*check_linear_stability(tableau, h, t, ev, "", False, nsteps), True)

"""The stability check at the start of an Exudyn-evaluated run (bridge/evaluated_stiffness.py):
with no or proportional (Rayleigh) damping, the eigenvalues of the linearised equations come from
those of ``M^-1 K`` alone (``modal_eigenvalues``), a problem of half the size.

Checked against numpy's eigenvalues of the whole first-order matrix, and through the drop-in on
an ObjectGenericODE2 whose modes are known in closed form (the rate it prints is the analytic one).
"""
import re
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2

import exudyn_lie as exl
from exudyn_lie.bridge import evaluated_stiffness
from exudyn_lie.bridge.evaluated_stiffness import modal_eigenvalues
from exudyn_lie.errors import StepSizeError


def _first_order(MK, MD):
    k = MK.shape[0]
    A = np.zeros((2 * k, 2 * k))
    A[:k, k:] = np.eye(k)
    A[k:, :k] = -MK
    A[k:, k:] = -MD
    return np.linalg.eigvals(A)


def _mismatch(ev, ref):
    """The largest distance of an eigenvalue of ``ev`` to the nearest of ``ref`` and back,
    relative to the largest |lambda|."""
    d = max(max(np.min(np.abs(ref - x)) for x in ev), max(np.min(np.abs(ev - x)) for x in ref))
    return d / np.max(np.abs(ref))


@pytest.mark.parametrize("damping", ["none", "rayleigh", "overdamped"])
def test_modal_eigenvalues_are_those_of_the_first_order_matrix(damping):
    rng = np.random.default_rng(7)
    k = 40
    B = rng.standard_normal((k, k))
    C = rng.standard_normal((k, k))
    MK = np.linalg.solve(B @ B.T + k * np.eye(k), 1e4 * (C @ C.T))
    MD = {"none": np.zeros((k, k)), "rayleigh": 0.3 * np.eye(k) + 2e-3 * MK,
          "overdamped": 5.0 * np.eye(k) + MK}[damping]
    ev = modal_eigenvalues(MK, MD, rtol=1e-12)
    assert ev is not None and ev.shape == (2 * k,)
    assert _mismatch(ev, _first_order(MK, MD)) < 1e-10


def _root_residual(lam, c, w2):
    """The largest relative residual of ``lambda^2 + c lambda + w2`` over ``lam``, each against the
    quadratic (c, w2) it fits best: a root computed with cancellation fails it."""
    r = np.abs(lam[:, None] ** 2 + c[None, :] * lam[:, None] + w2[None, :])
    s = np.abs(lam[:, None]) ** 2 + np.abs(c[None, :] * lam[:, None]) + np.abs(w2[None, :]) + 1e-300
    return float(np.max(np.min(r / s, axis=1)))


@pytest.mark.parametrize("case", ["strongly_overdamped", "rigid_modes", "complex"])
def test_modal_eigenvalues_solve_each_quadratic_to_round_off(case):
    """Each eigenvalue to round-off relative to itself: a strongly damped mode's slow root (1e-6
    beside 1e6, which cancels in the textbook formula), zero eigenvalues of M^-1 K with stiffness-
    proportional damping (rigid modes: lambda^2 = 0, both roots 0) and complex ones (a non-symmetric
    stiffness)."""
    rng = np.random.default_rng(11)
    k = 8
    Q, _ = np.linalg.qr(rng.standard_normal((k, k)))
    if case == "strongly_overdamped":
        w2, a, b = 1.0 + rng.random(k), 1e6, 0.0
    elif case == "rigid_modes":
        Q = np.eye(k)                       # (the zero eigenvalues exact)
        w2, a, b = np.r_[0.0, 0.0, 1e3 * rng.random(k - 2)], 0.0, 1e-3
    else:
        w2, a, b = np.r_[1e2 + 30j, 1e2 - 30j, 5.0 + rng.random(k - 2)], 0.5, 2e-3
    MK = (Q * w2) @ Q.T if case != "complex" else np.real_if_close(Q @ _real_block(w2) @ Q.T)
    ev = modal_eigenvalues(MK, a * np.eye(k) + b * MK, rtol=1e-12)
    assert ev is not None
    w2 = np.asarray(w2, complex)
    if case == "rigid_modes":
        # (the fit's a is round-off, ~1e-17, not 0: those roots are checked against 0, not against it)
        rigid = np.abs(ev) < 1e-12
        assert np.sum(rigid) == 4 and np.all(np.isfinite(ev))
        ev = ev[~rigid]
    assert _root_residual(ev, a + b * w2, w2) < 1e-13


def _real_block(w2):
    """A real matrix with the eigenvalues ``w2`` (a conjugate pair first, as a 2 x 2 block)."""
    B = np.diag(np.real(w2)).astype(float)
    B[0, 1], B[1, 0] = np.imag(w2[0]), -np.imag(w2[0])
    return B


def test_modal_eigenvalues_refuse_damping_that_is_not_proportional():
    rng = np.random.default_rng(3)
    MK = np.diag(rng.random(6) * 100)
    assert modal_eigenvalues(MK, np.diag(rng.random(6))) is None
    # proportional up to one entry: not proportional
    MD = 0.1 * np.eye(6) + 0.01 * MK
    MD[0, 5] = 1e-3
    assert modal_eigenvalues(MK, MD) is None
    # M^-1 K near a multiple of I (equal oscillators, weak coupling) and dampers 30 % apart: a and b
    # of the fit grow large and cancel; the test against MD itself still refuses it
    n = 10
    L = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    MK = 1e4 * np.eye(n) + 1e-2 * L
    d = 1.0 + 0.3 * np.sin(np.arange(n - 1))
    MD = np.zeros((n, n))
    for i, di in enumerate(d):
        MD[i:i + 2, i:i + 2] += di * np.array([[1.0, -1.0], [-1.0, 1.0]])
    assert modal_eigenvalues(MK, MD) is None


@pytest.mark.parametrize("rayleigh", [(0.0, 0.0), (2.0, 1e-4)])
def test_dropin_prints_the_analytic_fastest_mode_of_a_stiff_generic_ode2(rayleigh, capsys, monkeypatch):
    """Three uncoupled oscillators (m = 1, 2, 0.5 kg; k = 1e6, 2e4, 5e2 N/m) with Rayleigh damping
    D = a M + b K: each mode solves lambda^2 + (a + b w^2) lambda + w^2 = 0; at h = 0.01 s RK4 is not
    stable, and the line that says so gives the fastest |lambda| and RK4's largest stable step."""
    a, b = rayleigh
    m, kk = np.array([1.0, 2.0, 0.5]), np.array([1e6, 2e4, 5e2])
    M, K = np.diag(m), np.diag(kk)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * 3, initialCoordinates=[1e-3, 0.0, 0.0],
                                    initialCoordinates_t=[0.0] * 3, numberOfODE2Coordinates=3))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=M, stiffnessMatrix=K, dampingMatrix=a * M + b * K))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = 5
    ss.timeIntegration.endTime = 0.05
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    used = []

    def modal(MK, MD):
        used.append(evaluated_stiffness.modal_eigenvalues.__wrapped__(MK, MD))
        return used[-1]
    modal.__wrapped__ = evaluated_stiffness.modal_eigenvalues
    monkeypatch.setattr(evaluated_stiffness, "modal_eigenvalues", modal)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss)
    assert used and used[0] is not None            # (the check took the modal route)
    out = capsys.readouterr().out
    found = re.search(r"fastest mode \|lambda\| ~ ([0-9.e+-]+) 1/s", out)
    assert found, out
    w2 = kk / m
    c = a + b * w2
    lam = np.concatenate([np.roots([1.0, ci, wi]) for ci, wi in zip(c, w2)])
    assert float(found.group(1)) == pytest.approx(np.max(np.abs(lam)), rel=1e-3)
    if a == b == 0.0:
        hmax = float(re.search(r"stable up to h = ([0-9.e+-]+) s", out).group(1))
        assert hmax == pytest.approx(2.0 * np.sqrt(2.0) / np.sqrt(w2.max()), rel=5e-3)   # RK4 on the imaginary axis


@pytest.mark.parametrize("omega", [1e4, 4e6, 1e9])
def test_dominant_eigenvalues_are_eigenvalues_and_find_the_fastest(omega):
    """The converged Ritz values of Arnoldi's iteration (non-proportional damping) lie on eigenvalues
    of the first-order matrix, and the fastest one is among them, up to the stiffness of Exudyn's
    contact and FFRF scripts (omega = 1e9: the unscaled iteration accepted values 70 % off)."""
    rng = np.random.default_rng(5)
    k = 150
    B = rng.standard_normal((k, k))
    w2 = np.r_[omega ** 2, 0.3 * omega ** 2, rng.random(k - 2) * 1e4]
    Q, _ = np.linalg.qr(rng.standard_normal((k, k)))
    MK = (Q * w2) @ Q.T
    MD = np.diag(rng.random(k)) + 1e-3 * (B @ B.T)
    ritz = evaluated_stiffness.dominant_eigenvalues(MK, MD)
    full = _first_order(MK, MD)
    assert ritz.size >= 2
    for th in ritz:
        assert np.min(np.abs(full - th)) <= 1e-6 * abs(th)
    assert np.max(np.abs(ritz)) == pytest.approx(np.max(np.abs(full)), rel=1e-9)
    assert np.max(np.abs(ritz)) == pytest.approx(omega, rel=1e-6)          # (light damping: |lambda| ~ omega)


def _oscillators(n, kk, d, h, steps=5, method=None):
    """n uncoupled unit masses with stiffnesses ``kk`` and dampers ``d`` (not proportional) as one
    ObjectGenericODE2; returns (printed output, final coordinates)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=[1e-3] * n,
                                       initialCoordinates_t=[0.0] * n, numberOfODE2Coordinates=n))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=np.eye(n), stiffnessMatrix=np.diag(kk),
                                    dampingMatrix=np.diag(d)))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = steps
    ss.timeIntegration.endTime = steps * h
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, **({} if method is None else {"method": method}))
    return np.array(mbs.systemData.GetODE2Coordinates())


def test_dropin_choice_by_the_largest_modes_with_damping_not_proportional(capsys):
    """120 oscillators (2 k = 240 >= KRYLOV_FROM), one of them stiff, dampers not proportional: the
    drop-in's line names Arnoldi's iteration and the analytic fastest |lambda|; at a step where RK4 is
    stable the estimate decides nothing and the run is RK4's (equal to the bit to a named RK4 run)."""
    n = 120
    rng = np.random.default_rng(2)
    kk = np.r_[1e8, rng.random(n - 1) * 1e3 + 10.0]
    d = rng.random(n) * 0.5
    assert 2 * n >= evaluated_stiffness.KRYLOV_FROM
    _oscillators(n, kk, d, 1e-3)
    out = capsys.readouterr().out
    assert "Arnoldi" in out and "implicit ESDIRK3" in out, out
    lam = np.concatenate([np.roots([1.0, di, ki]) for di, ki in zip(d, kk)])
    rate = float(re.search(r"fastest mode \|lambda\| ~ ([0-9.e+-]+) 1/s", out).group(1))
    assert rate == pytest.approx(np.max(np.abs(lam)), rel=1e-3)
    q = _oscillators(n, kk, d, 1e-5)                  # h |lambda| = 0.1: RK4 stable
    assert "ESDIRK3" not in capsys.readouterr().out
    np.testing.assert_array_equal(q, _oscillators(n, kk, d, 1e-5, method="RK4"))


def test_a_named_rk4_still_stops_by_every_eigenvalue():
    """Naming the method keeps the StepSizeError of the whole spectrum (not the largest modes alone)."""
    n = 120
    rng = np.random.default_rng(2)
    kk = np.r_[1e8, rng.random(n - 1) * 1e3 + 10.0]
    with pytest.raises(StepSizeError) as err:
        _oscillators(n, kk, rng.random(n) * 0.5, 1e-3, method="RK4")
    assert "Arnoldi" not in str(err.value)

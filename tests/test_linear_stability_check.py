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


def test_modal_eigenvalues_refuse_damping_that_is_not_proportional():
    rng = np.random.default_rng(3)
    MK = np.diag(rng.random(6) * 100)
    assert modal_eigenvalues(MK, np.diag(rng.random(6))) is None
    # proportional up to one entry: not proportional
    MD = 0.1 * np.eye(6) + 0.01 * MK
    MD[0, 5] = 1e-3
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

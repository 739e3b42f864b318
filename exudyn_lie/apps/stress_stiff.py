"""Stress case ``stiff``: the implicit ESDIRK3 (mbs/implicit.py) at one step whatever the stiffness.

* A body on an undamped zero-length spring (``stress_models.spring_mass``), stiffness 1e2 ... 1e10,
  released from rest, fixed step h = 1e-2 s for 1 s (h omega from 0.1 to 1e3): finite, the energy
  never above the initial one, and the energy after the run against the linear theory
  ``|R(i h omega)|^(2 n)`` of the method's rational stability function (the oscillator's energy is
  multiplied by ``|R|^2`` per step).
* A body on a revolute joint to the ground with a torsional spring of stiffness 1e2 ... 1e10 (no
  projection), h = 5e-3 s for 1 s, on SE3: finite, the joint held to round-off (corollary 1).

No silent failure: a run either ends with these checks or raises an error (a failed check).
"""
import numpy as np

from ..integrators import stability as S
from ..mbs import GROUND, Scene, Simulator
from . import stress_models as M

STIFFNESS = tuple(10.0 ** k for k in range(2, 11))


def _pendulum(k):
    sc = Scene(gravity=[0, 0, -9.81])
    b = sc.AddBody(2.0, np.diag([0.02, 0.03, 0.04]), r0=[0.5, 0.2, 0.1], omega0=[0, 3.0, 0])
    sc.AddRevoluteJoint(GROUND, b, [0.2, 0.2, 0.0], axis=[0, 1, 0])
    Y = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]          # the spring's z axis along the joint's axis y
    sc.AddTorsionalSpringDamper(GROUND, b, rotA=Y, rotB=Y, stiffness=k)
    return sc


def case_stiff(quick, outdir):
    from .stress_cases import CaseResult, Table, e2
    cr = CaseResult("stiff", "Stiffness 1e2 ... 1e10 at one step: the implicit ESDIRK3",
                    intro="A spring-mass (h = 1e-2 s) and a pendulum on a revolute joint with a torsional spring "
                          "(h = 5e-3 s, SE3, no projection), 1 s each, with MK-ESDIRK3 (L-stable, order 3): finite, "
                          "energy bounded and as the linear theory has it, the joint held.")
    ks = STIFFNESS[::2] if quick else STIFFNESS
    rows = []
    h, T = 1e-2, 1.0
    n = int(round(T / h))
    for k in ks:
        sim = Simulator(M.spring_mass(k), "ESDIRK3", "SE3")
        e0 = sim.Diagnostics()[0].sum()
        res = sim.Run(T, h, outputEvery=1)
        energies = res.energy.sum(axis=1)
        finite = bool(np.all(np.isfinite(res.r)) and np.all(np.isfinite(res.V)))
        ratio = float(energies[-1] / e0)
        theory = float(abs(S.stability_function("ESDIRK3", [1j * h * np.sqrt(k)])[0]) ** (2 * n))
        c = sim.newtonCounters
        rows.append([f"{k:.0e}", f"{h * np.sqrt(k):.3g}", e2(ratio), e2(theory), f"{c['iterations'] / c['stages']:.2f}",
                     c["jacobians"]])
        cr.check(f"spring-mass k = {k:.0e}: finite", finite)
        cr.check(f"spring-mass k = {k:.0e}: energy never above the initial one",
                 np.all(energies <= e0 * (1 + 1e-9)), f"max ratio {np.max(energies) / e0:.3g}")
        # the theory where it is above the round-off of the energy, else both at round-off
        agree = (abs(ratio - theory) <= 1e-6 * max(theory, 1e-12) + 1e-12) if theory > 1e-10 else ratio < 1e-9
        cr.check(f"spring-mass k = {k:.0e}: energy ratio as |R(i h omega)|^(2n)", agree,
                 f"measured {ratio:.6g}, theory {theory:.6g}")
    cr.tables.append(Table("Spring-mass, h = 1e-2 s, 100 steps: energy after the run / initial",
                           ["k [N/m]", "h omega", "measured", "|R(i h omega)|^(2n)", "Newton iterations / stage",
                            "Jacobians"], rows))
    rows = []
    for k in ks:
        sim = Simulator(_pendulum(k), "ESDIRK3", "SE3", projectInitial=True)
        sim.Run(1.0, 5e-3, outputEvery=200)
        _, _, pv, rv = sim.Diagnostics()
        viol = float(max(pv.max(), rv.max()))
        finite = bool(np.all(np.isfinite(sim.r)) and np.all(np.isfinite(sim.V)))
        lam = np.sqrt(k / 0.03)
        rows.append([f"{k:.0e}", f"{5e-3 * lam:.3g}", e2(viol)])
        cr.check(f"pendulum k = {k:.0e}: finite", finite)
        cr.check(f"pendulum k = {k:.0e}: joint held on SE3 (corollary 1)", viol < 1e-9, f"{viol:.3g}")
    cr.tables.append(Table("Pendulum on a revolute joint with a torsional spring, SE3, h = 5e-3 s, no projection",
                           ["k [Nm/rad]", "h omega (about)", "joint violation after 1 s"], rows))
    cr.headline = (f"ESDIRK3 at one step for stiffness {ks[0]:.0e} ... {ks[-1]:.0e}: "
                   f"{sum(c.ok for c in cr.checks)} of {len(cr.checks)} checks pass")
    return cr

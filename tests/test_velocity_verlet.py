"""Exudyn's VelocityVerlet through the drop-in: the partitioned tableau (integrators/partitioned.py)
checks itself, runs Exudyn's scheme on the bodies' groups (to round-off where the forces depend on
the configuration alone), converges like it where they do not, is symplectic, and a named velocity
Verlet stops with a StepSizeError beyond its stability region."""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import InertiaSphere, SensorBody

import exudyn_lie as exl
from exudyn_lie.errors import StepSizeError
from exudyn_lie.integrators import get_method
from exudyn_lie.integrators.partitioned import PartitionedTableau, VelocityVerlet, first_order_part
from exudyn_lie.integrators.stability import pair_growth, stability_function, stability_radius

from test_bridge_common import new_mbs
from test_bridge_solve import data
from test_bridge_solvertype import exl_run, fixed_settings, native_run

DST = exu.DynamicSolverType
O = exu.OutputVariableType


def test_tableau_checks_itself_and_is_found_by_name():
    assert get_method("velocity-verlet") is VelocityVerlet and get_method("Verlet") is VelocityVerlet
    assert VelocityVerlet.partitioned and not VelocityVerlet.implicit and VelocityVerlet.b_hat is None
    assert VelocityVerlet.order2 == 2 and VelocityVerlet.order == 1      # first-order part: order 1
    with pytest.raises(ValueError, match=r"sum_j bq_j c_j = 1.0, not 1/2"):     # the drift on V, not V_1/2
        PartitionedTableau(name="x", order=1, A=[[0, 0], [1, 0]], b=["1/2", "1/2"], c=[0, 1],
                           Aq=[[0, 0], [0, 1]], bq=[0, 1])
    with pytest.raises(ValueError, match=r"the first stage must be the step's start"):
        PartitionedTableau(name="x", order=1, A=[[0, 0], ["1/2", 0]], b=["1/2", "1/2"], c=[0, "1/2"],
                           Aq=[[1, 0], [0, 1]], bq=[0, 1])
    with pytest.raises(ValueError, match=r"diagonal entry needs the rest of the row zero"):
        PartitionedTableau(name="x", order=1, A=[[0, 0], ["1/2", 0]], b=["1/2", "1/2"], c=[0, "1/2"],
                           Aq=[[0, 0], ["1/2", "1/2"]], bq=[0, 1])


def test_stability_of_the_mode_pair():
    """Undamped: stable up to h omega = 2 (the leapfrog's limit) and exactly on the unit circle
    below it (symplectic); the half-disk radius of the damped pairs is smaller."""
    y = np.linspace(0.01, 1.99, 50)
    assert np.all(np.abs(pair_growth(VelocityVerlet, 1j * y) - 1.0) < 1e-12)
    assert pair_growth(VelocityVerlet, 2.02j)[()] > 1.1
    r = stability_radius(VelocityVerlet)
    assert 1.5 < r < 2.0
    assert pair_growth(VelocityVerlet, -0.99 * r)[()] <= 1.0 + 1e-3
    # first-order coordinates: its (A, b) alone, R(z) = 1 + z + z^2 / 4 (stable on [-4, 0], not on the
    # imaginary axis); no scalar function of the partitioned method itself
    first = first_order_part(VelocityVerlet)
    assert abs(stability_function(first, -2.5)[0] - (1 - 2.5 + 2.5 ** 2 / 4)) < 1e-15
    assert abs(stability_function(first, 0.5j)[0]) > 1.0
    with pytest.raises(ValueError, match="partitioned"):
        stability_function(VelocityVerlet, -1.0)


def spring_body(damping=0.0, stiffness=(300, 200, 100), torque=(0.1, 0, 0.2)):
    """A rigid body of isotropic inertia (no gyroscopic term) on a Cartesian spring, with gravity and
    a body-fixed torque (the items of test_bridge_solve.free_body: one kind of compiled model):
    without damping its forces depend on the configuration alone (the torque is constant in the
    body frame)."""
    mbs = new_mbs()
    g = mbs.CreateGround()
    inert = InertiaSphere(mass=2.0, radius=0.1)
    b = mbs.CreateRigidBody(inertia=inert, referencePosition=[0.5, 0.1, 0],
                            nodeType=exu.NodeType.RotationRotationVector, initialAngularVelocity=[10.0, 2.0, 1.0],
                            initialVelocity=[1, 0, 0.5], gravity=[0, 0, -9.81])
    mbs.CreateCartesianSpringDamper(itemNumbers=[g, b], localPosition0=[0.6, 0, 0.1], localPosition1=[0.1, 0, 0],
                                    stiffness=list(stiffness), damping=[damping] * 3)
    mbs.CreateTorque(itemNumber=b, loadVector=list(torque), bodyFixed=True)
    s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                 localPosition=[0.1, 0.1, 0]))
    mbs.Assemble()
    return mbs, s


def run(solve, T, h, **kw):
    mbs, s = spring_body(**{k: kw.pop(k) for k in ("damping",) if k in kw})
    ss = fixed_settings(T, h, DST.VelocityVerlet)
    if solve == "native":
        mbs.SolveDynamic(ss)
    else:
        exl.SolveDynamic(mbs, ss, liegroup="SO3xR3", **kw)
    return data(mbs, s)


@pytest.mark.parametrize("evaluation", ["compiled", "exudyn"])
def test_configuration_forces_agree_with_exudyns_velocity_verlet_to_round_off(evaluation):
    """Exudyn's SO(3)xR3 update is the same exp of the half-step velocity: with forces of the
    configuration alone the two schemes are one (Exudyn reuses the last stage's accelerations,
    which then equal those at the next step's start).  The type as argument, as setting, and
    method='VelocityVerlet' run the same."""
    T, h = 0.3, 1e-3
    ours = run("exl", T, h, evaluation=evaluation)
    native = run("native", T, h)
    assert ours.shape == native.shape
    assert np.max(np.abs(ours - native)) < 1e-12
    if evaluation == "compiled":
        mbs, s = spring_body()
        exl.SolveDynamic(mbs, fixed_settings(T, h), solverType=DST.VelocityVerlet, liegroup="SO3xR3")
        assert mbs.sys["lieGroupSolver"].tableau is VelocityVerlet
        assert np.array_equal(data(mbs, s), ours)
        mbs, s = spring_body()
        exl.SolveDynamic(mbs, fixed_settings(T, h), method="velocity-verlet", liegroup="SO3xR3")
        assert np.array_equal(data(mbs, s), ours)


def test_velocity_forces_converge_at_first_order_like_exudyns():
    """A damped, gyroscopic body: Exudyn's scheme (the half-step velocity in the second stage, the
    last stage's accelerations reused) and this one (the first stage at the step's start) are both
    of order 1 for velocity-dependent forces, against RK4 at h = 1e-5."""
    T = 0.3
    ref = exl_run(T, 1e-5, method="RK4")[1][-1, 1:]
    hs = (1e-3, 5e-4, 2.5e-4)
    ours = [np.max(np.abs(exl_run(T, h, solverType=DST.VelocityVerlet)[1][-1, 1:] - ref)) for h in hs]
    native = [np.max(np.abs(native_run(T, h, DST.VelocityVerlet)[-1, 1:] - ref)) for h in hs]
    for err in (ours, native):
        slope = np.polyfit(np.log(hs), np.log(err), 1)[0]
        assert 0.9 < slope < 1.1, (err, slope)
    assert all(o <= n for o, n in zip(ours, native)), (ours, native)


def test_symplectic_energy_stays_bounded():
    """Undamped, isotropic, 20,000 steps: the energy error oscillates, it does not drift (the error
    over the last quarter of the run is no larger than over the first)."""
    T, h = 20.0, 1e-3
    mbs, s = spring_body(torque=(0, 0, 0))
    ss = fixed_settings(T, h, DST.VelocityVerlet)
    ss.solution.sensors.writePeriod = 0.01
    ke = mbs.AddSensor(SensorBody(bodyNumber=1, storeInternal=True, outputVariableType=O.KineticEnergy))
    com = mbs.AddSensor(SensorBody(bodyNumber=1, storeInternal=True, outputVariableType=O.Position))
    tip = mbs.AddSensor(SensorBody(bodyNumber=1, storeInternal=True, outputVariableType=O.Position,
                                   localPosition=[0.1, 0, 0]))
    mbs.Assemble()
    exl.SolveDynamic(mbs, ss, liegroup="SO3xR3")
    d = data(mbs, tip)[:, 1:] - np.array([0.6, 0, 0.1])
    energy = (data(mbs, ke)[:, 1] + 2.0 * 9.81 * data(mbs, com)[:, 3]
              + 0.5 * (d ** 2) @ np.array([300.0, 200.0, 100.0]))
    err = np.abs(energy - energy[0])
    n = len(err) // 4
    assert np.all(np.isfinite(err)) and len(err) > 1000
    assert err.max() < 1e-3 * abs(energy[0])
    assert err[-n:].max() <= 1.2 * err[:n].max(), (err[:n].max(), err[-n:].max())


def test_named_velocity_verlet_stops_beyond_its_region():
    """A stiff spring at h omega = 7: the StepSizeError of the method named (no switch)."""
    mbs, s = spring_body(stiffness=(1e8, 1e8, 1e8))
    with pytest.raises(StepSizeError, match="VelocityVerlet"):
        exl.SolveDynamic(mbs, fixed_settings(0.01, 1e-3, DST.VelocityVerlet), liegroup="SO3xR3")

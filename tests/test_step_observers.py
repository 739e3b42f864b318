"""The step observers (mbs/step_observers.py): the path-dependent state is moved on after
every accepted step, by the one generated ``after_accepted_step``, and a step that fails
leaves it as it was at the last accepted step."""
import numpy as np
import pytest

from exudyn_lie.errors import StepSizeError
from exudyn_lie.mbs import GROUND, Scene, Simulator
from exudyn_lie.mbs import step_observers as so
from exudyn_lie.mbs.forces import torsion_angle


def test_every_registered_observer_is_called_once_after_a_step_and_at_start_if_registered_so():
    names = [o.name for o in so.OBSERVERS]
    assert len(set(names)) == len(names) == 5
    # the generated functions call each observer's update by its registry position
    step_calls = so.after_accepted_step.py_func.__code__.co_names
    start_calls = so.observe_initial_state.py_func.__code__.co_names
    for k, o in enumerate(so.OBSERVERS):
        assert f"observer{k}" in step_calls
        assert (f"observer{k}" in start_calls) == o.atStart
    with pytest.raises(ValueError, match="registered twice"):
        so.register_observer(names[0], so.OBSERVERS[0].update, True, lambda sd, wk: False)
    with pytest.raises(ValueError, match="before the stepper's code is generated"):
        so.register_observer("late", so.OBSERVERS[0].update, True, lambda sd, wk: False)
    assert len(so.OBSERVERS) == len(names)


def _spinning_torsion_scene(k):
    """A body spinning about the world z axis against a torsional spring to the ground."""
    sc = Scene()
    b = sc.AddBody(1.0, np.diag([0.1, 0.1, 0.1]), omega0=(0, 0, 30.0))
    sc.AddTorsionalSpringDamper(GROUND, b, stiffness=k)
    return sc


def _angle_at(sim, prev):
    wk = sim.wk
    ident = np.eye(3)
    phi, _ = torsion_angle(ident, ident, prev, ident, np.zeros(6), sim.R[0], sim.V[0], wk.m3[0], wk.m3[1])
    return phi


def test_torsion_turns_follow_accepted_steps():
    """Turns are counted over many revolutions: the tracked angle is the body's total angle,
    ``phi(t) = (omega0 / Omega) sin(Omega t)`` with ``Omega = sqrt(k / J)``."""
    sim = Simulator(_spinning_torsion_scene(1e-3), "RK4", "SE3")
    sim.Advance(1000, 1e-3)                     # 30 rad: almost five turns
    phi = float(sim.wk.path.torsionAngles[0])
    assert phi == pytest.approx(300.0 * np.sin(0.1), rel=1e-9)
    assert phi == pytest.approx(_angle_at(sim, phi), abs=1e-12)


def test_a_failed_step_leaves_the_path_state_at_the_last_accepted_step():
    """A step beyond the stability limit blows up and is undone (StepSizeError): the torsion
    angle is still that of the restored state, not of the rejected one."""
    sim = Simulator(_spinning_torsion_scene(1e6), "RK4", "SE3")
    with pytest.raises(StepSizeError):
        sim.Advance(10000, 2e-3)                  # sqrt(k / J) h = 6.3: far beyond RK4's 2.8
    phi = float(sim.wk.path.torsionAngles[0])
    assert np.isfinite(phi) and np.all(np.isfinite(sim.R))
    assert phi == pytest.approx(_angle_at(sim, phi), abs=1e-12)

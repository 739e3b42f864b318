"""The seams through which the compiled stepper calls Python, as parts of a
:class:`~.simulator.Simulator`: the rows' moving offsets (:mod:`.row_drives`), the Python
forces added at every stage, and a whole right-hand side from outside
(``Scene.SetRightHandSide``); all through :mod:`.external`."""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError
from . import kernel
from .state import BodyStates, twist_to_world_velocity


class ExternalSeams:
    """The Python side of the stepper's seams (:mod:`.external`) for a
    :class:`~.simulator.Simulator`."""

    def _row_drives(self, t):
        """The row-drive seam (:mod:`.row_drives`, through :mod:`.external`): called by the
        compiled stepper once per stage (and before a projection at a step's end); writes the
        moving offsets of the rows and their derivatives at ``t`` into ``wk.rdrive``."""
        self._drives.evaluate(t, self.wk.rdrive)

    def _drives_at(self, t):
        """The rows' moving offsets at ``t`` before rows are evaluated from Python."""
        if self._drives:
            self._drives.evaluate(t, self.wk.rdrive)

    @property
    def rates(self):
        """True if the scene's whole right-hand side comes from outside (Scene.SetRightHandSide)."""
        return self.sd.hasQext == kernel.EXTERNAL_RATES

    def _external_rates(self, t):
        """The right-hand side seam with the whole ``Vdot`` from the scene's problem
        (``Scene.SetRightHandSide``), bound once per work set to the stage state and to
        ``wk.Qext``, where it writes."""
        bound = self._extViews
        if bound is None or bound[0] is not self.wk:
            wk = self.wk
            bound = self._extViews = (wk, self.scene.rightHandSide.bind(wk.Rs, wk.rs, wk.Vs, wk.Qext))
        bound[1](t)

    def _external_forces(self, t):
        """The right-hand side seam (:mod:`.external`): called by the compiled stepper once
        per stage; adds the Python forces at the stage state to ``wk.Qext`` as world forces
        at the frame origins and world torques (the compiled caller turns them into
        generalised forces and checks them).  Allocates nothing itself: the callbacks see
        read-only views of the stage state (valid during the call)."""
        views = self._extViews          # (work set, views); checked here, not in a call: once per stage
        st, F, T, adders = views[1] if views is not None and views[0] is self.wk else self._external_views()
        st.t = t
        for add in adders:
            add(t, st, F, T)

    def _add_returned(self, pf):
        """An adder for a callback ``fn(t, st) -> (F, T)`` (checks the shapes; the compiled
        caller checks that the sums are finite)."""
        nb = self.sd.nb

        def add(t, st, F, T):
            Fi, Ti = pf.fn(t, st)
            Fi = np.asarray(Fi, float)
            Ti = np.asarray(Ti, float)
            if Fi.shape != F.shape or Ti.shape != T.shape:
                raise SimulationError(f"{pf.name} must return finite (F, T) arrays of shape "
                                      f"({nb}, 3); got {Fi.shape}, {Ti.shape}")
            F += Fi
            T += Ti
        return add

    def _external_views(self):
        """(BodyStates, F, T, adders) for the external seam, made once per work set: views
        of the work arrays (the state read-only, so a callback cannot change the stage) and
        one ``add(t, st, F, T)`` per Python force (its ``add_into`` if it has one)."""
        wk = self.wk
        cached = self._extViews
        if cached is not None and cached[0] is wk:
            return cached[1]

        def ro(a):
            v = a.view()
            v.flags.writeable = False
            return v
        st = BodyStates(self.t, ro(wk.Rs), ro(wk.rs), ro(wk.Vw[:, :3]), ro(wk.Vw[:, 3:]))
        adders = tuple(self._stage_adder(pf, wk) for pf in self.scene.pythonForces)
        views = (st, wk.Qext[:, :3], wk.Qext[:, 3:], adders)
        self._extViews = (wk, views)
        return views

    def _stage_adder(self, pf, wk):
        """The seam's ``add(t, st, F, T)`` of a Python force: its ``stage_adder(probe, Qext)``
        if it reads kinematics the compiled stage computed (mbs/external_probes.py), else its
        ``add_into``, else its returned ``(F, T)`` added."""
        bind = getattr(pf.fn, "stage_adder", None)
        if bind is not None:
            return bind(wk.probe, wk.Qext)
        return getattr(pf.fn, "add_into", None) or self._add_returned(pf)

    def _python_forces(self, t, R, r, V):
        """The generalised Python forces (nb, 6) at a state (tests, diagnostics): the same
        evaluation as the compiled seam, on copies."""
        omega, vel = twist_to_world_velocity(self.gid, R, V)
        st = BodyStates(t, R.copy(), r.copy(), omega, vel)
        F = np.zeros((self.sd.nb, 3))
        T = np.zeros((self.sd.nb, 3))
        for pf in self.scene.pythonForces:
            add_into = getattr(pf.fn, "add_into", None)
            if add_into is not None:
                add_into(t, st, F, T)
            else:
                Fi, Ti = pf.fn(t, st)
                F += np.asarray(Fi, float)
                T += np.asarray(Ti, float)
        Q = np.zeros((self.sd.nb, 6))
        for i in range(self.sd.nb):
            kernel.add_point_force(int(self.gid[i]), R[i], np.zeros(3), F[i], Q[i])
            kernel.add_world_torque(R[i], T[i], Q[i])
        return Q

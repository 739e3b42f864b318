"""The compiled path's state in and out of mbs (a part of :class:`~.solver.LieGroupSolver`):
coordinate buffers (zero-copy views of mbs' Current configuration where Exudyn allows),
node coordinates written from the simulator's state or from the next output row, the state
re-read from mbs after a user function or a repeated step, Rxyz nodes watched near their
singularity, and the data nodes of torsional springs and penalty rolling discs."""
from __future__ import annotations

import math
import time

import numpy as np

from .fast import AdaptiveOutputChunks, NodeTable
from .time_loop import off_plan


class StateIO:
    """State in and out of mbs for :class:`~.solver.LieGroupSolver`."""

    #: the stage states are written into mbs while the stepper runs (bridge/stage_state.py)
    _stageWrites = False

    def _build_buffers(self):
        sc, sim = self.scene, self.sim
        # kernel rows of every joint, and their AE slots in Exudyn
        self._jrows = []
        for ji in sc.joints_info:
            self._jrows.append((np.array(sim.JointRows(ji.sceneJoint), np.int64), ji.aeRows))

    # ------------------------------------------------------------------ state <-> mbs
    def _views(self):
        """Writable zero-copy views of mbs' Current q, q_t, q_tt, AE coordinates (Exudyn
        >= 1.13 getters with ``copy=False``), checked to be live; None if unavailable."""
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        try:
            views = (sd.GetODE2Coordinates(configuration=cur, copy=False),
                     sd.GetODE2Coordinates_t(configuration=cur, copy=False),
                     sd.GetODE2Coordinates_tt(configuration=cur, copy=False),
                     sd.GetAECoordinates(configuration=cur, copy=False) if sd.AEsize() else np.zeros(0))
        except TypeError:
            return None
        for v in views[:3]:
            if not (isinstance(v, np.ndarray) and v.dtype == np.float64 and v.flags.c_contiguous
                    and v.flags.writeable) or v.size == 0:
                return None
        q = views[0]
        old = q[0]
        q[0] = old + 1.0
        live = sd.GetODE2Coordinates(configuration=cur)[0] == old + 1.0
        q[0] = old
        return views if live else None

    def _init_buffers_from_mbs(self, t0=None):
        """Coordinate buffers: zero-copy views of mbs' Current configuration if possible
        (then nothing has to be copied per output step), else copies pushed with Set*.
        Called right after Exudyn's InitializeSolver (Current = the initial values)."""
        exu = self._exu
        sd = self.mbs.systemData
        cur = exu.ConfigurationType.Current
        self._nAE = sd.AEsize()
        views = self._views()
        self._live = views is not None
        if self._live:
            self._q, self._qt, self._qtt, self._ae = views
        else:
            self._q = np.array(sd.GetODE2Coordinates(configuration=cur), float)
            self._qt = np.array(sd.GetODE2Coordinates_t(configuration=cur), float)
            self._qtt = np.array(sd.GetODE2Coordinates_tt(configuration=cur), float)
            self._ae = np.array(sd.GetAECoordinates(configuration=cur), float) if self._nAE else np.zeros(0)
        if self._nAE:
            self._ae[self.scene.aeZero] = 0.0
        for kind in self.scene.nodeKinds:       # continuity starts from the initial parameters
            kind.read(np.array(self._q), np.array(self._qt))
        self._nodes = NodeTable(self.scene.nodeKinds, self.scene.kindBodies, self.sim.t if t0 is None else t0)
        jr = self._jrows
        self._jrow = np.concatenate([x[0] for x in jr]).astype(np.int64) if jr else np.zeros(0, np.int64)
        self._jae = np.concatenate([x[1] for x in jr]).astype(np.int64) if jr else np.zeros(0, np.int64)
        self._Vdot = np.zeros((self.scene.nBodies, 6))
        self._lam = np.zeros(self.sim.nRows)
        self._hasJ = len(self._jrow) > 0

    def _watch_singular_nodes(self):
        """Nodes with singular coordinates (Rxyz) are watched at every internal step, so
        that passing near the singularity between two outputs is reported too."""
        nodes, bodies, limits, entry = [], [], [], None
        for kind, kb in zip(self.scene.nodeKinds, self.scene.kindBodies):
            if kind.singularity is not None:
                entry = kind.singularity[0]
                nodes += [(kind, k) for k in range(len(kind))]
                bodies += list(kb)
                limits += [kind.singularity[1]] * len(kind)
        self._watchNodes = nodes
        self._watchLimit = np.array(limits)
        if nodes:
            self.sim.WatchRotationEntries(bodies, *entry)

    def _warn_watched_nodes(self):
        """Warn (once per node) about watched nodes that came near their singularity
        since the last call."""
        if not self._watchNodes:
            return
        hit = self.sim.watchedMaxima > self._watchLimit
        if hit.any():
            self.sim.ResetWatch()
            for w in np.nonzero(hit)[0]:
                kind, k = self._watchNodes[w]
                kind.singular_warning(k)

    def _fill(self, accelerations):
        """Node and AE buffers from the simulator state (Python path)."""
        sim = self.sim
        lam = self._lam
        if accelerations:
            Vdot, lam = sim.Accelerations()
            self._Vdot[:] = Vdot
        return self._nodes.write(sim, self._Vdot, lam, accelerations, self._q, self._qt, self._qtt,
                                 (self._jrow, self._jae, self._ae))

    def _push(self, accelerations):
        """Copy the buffers into mbs' Current configuration (nothing to do for views)."""
        if not self._live:
            sd = self.mbs.systemData
            cur = self._exu.ConfigurationType.Current
            sd.SetODE2Coordinates(self._q, configuration=cur)
            sd.SetODE2Coordinates_t(self._qt, configuration=cur)
            if accelerations:
                sd.SetODE2Coordinates_tt(self._qtt, configuration=cur)
                if self._nAE:
                    sd.SetAECoordinates(self._ae, configuration=cur)
        if self._nodes.flags.any():
            self._nodes.warn_flags()

    def _write(self, accelerations):
        self._fill(accelerations)
        self._push(accelerations)

    def _next_output(self, t1, outputsLeft):
        """The compiled path: the buffers at Exudyn's time ``t1`` from the next row of the
        output chunk, integrating a new chunk when the last one is used up."""
        ch = self._chunks
        while ch.next == ch.rows:
            if ch.failure is not None:
                self._failed(ch, t1)     # raises, or continues from Exudyn's state with another method
                ch = self._chunks
            tic = time.perf_counter()
            keep = (self._q.copy(), self._qt.copy()) if self._stageWrites else None
            try:
                rows, nflag = ch.refill(outputsLeft)
            finally:
                if keep is not None:          # mbs holds the step's start again (bridge/stage_state.py),
                    self._q[:], self._qt[:] = keep      # also for a hand-over a user function raised
                    self._push(False)
            sec = time.perf_counter() - tic
            ch.adapt(sec, rows)
            self.timing["integration"] += sec
            if nflag:
                self._nodes.warn_flags()
            self._warn_watched_nodes()
            if rows == 0 and ch.failure is None:
                raise AssertionError("an output chunk without outputs and without a failure")
        if not ch.on_plan(t1):
            raise off_plan(t1, ch.time_of_next())
        ch.pop()

    def _failed(self, ch, t1):
        """A kernel failure in the chunk: the method's replacement when the user named none and an
        explicit method blew up (``_replace_after_failure``: the run continues from Exudyn's state at
        the start of this step, the outputs integrated ahead are dropped), else its error."""
        tStep = t1 - ch.nsub * ch.h
        if self._replace_after_failure(ch.failure, ch.h, tStep):
            self._restart_from_mbs(tStep)
            return
        self.sim.RaiseStatus(ch.failure, ch.h)

    def _replace_after_failure(self, status, h, t):
        return False

    def _restart_from_mbs(self, t):
        """Continue from the state in mbs at time ``t`` (Exudyn's start of the step): a user
        function changed the coordinates, Exudyn's discontinuous iteration repeats the step
        (it resets the ODE2 coordinates to the start of the step), or changed parameters
        invalidate the outputs integrated ahead."""
        self._reread_current(t)
        ch = self._chunks
        if ch is not None:
            ch.rows = ch.next = 0
            ch.failure = None
            if isinstance(ch, AdaptiveOutputChunks):     # a new first step, no FSAL reuse
                ch.restart(t)
                self.sim.RestartAdaptive()

    def _reread_current(self, t):
        """A pre-step user function changed the coordinates: continue from them."""
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        q = np.array(sd.GetODE2Coordinates(configuration=cur), float)
        qt = np.array(sd.GetODE2Coordinates_t(configuration=cur), float)
        nb = self.scene.nBodies
        R = np.zeros((nb, 3, 3))
        r = np.zeros((nb, 3))
        om = np.zeros((nb, 3))
        ve = np.zeros((nb, 3))
        for kind, bodies in zip(self.scene.nodeKinds, self.scene.kindBodies):
            R[bodies], r[bodies], om[bodies], ve[bodies] = kind.read(q, qt)
        U, _, Vt = np.linalg.svd(R)
        self.sim.SetInitialState(U @ Vt, r, om, ve, t0=t)
        for kind, bodies in zip(self.scene.nodeKinds, self.scene.kindBodies):
            for k, b in enumerate(bodies):          # the rotation parameters in mbs go on from here
                tr = kind.tracked(k)
                if tr is not None:
                    self.sim.SetTrackedParameters(b, tr[1])
        self._seed_torsion()
        self._seed_contact_data()
        self._nodes.prev[:] = NodeTable(self.scene.nodeKinds, self.scene.kindBodies, t).prev

    # ------------------------------------------------------------------ torsional springs' data nodes
    def _torsion_angles(self):
        """Exudyn's continuous angle of every torsional spring with a data node, at the
        simulator's state (compiled springs: the kernel's tracked angle + the folded turns)."""
        out = []
        st = None
        for td in self.scene.torsionData:
            if td.spring is not None:
                out.append(self.sim.TorsionAngle(td.spring) + 2.0 * math.pi * td.turns0)
            else:
                st = self.sim.states() if st is None else st
                out.append(float(td.item.angle(st)[0]))
        return out

    def _write_torsion_data(self):
        """Write the turned angles into the springs' data nodes (Current): Exudyn's own
        update after each of its steps takes the branch nearest to the last angle, which
        loses turns when a spring turns by more than pi between two outputs."""
        tds = self.scene.torsionData
        if not tds:
            return
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        data = np.array(sd.GetDataCoordinates(configuration=cur), float)
        for td, angle in zip(tds, self._torsion_angles()):
            data[int(sd.GetNodeLTGData(td.dataNode)[0])] = angle
        sd.SetDataCoordinates(data, configuration=cur)

    def _seed_contact_data(self):
        """After the state was re-read from mbs: the penalty rolling discs' data coordinates
        (slip velocity, gap of the last step) as they are in mbs."""
        if not self.scene.rollingDiscData:
            return
        sd = self.mbs.systemData
        data = np.asarray(sd.GetDataCoordinates(configuration=self._exu.ConfigurationType.Current), float)
        for k, (_, node) in enumerate(self.scene.rollingDiscData):
            self.sim.SetContactData(k, data[np.asarray(sd.GetNodeLTGData(node), np.int64)])

    def _seed_torsion(self):
        """After the state was re-read from mbs: continue every tracked torsion angle from
        the angle in its data node, as Exudyn does (the simulator restarts its tracking from
        the principal angle)."""
        tds = self.scene.torsionData
        if not tds:
            return
        sd = self.mbs.systemData
        data = np.asarray(sd.GetDataCoordinates(configuration=self._exu.ConfigurationType.Current), float)
        sim = self.sim
        for td in tds:
            prev = float(data[int(sd.GetNodeLTGData(td.dataNode)[0])])
            if td.spring is not None:
                target = prev - 2.0 * math.pi * td.turns0           # in the kernel's frame
                phi = sim.TorsionAngle(td.spring)
                sim.SetTorsionAngle(td.spring, phi + 2.0 * math.pi * round((target - phi) / (2.0 * math.pi)))
            else:
                td.item.prev = prev

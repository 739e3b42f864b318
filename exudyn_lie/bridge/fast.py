"""Exudyn output steps on the compiled path: chunks of outputs per call of the kernel.

A Python call of a numba function unboxes every array it receives: the stepper's scene and
work tuples hold ~60 arrays, the write-back ~20.  Per Exudyn output step that would be most of
the bridge's cost at the usual ten steps per output.  So :class:`OutputChunks` takes a chunk of the kernel's output rows (state, and
accelerations / multipliers, at each output: :mod:`exudyn_lie.mbs.outputs`), converts the
chunk to node coordinates in one call of
:func:`~exudyn_lie.bridge.node_writers.write_rows`, and per Exudyn step only copies one row into
mbs.  Where a user function may change the state between outputs, or Python forces run, the
chunk is one output long.  Both calls go through entry points resolved once
(:func:`~exudyn_lie.mbs.entry.call`).  Every output path of the bridge goes through here.
"""
import numpy as np

from ..mbs.entry import call
from ..mbs.outputs import CHUNK_ROWS, AdaptiveOutputRows, OutputRows
from .node_writers import CODE_1D_ROT, CODE_2D, NCOORD_MAX, present_writers, write_rows


class OutputChunks:
    """Exudyn output steps of ``nsub`` MK steps each: the kernel's output rows
    (:class:`~exudyn_lie.mbs.outputs.OutputRows`, a chunk per call of the stepper) converted
    to node coordinates a chunk at a time.

    :meth:`refill` integrates the next chunk from the simulator's state (which then runs
    ahead of Exudyn's time by up to one chunk) and :meth:`pop` copies the next output row
    into the coordinate buffers ``(q, qt, qtt, ae)`` (with ``doacc`` also accelerations and
    joint multipliers).  ``maxRows = 1`` keeps the simulator in step with Exudyn."""

    def __init__(self, sim, nodes, vmax, bufs, jac, nsub, h, doacc, maxRows=CHUNK_ROWS):
        self.sim, self.nodes = sim, nodes
        self.vmax, self.nsub, self.h, self.doacc = float(vmax), int(nsub), float(h), bool(doacc)
        self.bufs = bufs
        self.jac = jac
        q, qt, qtt, ae = bufs
        self.out = self._rows(sim, nsub, h, doacc, maxRows, 3 * q.size + ae.size)
        M = self.out.maxRows
        # rows start as the current coordinates: entries the write-back does not touch
        # (AE coordinates of no joint row) keep their values
        self.Q, self.Qt, self.Qtt = np.tile(q, (M, 1)), np.tile(qt, (M, 1)), np.tile(qtt, (M, 1))
        self.AE = np.tile(ae, (M, 1))
        # one view per row, made once: the per-output copy then indexes a list
        self.rowViews = (list(self.Q), list(self.Qt), list(self.Qtt), list(self.AE))
        self.rows = self.next = 0
        self.tStart = sim.t
        self.failure = None
        self._ep = {}

    _rows = OutputRows

    @property
    def maxRows(self):
        return self.out.maxRows

    @property
    def size(self):
        """Outputs in the next chunk."""
        return self.out.size

    def _write(self, rows, times):
        """Node coordinates (and multipliers) of the first ``rows`` output rows; returns the
        number of nodes flagged."""
        o, nt = self.out, self.nodes
        jrow, jae = self.jac
        a2 = (rows, self.sim.gid, o.Ro, o.ro, o.Vo, o.Vdo, o.lamo, self.doacc, nt.code, nt.body, nt.idx, nt.nq,
              nt.qref, nt.prev, self.Q, self.Qt, self.Qtt, nt.flags, jrow, jae, self.AE,
              np.ascontiguousarray(times, dtype=float), o.Po, nt.scratch, nt.present)
        return call(self._ep, "write", write_rows, a2)

    def refill(self, nout):
        """Integrate the next outputs (at most ``nout``); returns (outputs computed, flagged
        nodes).  On a kernel failure the outputs before it are kept, the simulator holds the
        last accepted step and :attr:`failure` the status."""
        t0 = self.sim.t
        rows, times = self.out.integrate(nout, self.vmax)
        nflag = self._write(rows, times)
        self.tStart, self.rows, self.next = t0, rows, 0
        self.failure = self.out.failure
        return rows, nflag

    def adapt(self, seconds, rows):
        """The next chunk's size from the wall time of this one."""
        self.out.adapt(seconds, rows)

    def time_of_next(self):
        return self.tStart + (self.next + 1) * self.nsub * self.h

    def on_plan(self, t1):
        """Exudyn's step ends at ``t1``, the time of the next output row."""
        return abs(self.time_of_next() - t1) <= 1e-6 * self.nsub * self.h + 1e-12 * abs(t1)

    def pop(self):
        """Copy the next output row into the coordinate buffers."""
        o = self.next
        q, qt, qtt, ae = self.bufs
        Qr, Qtr, Qttr, AEr = self.rowViews
        q[:] = Qr[o]
        qt[:] = Qtr[o]
        if self.doacc:
            qtt[:] = Qttr[o]
            if ae.size:
                ae[:] = AEr[o]
        self.next = o + 1


class AdaptiveOutputChunks(OutputChunks):
    """Exudyn's output times on adaptive steps (:class:`~exudyn_lie.mbs.outputs.
    AdaptiveOutputRows`): the same grid of outputs every ``nsub * h`` as
    :class:`OutputChunks` (the last at ``tEnd``), each from the dense output on the group of
    the step that contains it; no step is shortened for an output, unless ``clip``: then every
    chunk's last step ends at its last output, where a pre- or post-step function may change the
    state or the parameters and the run continues from that state (from a dense output instead,
    each such restart would add the interpolation's error)."""

    _rows = AdaptiveOutputRows

    def __init__(self, sim, nodes, vmax, bufs, jac, nsub, h, doacc, tEnd, maxRows=CHUNK_ROWS, clip=False):
        super().__init__(sim, nodes, vmax, bufs, jac, nsub, h, doacc, maxRows=maxRows)
        self.tEnd = float(tEnd)
        self.clip = bool(clip)
        self.restart(sim.t)

    def restart(self, t):
        """Outputs from Exudyn's time ``t`` on (start, or a restart from the state in mbs)."""
        self.t0, self.done = float(t), 0
        self.total = max(1, int(round((self.tEnd - self.t0) / (self.nsub * self.h))))

    def _output_times(self, n):
        dt = self.nsub * self.h
        idx = self.done + 1 + np.arange(n)
        t = self.t0 + idx * dt
        t[idx >= self.total] = self.tEnd           # Exudyn's last step ends at endTime
        return t

    def refill(self, nout):
        n = max(1, min(int(nout), self.out.size, self.total - self.done))
        tout = self._output_times(n)
        rows = self.out.integrate_at(float(tout[-1]) if self.clip else self.tEnd, tout)
        nflag = self._write(rows, tout)
        self.tStart, self.rows, self.next = self.t0 + self.done * self.nsub * self.h, rows, 0
        self.done += rows
        self.failure = self.out.failure
        return rows, nflag


class NodeTable:
    """All rigid nodes of a scene as flat arrays for :func:`~.node_writers.write_rows`."""

    def __init__(self, kinds, kindBodies, t0=0.0):
        """``t0``: the time of the state the kinds read (a 2D node's angle continues from it)."""
        rows = sum(len(k) for k in kinds)
        self.code = np.zeros(rows, np.int64)
        self.body = np.zeros(rows, np.int64)
        self.idx = np.zeros((rows, NCOORD_MAX), np.int64)
        self.nq = np.zeros(rows, np.int64)
        self.qref = np.zeros((rows, NCOORD_MAX))
        self.prev = np.zeros((rows, 4))
        self.flags = np.zeros(rows, np.int64)
        self.kindOfRow = []
        self.tracked = None             # the kernel's tracked values of the state written (write)
        self.scratch = np.zeros((8, 4))  # write_rows' working vectors (it allocates nothing)
        i = 0
        for kind, bodies in zip(kinds, kindBodies):
            n = len(kind)
            m = kind.idx.shape[1]             # coordinates per node
            self.code[i:i + n] = kind.row_codes()
            self.body[i:i + n] = bodies
            self.idx[i:i + n, :m] = kind.idx
            self.nq[i:i + n] = m
            ref = kind.table_reference()
            self.qref[i:i + n, :ref.shape[1]] = ref
            self.prev[i:i + n] = kind.prev
            angles = (self.code[i:i + n] == CODE_2D) | (self.code[i:i + n] == CODE_1D_ROT)
            self.prev[i:i + n, 2][angles] = t0             # node_writers.continued_angle: time of prev
            self.kindOfRow += [(kind, k) for k in range(n)]
            i += n
        self.present = present_writers(self.code)     # only these row writers are compiled

    def write(self, sim, Vdot, lam, doacc, q, qt, qtt, multipliers):
        """Node coordinates of the simulator's state (and with ``doacc`` accelerations and
        the joint multipliers ``(rows, AE slots, AE buffer)``); returns the number
        of nodes flagged (Rxyz near its singularity)."""
        jrow, jae, ae = multipliers
        nb = len(sim.gid)
        if self.tracked is None or self.tracked.shape[1] != nb:
            self.tracked = np.zeros((1, nb, 4))
        sim.TrackedParameters(self.tracked[0])
        return write_rows(1, sim.gid, sim.R[None], sim.r[None], sim.V[None], Vdot[None], lam[None], bool(doacc),
                          self.code, self.body, self.idx, self.nq, self.qref, self.prev, q[None], qt[None], qtt[None],
                          self.flags, jrow, jae, ae[None], np.array([float(sim.t)]), self.tracked, self.scratch,
                          self.present)

    def write_state(self, sim, t, R, r, V, q, qt):
        """Node coordinates and their rates of the state ``(R, r, V)`` at ``t`` (a stage's, for user
        functions that read mbs: bridge/stage_state.py), continuing from the last written."""
        nb = len(sim.gid)
        if self.tracked is None or self.tracked.shape[1] != nb:
            self.tracked = np.zeros((1, nb, 4))
        if getattr(self, "_stage", None) is None or self._stage[0].shape[1] != nb:
            self._stage = (np.zeros((1, nb, 6)), np.zeros((1, 0)), np.zeros(0, np.int64), np.zeros((1, 0)),
                           np.zeros((1, q.size)), np.zeros(1))
        Vdot, lam, none, ae, qtt, tt = self._stage
        tt[0] = t
        sim.TrackedParameters(self.tracked[0])
        return write_rows(1, sim.gid, R[None], r[None], V[None], Vdot, lam, False, self.code, self.body, self.idx,
                          self.nq, self.qref, self.prev, q[None], qt[None], qtt, self.flags, none, none, ae, tt,
                          self.tracked, self.scratch, self.present)

    def warn_flags(self):
        for i in np.nonzero(self.flags)[0]:
            kind, k = self.kindOfRow[i]
            kind.singular_warning(k)
        self.flags[:] = 0

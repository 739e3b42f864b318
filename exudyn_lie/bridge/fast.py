"""Exudyn output steps on the compiled path: chunks of outputs per call of the kernel.

A Python call of a numba function unboxes every array it receives: the kernel's scene and
work tuples hold ~60 arrays (~2 us per call, as much as a heavy-top step), the write-back
another ~20.  Per Exudyn output step that would be most of the bridge's cost at the usual
ten steps per output.  So :class:`OutputChunks` lets ``kernel.mk_steps`` integrate a chunk
of output steps in one call, recording the state (and accelerations / multipliers) at each
output, converts the chunk to node coordinates in one call of
:func:`~exudyn_lie.bridge.nodes.write_rows`, and per Exudyn step only copies one row into
mbs.  Where a user function may change the state between outputs, or Python forces run, the
chunk is one output long.  Both calls go through entry points resolved once
(:func:`~exudyn_lie.mbs.entry.call`).  Every output path of the bridge goes through here.
"""
import numpy as np

from ..mbs import kernel, stepper
from ..mbs.entry import call
from ..mbs.rotation_parameters import record_tracked
from .nodes import CODE_1D_ROT, CODE_2D, NCOORD_MAX, present_writers, write_rows

CHUNK_SECONDS = 0.05        # aimed wall time of one chunk (progress, responsiveness)
CHUNK_DOUBLES = 1 << 22     # at most this many doubles of chunk buffers (32 MiB)
CHUNK_ROWS = 256            # at most this many outputs per chunk

class OutputChunks:
    """Output steps of ``nsub`` MK steps each, computed a chunk at a time.

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
        nb, m = sim.sd.nb, sim.sd.nrows
        perRow = nb * 24 + m + 3 * q.size + ae.size
        self.maxRows = max(1, min(int(maxRows), CHUNK_DOUBLES // max(perRow, 1)))
        M = self.maxRows
        self.Ro, self.ro = np.zeros((M, nb, 3, 3)), np.zeros((M, nb, 3))
        self.Vo, self.Vdo, self.lamo = np.zeros((M, nb, 6)), np.zeros((M, nb, 6)), np.zeros((M, m))
        self.Po = np.zeros((M, nb, 4))          # tracked angles / node rotation parameters per row
        # rows start as the current coordinates: entries the write-back does not touch
        # (AE coordinates of no joint row) keep their values
        self.Q, self.Qt, self.Qtt = np.tile(q, (M, 1)), np.tile(qt, (M, 1)), np.tile(qtt, (M, 1))
        self.AE = np.tile(ae, (M, 1))
        # one view per row, made once: the per-output copy then indexes a list
        self.rowViews = (list(self.Q), list(self.Qt), list(self.Qtt), list(self.AE))
        self.size = 1                   # outputs in the next chunk (adapted to CHUNK_SECONDS)
        self.rows = self.next = 0
        self.tStart = sim.t
        self.failure = None
        self._ep = {}

    def refill(self, nout):
        """Integrate the next ``min(nout, size)`` outputs; returns (outputs computed,
        flagged nodes).  On a kernel failure the outputs before it are kept, the
        simulator holds the last accepted step and :attr:`failure` the status."""
        sim, h, nsub = self.sim, self.h, self.nsub
        n = max(1, min(int(nout), self.size))
        t0 = sim.t
        acc = n if self.doacc else 0
        a1 = (sim.sd, sim.wk, sim.method, sim.control, float(t0), h, n * nsub, sim.R, sim.r, sim.V, self.vmax, nsub,
              self.Ro[:n], self.ro[:n], self.Vo[:n], self.Po[:n], self.Vdo[:acc], self.lamo[:acc])
        st, done = call(self._ep, "mk", stepper.mk_steps, a1)
        rows = done // nsub
        if st != kernel.STATUS_OK and self.doacc and rows > 0 and np.isnan(self.Vdo[rows - 1, 0, 0]):
            rows -= 1                   # its accelerations failed: not an output
        nt = self.nodes
        q, qt, qtt, ae = self.bufs
        jrow, jae = self.jac
        To = t0 + ((np.arange(self.maxRows) + 1) * nsub) * h        # the rows' times (the last: t0 + done h)
        a2 = (rows, sim.sd.gid, self.Ro, self.ro, self.Vo, self.Vdo, self.lamo, self.doacc, nt.code, nt.body,
              nt.idx, nt.nq, nt.qref, nt.prev, self.Q, self.Qt, self.Qtt, nt.flags, jrow, jae, self.AE, To,
              self.Po, nt.scratch, nt.present)
        nflag = call(self._ep, "write", write_rows, a2)
        sim.t = t0 + done * h           # on a failure: the last accepted step
        self.tStart, self.rows, self.next = t0, rows, 0
        self.failure = None if st == kernel.STATUS_OK else st
        return rows, nflag

    def adapt(self, seconds, rows):
        """The next chunk's size from the wall time of this one."""
        if rows > 0 and self.maxRows > 1:
            per = max(seconds / rows, 1e-9)
            self.size = max(1, min(self.maxRows, int(CHUNK_SECONDS / per)))

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
    """Exudyn's output times on adaptive steps (:mod:`~exudyn_lie.mbs.adaptive`): the same
    grid of outputs every ``nsub * h`` as :class:`OutputChunks` (the last at ``tEnd``), each
    from the dense output on the group of the step that contains it; no step is shortened
    for an output.  Accelerations and multipliers at an output (``doacc``) are one
    evaluation of the equations of motion at its state (not counted as integration work)."""

    def __init__(self, sim, nodes, vmax, bufs, jac, nsub, h, doacc, tEnd, maxRows=CHUNK_ROWS):
        super().__init__(sim, nodes, vmax, bufs, jac, nsub, h, doacc, maxRows=maxRows)
        self.tEnd = float(tEnd)
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
        sim = self.sim
        n = max(1, min(int(nout), self.size, self.total - self.done))
        tout = self._output_times(n)
        tPrev = self.t0 + self.done * self.nsub * self.h
        st, rows = sim.AdvanceToInto(self.tEnd, tout, self.Ro[:n], self.ro[:n], self.Vo[:n], self.Po[:n])
        if self.doacc and rows > 0:
            wk = sim.wk
            keep0, keepLam = wk.Vd[0].copy(), wk.lam.copy()     # stage 1 / dense data of the step
            for o in range(rows):
                est = sim._evaluate(float(tout[o]), self.Ro[o], self.ro[o], self.Vo[o])
                if est != kernel.STATUS_OK:
                    rows, st = o, est
                    break
                self.Vdo[o] = wk.Vd[0]
                self.lamo[o] = wk.lam
            wk.Vd[0] = keep0
            wk.lam[:] = keepLam
        nt = self.nodes
        q, qt, qtt, ae = self.bufs
        jrow, jae = self.jac
        a2 = (rows, sim.sd.gid, self.Ro, self.ro, self.Vo, self.Vdo, self.lamo, self.doacc, nt.code, nt.body,
              nt.idx, nt.nq, nt.qref, nt.prev, self.Q, self.Qt, self.Qtt, nt.flags, jrow, jae, self.AE,
              np.ascontiguousarray(tout, dtype=float), self.Po, nt.scratch, nt.present)
        nflag = call(self._ep, "write", write_rows, a2)
        self.tStart, self.rows, self.next = tPrev, rows, 0
        self.done += rows
        self.failure = None if st == kernel.STATUS_OK else st
        return rows, nflag


class NodeTable:
    """All rigid nodes of a scene as flat arrays for :func:`~.nodes.write_rows`."""

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
            self.prev[i:i + n, 2][angles] = t0             # nodes.continued_angle: time of prev
            self.kindOfRow += [(kind, k) for k in range(n)]
            i += n
        self.present = present_writers(self.code)     # only these row writers are compiled

    def write(self, sim, Vdot, lam, doacc, q, qt, qtt, multipliers):
        """Node coordinates of the simulator's state (and with ``doacc`` accelerations and
        the joint multipliers ``(rows, AE slots, AE buffer)``); returns the number
        of nodes flagged (Rxyz near its singularity)."""
        jrow, jae, ae = multipliers
        sd = sim.sd
        if self.tracked is None or self.tracked.shape[1] != sd.nb:
            self.tracked = np.zeros((1, sd.nb, 4))
        record_tracked(sim.wk.btrack, sim.wk.bangle, sim.wk.bparam, self.tracked[0])
        return write_rows(1, sd.gid, sim.R[None], sim.r[None], sim.V[None], Vdot[None], lam[None], bool(doacc),
                          self.code, self.body, self.idx, self.nq, self.qref, self.prev, q[None], qt[None], qtt[None],
                          self.flags, jrow, jae, ae[None], np.array([float(sim.t)]), self.tracked, self.scratch,
                          self.present)

    def warn_flags(self):
        for i in np.nonzero(self.flags)[0]:
            kind, k = self.kindOfRow[i]
            kind.singular_warning(k)
        self.flags[:] = 0

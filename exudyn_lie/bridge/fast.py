"""Cheap repeated calls of the compiled kernel between two Exudyn output steps.

A plain numba call with the kernel's scene/work tuples spends ~10 us in resolving the
argument types; ``Simulator.Advance`` and ``Simulator.Accelerations`` pay it per call.  The bridge calls the same kernel functions with arguments
of identical types once per Exudyn step, so :class:`KernelCalls` resolves the compiled
overload once (:func:`entry_point`) and calls it directly.  It is used when the
simulator runs its pure compiled loop (no Python forces).

The node write-back (:func:`~exudyn_lie.bridge.nodes.write_all`) is compiled too.
"""
import numpy as np

from ..mbs import kernel
from .nodes import NCOORD_MAX, write_all


_ENTRY_CACHE = {}


def _type_key(x):
    """A cheap key that determines numba's type of an argument (arrays: dtype, ndim,
    layout, writeability; namedtuples: their class and fields)."""
    if isinstance(x, np.ndarray):
        return (x.dtype.str, x.ndim, x.flags.c_contiguous, x.flags.writeable)
    if isinstance(x, tuple):
        return (type(x),) + tuple(_type_key(v) for v in x)
    return type(x)


def entry_point(dispatcher, args):
    """The compiled entry point of a numba ``dispatcher`` for exactly these argument
    types (the dispatcher must have been called with them once); None if unavailable.
    Resolved signatures are cached by a cheap structural key of the arguments, so a
    repeated solve does not pay numba's type resolution (~1 ms per namedtuple) again."""
    try:
        key = (id(dispatcher),) + tuple(_type_key(a) for a in args)
        ep = _ENTRY_CACHE.get(key)
        if ep is None:
            sig = tuple(dispatcher.typeof_pyval(a) for a in args)
            ov = dispatcher.overloads.get(sig)
            if ov is None:
                return None
            ep = _ENTRY_CACHE[key] = ov.entry_point
        return ep
    except Exception:
        return None


class KernelCalls:
    """One Exudyn step on the fast path: ``kernel.mk_steps`` (n MK steps; with
    accelerations, a second call with no step evaluates the equations of motion at the
    end state: ``wk.Vd[0]`` and the multipliers ``wk.lam``) and the compiled write-back of
    all node / AE coordinates, each through a resolved entry point."""

    def __init__(self, sim, nodes, vmax, q, qt, qtt, jrow, jae, jsign, ae):
        self.sim = sim
        self.nodes = nodes
        self.vmax = float(vmax)
        self.bufs = (q, qt, qtt)
        self.jac = (jrow, jae, jsign, ae)
        self.mk = None
        self.wr = {}

    def _mk_steps(self, t, h, n):
        sim = self.sim
        a1 = (sim.sd, sim.wk, sim.A, sim.b, sim.c, float(t), float(h), int(n), sim.R, sim.r, sim.V, self.vmax)
        if self.mk is None:
            out = kernel.mk_steps(*a1)
            self.mk = entry_point(kernel.mk_steps, a1) or kernel.mk_steps
            return out
        return self.mk(*a1)

    def advance(self, n, h, accelerations):
        """n steps, then the node coordinates; returns (status, steps done, number of
        flagged nodes)."""
        sim = self.sim
        st, done = self._mk_steps(sim.t, h, n)
        if st != kernel.STATUS_OK:
            return st, done, 0
        if accelerations:
            st, _ = self._mk_steps(sim.t + n * h, 0.0, 0)
            if st != kernel.STATUS_OK:
                return st, done, 0
        nt = self.nodes
        q, qt, qtt = self.bufs
        jrow, jae, jsign, ae = self.jac
        a3 = (sim.sd.gid, sim.R, sim.r, sim.V, sim.wk.Vd[0], sim.wk.lam, bool(accelerations), nt.code, nt.body,
              nt.idx, nt.nq, nt.qref, nt.prev, q, qt, qtt, nt.flags, jrow, jae, jsign, ae)
        wr = self.wr.get(accelerations)
        if wr is None:
            nflag = write_all(*a3)
            self.wr[accelerations] = entry_point(write_all, a3) or write_all
            return st, done, nflag
        return st, done, wr(*a3)


class NodeTable:
    """All rigid nodes of a scene as flat arrays for :func:`~.nodes.write_all`."""

    def __init__(self, kinds, kindBodies):
        rows = sum(len(k) for k in kinds)
        self.code = np.zeros(rows, np.int64)
        self.body = np.zeros(rows, np.int64)
        self.idx = np.zeros((rows, NCOORD_MAX), np.int64)
        self.nq = np.zeros(rows, np.int64)
        self.qref = np.zeros((rows, NCOORD_MAX))
        self.prev = np.zeros((rows, 4))
        self.flags = np.zeros(rows, np.int64)
        self.kindOfRow = []
        i = 0
        for kind, bodies in zip(kinds, kindBodies):
            n = len(kind)
            m = 3 + kind.nrot
            self.code[i:i + n] = kind.code
            self.body[i:i + n] = bodies
            self.idx[i:i + n, :m] = kind.idx
            self.nq[i:i + n] = m
            self.qref[i:i + n, :m] = kind.qref
            self.prev[i:i + n] = kind.prev
            self.kindOfRow += [(kind, k) for k in range(n)]
            i += n

    def write(self, sim, Vdot, lam, doacc, q, qt, qtt, multipliers):
        """Node coordinates (and with ``doacc`` accelerations and the joint multipliers
        ``(rows, AE slots, signs, AE buffer)``); returns the number of nodes flagged (Rxyz
        near its singularity)."""
        jrow, jae, jsign, ae = multipliers
        return write_all(sim.sd.gid, sim.R, sim.r, sim.V, Vdot, lam, bool(doacc), self.code, self.body, self.idx,
                         self.nq, self.qref, self.prev, q, qt, qtt, self.flags, jrow, jae, jsign, ae)

    def warn_flags(self):
        for i in np.nonzero(self.flags)[0]:
            kind, k = self.kindOfRow[i]
            kind.singular_warning(k)
        self.flags[:] = 0

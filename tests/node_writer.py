"""Writing a state into Exudyn's coordinates node kind by node kind (the bridge's
:class:`~exudyn_lie.bridge.nodes.NodeKind` and its compiled row writer), for the tests that
compare the writer with the numpy maps and with Exudyn; the library writes all nodes in one
compiled call (bridge/fast.py)."""
import math

import numpy as np

from exudyn_lie.bridge.node_writers import WRITER_CODES, present_writers, write_row

ALL_WRITERS = present_writers(WRITER_CODES)          # every row writer


def write(kind, R, r, omega, vel, omegad=None, acc=None, q=None, q_t=None, q_tt=None):
    """Scatter the state into the full system vectors q, q_t (and q_tt if given);
    returns the total rotation parameters (n, nrot)."""
    n, m = len(kind), kind.nrot
    out = np.zeros((n, m))
    p_t = np.zeros(m)
    p_tt = np.zeros(m)
    zero = np.zeros(3)
    tmp = np.zeros(4)
    for i in range(n):
        p = out[i]
        flag = write_row(kind.code, np.ascontiguousarray(R[i], dtype=float),
                         np.ascontiguousarray(omega[i], dtype=float),
                         zero if omegad is None else np.ascontiguousarray(omegad[i], dtype=float),
                         kind.prev[i], kind.first, p, p_t, p_tt, 0.0, math.nan, tmp, ALL_WRITERS)
        ix = kind.idx[i]
        q[ix[:3]] = np.asarray(r[i]) - kind.qref[i, :3]
        q[ix[3:]] = p - kind.qref[i, 3:]
        q_t[ix[:3]] = vel[i]
        q_t[ix[3:]] = p_t
        if q_tt is not None and omegad is not None:
            q_tt[ix[:3]] = acc[i]
            q_tt[ix[3:]] = p_tt
        if flag:
            kind.singular_warning(i)
    kind.first = False
    return out


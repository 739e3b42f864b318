"""The stage state in mbs for Exudyn user functions that read it (compiled path).

In a native solve, mbs holds the iterate while Exudyn evaluates a load's or a connector's user
function, so a function may read the state from mbs instead of its arguments:
``mbs.GetSensorValues``, ``GetNodeOutput``, ``GetObjectOutputBody``, ``systemData.GetODE2Coordinates``
(a controller's load that reads a sensor, a contact written as a load).  The compiled stepper
evaluates those functions at its own stages, between the outputs it writes into mbs; such a
function read the state of the last output, up to several steps old, and the run integrated a
different model without a sign (a ball on a penalty floor written as a load: 35 m high at the
end, where it lies on the floor).  So, when a user function may read mbs, the stage state is
written into mbs' coordinates before the functions are called (:func:`install`), and mbs' state
is put back after the stepper returns (``StateIO._next_output``): a restart from the step's
start (an explicit method replaced, a run handed over) reads it there.

Whether a function may read mbs is decided from its code (:func:`may_read_mbs`): only a plain
Python function whose code, and that of the functions it calls by name, names no ``Get*``
attribute, no ``systemData`` and no other callable of its own module is taken not to; the
drop-in writes the stage for every other one.  The stage's time is not set in mbs (Exudyn's
loop owns it; the functions get ``t`` as argument)."""
from __future__ import annotations

import types

import numpy as np

from . import pyforces

#: attribute names through which a user function can read the state from mbs
STATE_ATTRIBUTES = ("systemData", "GetSensorValues", "GetSensorStoredData")
DEPTH = 3                # functions called by name followed this deep


def _code_names(code, out):
    out.update(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            _code_names(c, out)
    return out


def may_read_mbs(fn, depth=DEPTH):
    """Whether the user function ``fn`` may read the state from mbs (module docstring); True when
    its code cannot be read."""
    fn = getattr(fn, "__func__", fn)
    if fn is None:
        return False
    if not isinstance(fn, types.FunctionType):
        return True                        # a callable object, a builtin, Exudyn's symbolic function
    names = _code_names(fn.__code__, set())
    if any(n.startswith("Get") or n in STATE_ATTRIBUTES for n in names):
        return True
    scope = dict(fn.__globals__)
    if fn.__closure__:
        for name, cell in zip(fn.__code__.co_freevars, fn.__closure__):
            try:
                scope[name] = cell.cell_contents
            except ValueError:             # an empty cell
                pass
    for n in names | set(fn.__code__.co_freevars):
        v = scope.get(n)
        if isinstance(v, (types.FunctionType, types.MethodType)) or (
                callable(v) and not isinstance(v, (type, types.ModuleType, types.BuiltinFunctionType, np.ufunc))):
            if depth <= 0 or may_read_mbs(v, depth - 1):
                return True
    return False


def user_functions(items):
    """The Python user functions of the bridge's Python items."""
    return [it.uf for it in items if getattr(it, "uf", None) is not None]


def _combined(solver):
    found = [pf.fn for pf in solver.scene.pythonForces if isinstance(pf.fn, pyforces.Combined)]
    return found[0] if found else None


def needed(solver):
    """Whether a user function of ``solver``'s Python items may read the state from mbs."""
    comb = _combined(solver)
    return comb is not None and any(may_read_mbs(f) for f in user_functions(comb.items))


def install(solver):
    """Before the compiled path's Python items are called at a stage, the stage state into mbs'
    coordinates (a :class:`~.solver.LieGroupSolver` after its buffers are made), when one of their
    user functions may read it; returns whether it did."""
    comb = _combined(solver)
    solver._stageWrites = False
    if comb is None:
        return False
    if not needed(solver):
        comb.before = None
        return False
    solver._stageWrites = True
    sim, nodes = solver.sim, solver._nodes
    q, qt, live, mbs = solver._q, solver._qt, solver._live, solver.mbs

    def write(t, st):
        wk = sim.wk
        nodes.write_state(sim, t, wk.Rs, wk.rs, wk.Vs, q, qt)
        if not live:
            import exudyn as exu
            cur = exu.ConfigurationType.Current
            mbs.systemData.SetODE2Coordinates(q, configuration=cur)
            mbs.systemData.SetODE2Coordinates_t(qt, configuration=cur)
    comb.before = write
    return True

"""Which path ``SolveDynamic`` takes: the compiled kernel when it has every item of the
model, else the Exudyn-evaluated path (:mod:`.evaluated_solve`), which the user can also
force with ``evaluation='exudyn'``.

The decision reads only: item types the compiled reader does not know
(:func:`foreign_items`: types without a registration in :mod:`.items`), else the reader's own check of the model
(:func:`~.reader.SceneFromExudyn`), whose :class:`~.reader.NotCompiled` errors (an option of a
known item the kernel lacks, a PostNewtonUserFunction) also select the evaluated path; any
other error of the reader (bad input) is raised as it is.
"""
from __future__ import annotations

from . import items
from .reader import BridgeError, NotCompiled, SceneFromExudyn
from .settings import liegroup_argument


def _listing(kind, idx):
    shown = ", ".join(str(i) for i in idx[:4]) + (f", ... ({len(idx)} in all)" if len(idx) > 4 else "")
    return f"{kind}{'s' if len(idx) > 1 else ''} {shown}"


def foreign_items(mbs):
    """Descriptions of the items whose type the compiled kernel does not have, one per
    type (``ObjectANCFCable2D (objects 1, 2, 3, 4)``)."""
    sd = mbs.systemData
    found = {}

    def add(typeName, kind, i):
        found.setdefault(typeName, (kind, []))[1].append(i)

    for kind, count, getter, key in (("node", sd.NumberOfNodes(), mbs.GetNode, "nodeType"),
                                     ("object", sd.NumberOfObjects(), mbs.GetObject, "objectType"),
                                     ("marker", sd.NumberOfMarkers(), mbs.GetMarker, "markerType"),
                                     ("load", sd.NumberOfLoads(), mbs.GetLoad, "loadType")):
        for i in range(count):
            t = getter(i)[key]
            if (kind, t) not in items.ITEMS:        # registered in bridge/items.py: the compiled reader's
                add(items.PREFIX[kind] + t, kind, i)
    out = [f"{t} ({_listing(kind, idx)})" for t, (kind, idx) in found.items()]
    n = int(mbs.NumberOfGeneralContacts())
    if n:
        out.append(f"{n} GeneralContact(s)")
    return out


def _compiled_read(mbs, assemble):
    """``(scene, None)`` if the compiled reader takes the model (the scene it read, so that the
    compiled path does not read the model again), else ``(None, why not)`` (its NotCompiled
    error); other errors (bad input) are raised."""
    try:
        return SceneFromExudyn(mbs, "items" if assemble else "initial"), None
    except NotCompiled as e:
        return None, str(e)


def evaluated_path(mbs, evaluation, assemble, *, method, liegroup, stabilization, projectInitial, verbose, settings,
                   substeps, autoImplicit=False):
    """``(EvaluatedSolver of the run, None)``, or ``(None, the compiled reader's scene or None)``
    for the compiled path.  Raises before mbs is touched for input neither path takes."""
    from .evaluated_solve import EvaluatedSolver
    from .solver import _check_method
    if evaluation == "auto":
        reasons = foreign_items(mbs)
        if not reasons:
            scene, why = _compiled_read(mbs, assemble)
            if why is None:
                return None, scene
            reasons = [why.rstrip(".")]
    else:
        reasons = None
    if stabilization not in (None, "none", "velocity", "position"):
        raise BridgeError(f"unknown stabilization {stabilization!r}; use None, 'velocity' or 'position'")
    tab = _check_method(method)
    lg = liegroup_argument(liegroup)
    solver = EvaluatedSolver(mbs, tab, lg, verbose=verbose, reasons=reasons, projectInitial=projectInitial,
                             stabilization=stabilization,
                             autoImplicit=autoImplicit)
    solver.check_run(settings, substeps)
    return solver, None

"""Parameters changed during a solve: honoured as in a native solve, or a clear stop.

User functions change item parameters while Exudyn's time loop runs: a PD controller sets
``loadVector`` every step, a switch sets ``activeConnector``, a moving reference frame sets
a ground marker's ``localPosition`` or a ground's ``referencePosition``.  A native solve
reads the new value at its next evaluation; a pre-step change therefore acts on the whole
following step, a post-step change on the step after it (Exudyn's ``InitializeStep`` calls
the pre-step function before the step's Newton iteration, ``FinishStep`` the post-step
function after it; ``CSolverBase::SolveSteps``).

How the bridge does the same (:class:`ParameterWatch`): while Exudyn's time loop runs, the
``exudyn.MainSystem`` methods ``Set{Object,Node,Marker,Load}Parameter`` and
``Modify{Object,Node,Marker,Load}`` are wrapped (class attributes, restored in a
``finally``) so that each call on the solved ``mbs`` records the item.  Before the next
integration step the bridge re-reads only the recorded items and writes the compiled rows
they own (a load's ``SceneData.loadVectors / loadIndex`` row; a connector's row of every field of its
force element, rewritten by the element's registration from the item the reader reads again,
:func:`~exudyn_lie.mbs.force_elements.write_row`), or refreshes their Python force items
(:mod:`.pyforces`).  A controller setting 12 load vectors per step costs 12 dictionary reads
and 12 row writes, not a new scene.

Every field of every supported item has a status in :data:`FIELDS`:

* ``live``: read at the start, and a change during the solve acts from the next step;
* ``fixed``: read at the start; it shapes the compiled model (markers, nodes, joint axes,
  masses), so a change during the solve stops it with a :class:`BridgeError` naming the
  item and the field, at the step where it changed;
* ``refused``: only Exudyn's default is supported (refused before ``mbs`` is touched);
* ``initial``: an initial value, used by ``Assemble`` only (no effect during a solve, as
  in Exudyn);
* ``ignored``: no effect on the motion (names, visualization ``V...`` fields).

A change made from inside a force user function while the bridge integrates a step
(Exudyn would see it at its next Newton evaluation, within the step) stops the solve: the
bridge applies changes between steps only.
"""
from __future__ import annotations

import math

import numpy as np

from . import items
from .items import FIXED, IGNORED, INITIAL, ITEMS, LIVE, REFUSED  # noqa: F401 (the statuses)
from ..mbs.force_elements import element
from ..mbs.scene import SceneError
from .reader import BridgeError, ExudynScene, _userfunction

# the status of every field of every supported item type comes from its registration
# (bridge/items.py); FIELDS: (kind, type) -> {field: (status, reason)}
FIELDS = items.FIELDS

_COMMON = {"name": (IGNORED, "a label"), "objectType": (IGNORED, "the item type"),
           "nodeType": (IGNORED, "the item type"), "markerType": (IGNORED, "the item type"),
           "loadType": (IGNORED, "the item type")}

_KINDS = {  # kind -> (getter, type key, label)
    "object": ("GetObject", "objectType", "object"),
    "node": ("GetNode", "nodeType", "node"),
    "marker": ("GetMarker", "markerType", "marker"),
    "load": ("GetLoad", "loadType", "load"),
}
_PREFIX = {"object": "Object", "node": "Node", "marker": "Marker", "load": "Load"}
_WRAPPED = {  # MainSystem method -> kind (the item index is the first argument)
    "SetObjectParameter": "object", "SetNodeParameter": "node", "SetMarkerParameter": "marker",
    "SetLoadParameter": "load", "ModifyObject": "object", "ModifyNode": "node", "ModifyMarker": "marker",
    "ModifyLoad": "load",
}


def is_visualization(key):
    """Exudyn's convention: visualization fields start with a capital ``V`` (``Vshow``,
    ``VgraphicsData``); every other field starts with a lower-case letter."""
    return key[:1] == "V"


def field_status(kind, itemType, key):
    """``(status, reason)`` of field ``key`` of an Exudyn item, or None if unknown."""
    if is_visualization(key):
        return (IGNORED, "visualization")
    if key in _COMMON:
        return _COMMON[key]
    return FIELDS.get((kind, itemType), {}).get(key)


def _same(a, b):
    """Equal Exudyn field values (numbers, arrays, lists, user-function dictionaries)."""
    if isinstance(a, dict) or isinstance(b, dict) or callable(a) or callable(b):
        fa = a.get("function", a) if isinstance(a, dict) else a
        fb = b.get("function", b) if isinstance(b, dict) else b
        return fa is fb
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    try:
        return bool(np.array_equal(np.asarray(a, float), np.asarray(b, float)))
    except (TypeError, ValueError):
        return a == b


def _finite(x, what, key):
    if isinstance(x, (float, int)):          # most fields: a number (the fast check, once per changed field)
        ok = math.isfinite(x)
    else:
        x = np.asarray(x, float)
        ok = bool(np.isfinite(x).all())
    if not ok:
        raise BridgeError(f"{what}: {key} set to a non-finite value {x!r} during the solve")
    return x


class MainSystemPatch:
    """While entered (Exudyn's loop runs), the ``exudyn.MainSystem`` methods ``patched`` are replaced
    by ``self.wrap(original, name)``; the originals are put back on exit."""
    patched = ()

    def wrap(self, orig, name):
        raise NotImplementedError

    def __enter__(self):
        import exudyn as exu
        self._saved = {}
        for name in self.patched:
            orig = self._saved[name] = getattr(exu.MainSystem, name)
            setattr(exu.MainSystem, name, self.wrap(orig, name))
        return self

    def __exit__(self, *exc):
        import exudyn as exu
        for name, orig in self._saved.items():
            setattr(exu.MainSystem, name, orig)
        self._saved = {}
        return False


class FixedParameterChanged(BridgeError):
    """A user function changed a parameter the compiled kernel holds fixed (items.FIXED, such as a
    joint's ``activeConnector``) before the step that starts at ``t``: with evaluation='auto' the run
    continues on the Exudyn-evaluated path (:meth:`~.solver.LieGroupSolver.hand_over`)."""

    def __init__(self, message, t, what):
        super().__init__(message)
        self.t, self.what = t, what


class ParameterWatch(MainSystemPatch):
    """Records the items a user function changes during ``Solve`` and applies the changes
    to the compiled scene before the next step.

    ``marks`` (a list, empty when nothing changed: the per-step check is its truth value)
    holds ``(kind, index, field or None, value or None)``; :meth:`apply` consumes it."""

    def __init__(self, solver):
        self.solver = solver
        self.mbs = solver.mbs
        self.scene: ExudynScene = solver.scene
        self.reader = self.scene.reader
        self.marks = []
        self.busy = False            # True while the bridge integrates (changes then are refused)
        self.late = []               # changes recorded while busy
        self._saved = {}
        self.updates = 0             # items re-read (for the bench and tests)
        self._fastLoad = {}          # compiled load -> (its loadVectors row view, marker rotation if bodyFixed)
        self._build_maps()

    # ------------------------------------------------------------------ set-up
    def _build_maps(self):
        mbs, sd = self.mbs, self.mbs.systemData
        self.snap = {}
        self.nItems = {"object": sd.NumberOfObjects(), "node": sd.NumberOfNodes(), "marker": sd.NumberOfMarkers(),
                       "load": sd.NumberOfLoads()}
        self.markerUsers = {}        # marker -> [("load", l) | ("object", o)]
        self.markersOn = {}          # ("object", ground o) / ("node", ground node n) -> [markers]
        self.fixedOffsets = {}       # ConnectorCoordinate -> its offset, held by a compiled row
        for o in range(self.nItems["object"]):
            d = self.snap[("object", o)] = mbs.GetObject(o)
            if d["objectType"] == "ConnectorCoordinate" and o not in self.scene.movableOffsets:
                self.fixedOffsets[o] = d.get("offset", 0.0)
            for m in d.get("markerNumbers", []):
                self.markerUsers.setdefault(int(m), []).append(("object", o))
        for l in range(self.nItems["load"]):
            d = self.snap[("load", l)] = mbs.GetLoad(l)
            self.markerUsers.setdefault(int(d["markerNumber"]), []).append(("load", l))
        for m in range(self.nItems["marker"]):
            d = self.snap[("marker", m)] = mbs.GetMarker(m)
            if "bodyNumber" in d:
                self.markersOn.setdefault(("object", int(d["bodyNumber"])), []).append(m)
            elif "nodeNumber" in d:
                self.markersOn.setdefault(("node", int(d["nodeNumber"])), []).append(m)
        for n in range(self.nItems["node"]):
            self.snap[("node", n)] = mbs.GetNode(n)

    patched = tuple(_WRAPPED)

    def wrap(self, orig, name):
        return self._wrapper(orig, _WRAPPED[name], name.startswith("Set"), self.mbs)

    def _wrapper(self, orig, kind, named, target):
        marks, late = self.marks, self.late
        watch = self

        def wrapped(mbs, *args, **kw):
            out = orig(mbs, *args, **kw)
            if mbs is target:
                if named and len(args) > 2:          # Set*Parameter(index, name, value): the common call
                    # a load vector's value, copied (a controller may reuse its buffer): the short path
                    mark = (kind, int(args[0]), args[1], tuple(args[2]) if args[1] == "loadVector" else None)
                else:
                    index = int(args[0]) if args else int(kw.get(kind + "Number", next(iter(kw.values()))))
                    mark = (kind, index, kw.get("parameterName") if named else None, None)
                (late if watch.busy else marks).append(mark)
            return out
        wrapped.__doc__ = orig.__doc__
        wrapped.__wrapped__ = orig
        return wrapped

    # ------------------------------------------------------------------ apply
    def what(self, kind, i, d=None):
        d = self.snap.get((kind, i), {}) if d is None else d
        return f"{_KINDS[kind][2]} {i} ('{d.get('name', '')}') {_PREFIX[kind]}{d.get(_KINDS[kind][1], '?')}"

    def apply(self, t):
        """Apply the recorded changes (made before the step that starts at ``t``)."""
        if self.late:
            kind, i, field, _ = self.late[0]
            del self.late[:]
            raise BridgeError(
                f"{self.what(kind, i)}: {field or 'its dictionary'} was changed by a user function while exudyn_lie "
                f"integrated the step ending at t = {t:.6g} s (a force or load user function); exudyn_lie applies "
                f"parameter changes between steps: change it in a pre-step user function (mbs.SetPreStepUserFunction)")
        marks = self.marks[:]              # (a repeated mark re-reads the item again: cheaper than de-duplicating)
        del self.marks[:]
        rebuild = {}
        fast = self._fastLoad
        for kind, i, field, value in marks:
            if field == "loadVector" and kind == "load" and i in fast:
                self._load_vector(i, fast[i], value, t)
                continue
            if i >= self.nItems[kind] or i < 0:
                continue                 # Exudyn raised for this index; nothing was changed
            getter = getattr(self.mbs, _KINDS[kind][0])
            new = getter(i)
            old = self.snap[(kind, i)]
            itemType = new[_KINDS[kind][1]]
            # a named field is checked directly; Modify*, and names that are aliases of a
            # dictionary key (SetObjectParameter(i, 'physicsMass', ...) sets 'mass'), by a diff
            keys = [field] if field in new else [k for k in new if not is_visualization(k)
                                                 and not _same(new[k], old.get(k))]
            for key in keys:
                st = field_status(kind, itemType, key)
                if st is None:
                    raise BridgeError(f"{self.what(kind, i, new)}: field '{key}' changed at t = {t:.6g} s is not "
                                      f"known to exudyn_lie; solve with exudyn.SolveDynamic")
                status, why = st
                if status == FIXED and not _same(new.get(key), old.get(key)):
                    raise FixedParameterChanged(
                        f"{self.what(kind, i, new)}: parameter '{key}' changed during the solve at t = {t:.6g} s; "
                        f"exudyn_lie cannot change it during a run ({why}); set it before the solve, or solve "
                        f"with exudyn.SolveDynamic", t, f"{self.what(kind, i, new)}: parameter '{key}'")
                if status == REFUSED and not _same(new.get(key), old.get(key)):
                    raise BridgeError(
                        f"{self.what(kind, i, new)}: parameter '{key}' changed during the solve at t = {t:.6g} s; "
                        f"exudyn_lie cannot change it during a run ({why}); set it before the solve, or solve "
                        f"with exudyn.SolveDynamic")
                if status == LIVE:
                    rebuild[(kind, i)] = True
            self.snap[(kind, i)] = new
        if rebuild:
            self._rebuild(list(rebuild), t)

    def _rebuild(self, items, t):
        rd = self.reader
        markers = []
        targets = {}
        for kind, i in items:
            d = self.snap[(kind, i)]
            if kind == "object" and d["objectType"] == "Ground":
                H = np.asarray(d["referenceRotation"], float)
                rd.ground[i] = (np.asarray(d["referencePosition"], float), H)
                markers += self.markersOn.get(("object", i), [])
            elif kind == "node":         # a ground node (rigid-node reference coordinates are fixed)
                markers += self.markersOn.get(("node", i), [])
            elif kind == "marker":
                markers.append(i)
            else:
                targets[(kind, i)] = None
        for m in dict.fromkeys(markers):
            rd.markers.pop(m, None)
            for user in self.markerUsers.get(m, []):
                if user[0] == "object" and ITEMS[("object", self.snap[user]["objectType"])].role == "joint":
                    raise BridgeError(
                        f"{self.what(*user)}: its marker {m} ({self.what('marker', m)}) moved during the solve at "
                        f"t = {t:.6g} s; exudyn_lie cannot move a joint's marker during a run (a moving joint frame "
                        f"needs its velocity and acceleration in the index-1 formulation); solve with "
                        f"exudyn.SolveDynamic, or attach the joint to a body whose motion you prescribe")
                targets[user] = None
        for kind, i in targets:
            d = self.snap[(kind, i)]
            if kind == "load" and d["loadType"] == "Coordinate":
                self._coordinate_load(i, d, t)
            elif kind == "load":
                self._load(i, d, t)
            elif ITEMS[("object", d["objectType"])].role == "connector":
                self._connector(i, d, t)
            elif ITEMS[("object", d["objectType"])].role == "joint":
                self._joint_offset(i, d, t)
            # other objects (ground, bodies, joints) have no live field besides the above
            self.updates += 1

    def _joint_offset(self, o, d, t):
        """A joint's live field is a ConnectorCoordinate's ``offset``, which its row reads at
        every step when a step function may move it (bridge/moving_offsets.py); another
        row (a velocity-level one, or one read without a step function) holds it fixed."""
        if o not in self.fixedOffsets or not d.get("activeConnector", True) \
                or _same(d.get("offset", 0.0), self.fixedOffsets[o]):
            return
        raise BridgeError(
            f"{self.what('object', o, d)}: parameter 'offset' changed during the solve at t = {t:.6g} s; exudyn_lie "
            f"follows a moved offset only on a position-level row and when it is moved by a pre- or post-step "
            f"function (mbs.SetPreStepUserFunction); set it there, or solve with exudyn.SolveDynamic")

    def _load(self, l, d, t):
        sc, rd = self.scene, self.reader
        table, k = sc.itemRows[("load", l)]
        lt = d["loadType"]
        what = self.what("load", l, d)
        lv = _finite(d["loadVector"], what, "loadVector")
        uf = _userfunction(d, "loadVectorUserFunction", what)
        if (uf is not None) != (table == "py") and table != "ground":
            raise BridgeError(f"{what}: loadVectorUserFunction was {'set' if uf is not None else 'removed'} during "
                              f"the solve at t = {t:.6g} s; exudyn_lie compiles constant loads and evaluates loads "
                              f"with a user function in Python, and cannot switch during a run; set it before "
                              f"the solve")
        mf = rd.marker(d["markerNumber"], what, allow_mass=(lt == "MassProportional"))
        if table == "ground":
            return
        if table == "massProportional":
            raise BridgeError(f"{what}: parameter 'loadVector' changed during the solve at t = {t:.6g} s; a constant "
                              f"mass-proportional load is compiled as gravity and cannot change during a run; give "
                              f"it a loadVectorUserFunction to vary it")
        bodyFixed = bool(d.get("bodyFixed", False))
        if mf.rot is None and (lt == "TorqueVector" or bodyFixed):
            raise BridgeError(f"{what}: bodyFixed=True needs a marker with an orientation at t = {t:.6g} s "
                              f"(Exudyn refuses it too)")
        if table == "py":
            item = sc.pyItems[k]
            item.lv, item.uf, item.mf, item.bodyFixed = lv, uf, mf, bodyFixed
            if getattr(item, "probeIndex", None) is not None:     # its point, read by the compiled stage
                self.solver.sim.SetProbeRow(item.probeIndex, _probe_row(item, what, t))
            return
        vector, point, flags = self.solver.sim.LoadRow(k)       # flags: [body, kind, bodyFixed]
        vector[:] = mf.rotation() @ lv if bodyFixed else lv
        point[:] = mf.pos if lt == "ForceVector" else 0.0
        flags[2] = int(bodyFixed)
        # from now on a new loadVector alone takes the short path (a controller's every step)
        self._fastLoad[l] = (vector, mf.rotation() if bodyFixed else None)

    def _coordinate_load(self, l, d, t):
        """LoadCoordinate: the new ``load`` (or user function) into its compiled load row, a
        world force ``load e_axis`` at the node (reader_forces.read_coordinate_load), or its Python item."""
        table, k = self.scene.itemRows[("load", l)]
        what = self.what("load", l, d)
        load = float(_finite(d["load"], what, "load"))
        uf = _userfunction(d, "loadUserFunction", what)
        if table == "ground":
            return
        if (uf is not None) != (table == "py"):
            raise BridgeError(f"{what}: loadUserFunction was {'set' if uf is not None else 'removed'} during the "
                              f"solve at t = {t:.6g} s; exudyn_lie compiles constant loads and evaluates loads with a "
                              f"user function in Python, and cannot switch during a run; set it before the solve")
        if table == "py":
            item = self.scene.pyItems[k]
            item.load, item.uf = load, uf
            return
        if table == "coordinateLoad":        # a node rotation parameter: f0 = -load of its coordinate spring row
            self.solver.sim.SetCoordinateSpringForce(k, -load)
            return
        cm = self.reader.coordinate_marker(d["markerNumber"], what)
        self.solver.sim.LoadRow(k)[0][:] = load * cm.direction

    def _load_vector(self, l, row, value, t):
        """Only ``loadVector`` of a compiled load changed: the new vector (the value Exudyn
        accepted in ``SetLoadParameter``, read back if it is not a plain 3-vector) into its
        row; the marker frame and bodyFixed are as at the last full re-read (:meth:`_load`)."""
        target, Rm = row
        try:
            x, y, z = value                      # None (not recorded) raises TypeError
            x, y, z = float(x), float(y), float(z)
            ok = math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
        except (TypeError, ValueError):
            v = self.mbs.GetLoadParameter(l, "loadVector")
            x, y, z = (float(c) for c in v) if len(v) == 3 else (np.nan,) * 3
            ok = math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
        if not ok:
            self._load(l, self.mbs.GetLoad(l), t)          # raises with the full message
            return
        if Rm is None:
            target[0] = x
            target[1] = y
            target[2] = z
        else:
            np.dot(Rm, np.array((x, y, z)), out=target)
        # (the snapshot keeps the old vector: a later Modify* diff then re-reads the load, harmless)
        self.updates += 1

    def _connector(self, o, d, t):
        """A connector (or one of its markers) changed: the reader reads it again with the code
        that read it before the solve (reader_forces.reread_connector: marker frames, velocityOffset
        folded, activeConnector, the torsional spring's kept turns), and its compiled row is
        rewritten by its force element's registration (force_elements.write_row: the row
        builders of its SceneData fields, its Work table's ``writeRow``); an item evaluated in
        Python is refreshed in place."""
        sc = self.scene
        row = sc.itemRows.get(("object", o))
        if row is None:
            return                       # ground to ground: no force on any body
        table, k = row
        what = self.what("object", o, d)
        it = ITEMS[("object", d["objectType"])]
        uf = _userfunction(d, it.userFunction, what) if it.userFunction else None
        if uf is not None and table != "py":
            raise BridgeError(f"{what}: {it.userFunction} was set during the solve at t = {t:.6g} s; exudyn_lie "
                              f"compiled the connector without it and cannot switch during a run; set it before "
                              f"the solve")
        if table != "py":
            for key, (status, _) in it.fields.items():
                if status == LIVE and key in d and not key.endswith("UserFunction") and key != "activeConnector":
                    _finite(d[key], what, key)
        try:
            scratch, new = self.reader.reread_connector(sc, o, d)
        except SceneError as e:             # (a BridgeError is one)
            raise BridgeError(f"{e} (changed during the solve at t = {t:.6g} s)") from None
        if table == "py":
            self._python_connector(o, d, k, scratch, new, t)
            return
        if new is None or new[0] != table:
            raise BridgeError(f"{what}: changed at t = {t:.6g} s so that exudyn_lie would compile it otherwise "
                              f"({table} -> {new and new[0]}); set its parameters before the solve")
        e = element(table)
        try:
            self.solver.sim.WriteElementRow(e, sc, k, getattr(scratch, e.sceneList)[0])
        except ValueError as err:
            raise BridgeError(f"{what}: changed during the solve at t = {t:.6g} s: {err}") from None

    def _python_connector(self, o, d, k, scratch, new, t):
        """A connector evaluated in Python: its item replaced by the one read again, keeping
        its angle tracking."""
        if new is None or new[0] != "py":
            raise BridgeError(f"{self.what('object', o, d)}: changed at t = {t:.6g} s so that it is no longer "
                              f"evaluated in Python; set its parameters before the solve")
        item = self.scene.pyItems[k]
        keep = {key: getattr(item, key) for key in ("prev", "probeIndex") if hasattr(item, key)}
        item.__dict__.update(scratch.pyItems[0].__dict__)
        item.__dict__.update(keep)
        item.active = bool(d.get("activeConnector", True))
        if getattr(item, "probeIndex", None) is not None:     # its frames, read by the compiled stage
            self.solver.sim.SetProbeRow(item.probeIndex, _probe_row(item, self.what('object', o, d), t))


def _probe_row(item, what, t):
    """The changed item's probe row (mbs/external_probes.py): it had one, so it must keep one."""
    row = item.probe_row()
    if row is None:
        raise BridgeError(f"{what}: changed at t = {t:.6g} s so that the compiled stage can no longer compute "
                          f"its kinematics; set its parameters before the solve")
    return row

"""The compiled force elements (connectors), one registration each.

A registration (:func:`register`) names the element's list in :class:`~.scene.Scene`
(``springs``, ...), its fields of :class:`~.compiled.SceneData` with how each is built from
the scene's items, its forces entry ``(sd, wk, R, r, V, Q)`` and, if it has a potential, its
energy entry ``(sd, wk, R, r, V, e) -> e + its energy`` (both in the element's own file, both
``inline="always"`` around functions with array arguments: a compiled function of its own
that receives the SceneData / Work tuples costs compile time steeply).
From :data:`ELEMENTS` derive:

* the element fields of ``SceneData`` and their part of ``compile_scene`` (:mod:`.compiled`);
* :func:`compute_forces`, the applied and inertial forces of a stage (generated below: one
  call per element, in registration order; a ``lean`` element's call is guarded by
  ``if <its table>.shape[0] > 0:``, any other element's goes through
  :func:`~.presence.guarded`, which compiles to nothing when its table is None, i.e. in a
  lean scene);
* :func:`spring_energy`, the elements' potential (:mod:`.diagnostics`);
* ``Scene.CONNECTOR_LISTS``, the scene's lists of two-body force elements (:mod:`.scene`).

The order of the registrations is the order of the SceneData fields and of the force sums:
it is kept as it was (a changed SceneData layout changes the per-step speed, see Work in
:mod:`.compiled`, and a changed sum order changes the last bits).  Adding a force element:
its scene dataclass and ``Add*`` (:mod:`.scene`), its own file with the force function and
the entries, and one :func:`register` line here.
"""
import sys
from collections import namedtuple

import numpy as np
from numba import njit

from .codegen import generate
from .coordinate_forces import coordinate_spring_element, coordinate_spring_element_energy
from .forces import (cartesian_element, cartesian_element_energy, gravity_forces, inertial_forces, load_forces,
                     rigid_spring_element, spring_element, spring_element_energy, torsional_element,
                     torsional_element_energy)
from .linear_spring_forces import linear_spring_element
from .presence import guarded
from .rolling_disc_penalty_forces import rolling_disc_penalty_element, write_rolling_disc_penalty_row

# one compiled force element: its Scene list, its SceneData fields ((name, build(scene, items)), ...;
# the first is its integer table, whose rows say whether the scene has the element), its entries;
# writeRow(sd, wk, k, item): its compiled data kept outside its fields (a Work table), rewritten
# from a changed scene item (write_row); lean: part of a lean scene (:mod:`.presence`)
ForceElement = namedtuple("ForceElement", ["name", "sceneList", "fields", "forces", "energy", "table", "writeRow",
                                           "lean"])

#: every compiled force element, in registration order
ELEMENTS = []


def register(name, sceneList, fields, forces, energy=None, table=None, writeRow=None, lean=False):
    """Register one compiled force element (module docstring).  ``table``: the array whose rows
    say whether the scene has the element, as an expression on the scene tuples (default: its
    first SceneData field); an element whose data change after each step keeps them in
    ``Work`` (e.g. ``wk.path.rollingDiscs``), registers no SceneData field and gives ``writeRow(sd, wk, k,
    item)``, which rewrites its row ``k`` from a changed scene item (:func:`write_row`).
    ``lean``: part of a lean scene (:mod:`.presence`); the fields of any other element are None
    in a lean scene and its code is compiled only for full scenes."""
    if any(e.name == name for e in ELEMENTS):
        raise ValueError(f"force element {name!r} is registered twice")
    fields = tuple(fields)
    if not fields and writeRow is None:
        raise ValueError(f"force element {name!r}: without SceneData fields it needs writeRow (its Work table)")
    ELEMENTS.append(ForceElement(name, sceneList, fields, forces, energy, table or f"sd.{fields[0][0]}", writeRow,
                                 bool(lean)))


def table(row, shape, dtype=float):
    """A field built row by row from the element's items (zero rows when there are none).
    The builder keeps ``row``, ``shape`` and ``dtype``: :func:`write_row` rewrites one row."""
    def build(scene, items):
        a = np.array([row(s) for s in items], dtype=dtype)
        return a.reshape(shape) if a.size else np.zeros((0,) + tuple(shape[1:]), dtype)
    build.row, build.shape, build.dtype = row, tuple(shape), dtype
    return build


def _angles(scene, items):
    """Rotation coordinates of the coordinate items (springs and constraints), tracked by
    mbs/coordinate_angles.py (code 1: an angle; node rotation parameters, codes >= 10, are tracked per body)."""
    return int(sum((s.angleA[0] == 1) + (s.angleB[0] == 1) for s in items)
               + sum((j.coordinate[4] == 1) + (j.coordinate[5] == 1) for j in scene.joints if j.coordinate is not None))


# ---------------------------------------------------------------- the registrations
register("spring", "springs", (
    ("springBodies", table(lambda s: [s.bodyA, s.bodyB], (-1, 2), np.int64)),
    ("springPoints", table(lambda s: [s.posA, s.posB], (-1, 2, 3))),
    ("springLaw", table(lambda s: [s.stiffness, s.damping, s.referenceLength, s.force], (-1, 4)))),
         spring_element, spring_element_energy, lean=True)
register("cartesian", "cartesianSprings", (
    ("cartesianBodies", table(lambda s: [s.bodyA, s.bodyB], (-1, 2), np.int64)),
    ("cartesianPoints", table(lambda s: [s.posA, s.posB], (-1, 2, 3))),
    ("cartesianLaw", table(lambda s: [s.stiffness, s.damping, s.offset], (-1, 3, 3)))),
         cartesian_element, cartesian_element_energy)
register("torsional", "torsionalSprings", (
    ("torsionBodies", table(lambda s: [s.bodyA, s.bodyB], (-1, 2), np.int64)),
    ("torsionFrames", table(lambda s: [s.rotA, s.rotB], (-1, 2, 3, 3))),
    ("torsionLaw", table(lambda s: [s.stiffness, s.damping, s.offset, s.torque], (-1, 4)))),
         torsional_element, torsional_element_energy)
register("coordinate", "coordinateSprings", (
    ("coordSpringEnds", table(lambda s: [s.bodyA, s.bodyB, int(s.angleA[0]), int(s.angleB[0])], (-1, 4), np.int64)),
    ("coordSpringLaw", table(lambda s: [s.stiffness, s.damping, s.offset, *s.axisA, *s.axisB, s.force], (-1, 10))),
    ("coordSpringFrames", table(lambda s: [s.angleA[1], s.angleB[1]], (-1, 2, 3, 3))),
    ("nCoordAngles", _angles)),
         coordinate_spring_element, coordinate_spring_element_energy)
register("linear", "linearSprings", (
    ("linearBodies", table(lambda s: [s.bodyA, s.bodyB], (-1, 2), np.int64)),
    ("linearPoints", table(lambda s: [s.posA, s.posB], (-1, 2, 3))),
    ("linearAxis", table(lambda s: s.axisA, (-1, 3))),
    ("linearLaw", table(lambda s: [s.stiffness, s.damping, s.offset, s.force], (-1, 4)))),
         linear_spring_element)
register("rigid", "rigidSprings", (
    ("rigidSpringBodies", table(lambda s: [s.bodyA, s.bodyB, int(s.intrinsic)], (-1, 3), np.int64)),
    ("rigidSpringPoints", table(lambda s: [s.posA, s.posB], (-1, 2, 3))),
    ("rigidSpringFrames", table(lambda s: [s.rotA, s.rotB], (-1, 2, 3, 3))),
    ("rigidSpringLaw", table(lambda s: np.vstack([s.stiffness, s.damping, s.offset[None]]), (-1, 13, 6)))),
         rigid_spring_element)
# the penalty rolling disc: bodies, flags, law and data coordinates packed into one path-state table,
# PathState.rollingDiscs (the data change after every accepted step: the contact-data step observer)
register("rollingDiscPenalty", "rollingDiscPenalties", (), rolling_disc_penalty_element, table="wk.path.rollingDiscs",
         writeRow=write_rolling_disc_penalty_row)


def scene_fields():
    """The element fields of SceneData, in registration order."""
    return [f for e in ELEMENTS for f, _ in e.fields]


def lean_elements_only(scene):
    """Whether the scene has items of lean elements only (:mod:`.presence`)."""
    return not any(getattr(scene, e.sceneList) for e in ELEMENTS if not e.lean)


def compile_elements(scene, lean=False):
    """The element fields' values for ``compile_scene``: {field: value}; with ``lean``, None
    for the fields of the elements that are not lean."""
    out = {}
    for e in ELEMENTS:
        items = getattr(scene, e.sceneList)
        for f, build in e.fields:
            out[f] = None if (lean and not e.lean) else build(scene, items)
    return out


def element(name):
    """The registration of the element named ``name`` (the tables of the bridge's itemRows)."""
    for e in ELEMENTS:
        if e.name == name:
            return e
    raise KeyError(f"no force element {name!r}; registered: {[e.name for e in ELEMENTS]}")


def write_row(e, scene, sd, wk, k, item):
    """Rewrite row ``k`` of element ``e``'s compiled data with ``item``, the new scene item
    (a parameter changed during a run, bridge/params.py), by the registration's own builders:
    each row field's ``row(item)``, then the ``writeRow`` hook (a Work table).  A field built
    from the whole scene (``nCoordAngles``) cannot change during a run: it is recomputed with the
    item replaced and must stay as compiled (ValueError otherwise).  ``scene``'s item ``k`` is
    replaced too, so that scene and compiled rows agree."""
    items = getattr(scene, e.sceneList)
    old = items[k]
    items[k] = item
    try:
        for f, build in e.fields:
            if hasattr(build, "row"):
                continue
            if not np.array_equal(np.asarray(build(scene, items)), np.asarray(getattr(sd, f))):
                raise ValueError(f"{f} of the {e.name} elements would change (it is compiled for the whole "
                                 f"scene and cannot change during a run)")
    except Exception:
        items[k] = old
        raise
    for f, build in e.fields:
        if hasattr(build, "row"):
            getattr(sd, f)[k] = np.asarray(build.row(item), build.dtype).reshape(build.shape[1:])
    if e.writeRow is not None:
        e.writeRow(sd, wk, k, item)


# ---------------------------------------------------------------- generated from the registrations
def _generate(name, header, lines, footer, env, doc):
    return generate(name, header, lines, footer, env, doc, sys.modules[__name__])


# a lean element is called when its table has rows; any other through a guard that compiles to
# nothing when the scene is lean (its table None, mod:`.presence`)
_ENV = {"gravity_forces": gravity_forces, "load_forces": load_forces, "inertial_forces": inertial_forces}
_ENV.update({f"forces{k}": e.forces if e.lean else guarded(e.forces, rows=True) for k, e in enumerate(ELEMENTS)})
_ENV.update({f"energy{k}": e.energy if e.lean else guarded(e.energy, rows=True, result=5)
             for k, e in enumerate(ELEMENTS) if e.energy is not None})


def _force_call(k, e):
    if e.lean:
        return [f"if {e.table}.shape[0] > 0:", f"    forces{k}(sd, wk, R, r, V, Q)"]
    return [f"forces{k}({e.table}, sd, wk, R, r, V, Q)"]


def _energy_call(k, e):
    return f"e = energy{k}(sd, wk, R, r, V, e)" if e.lean else f"e = energy{k}({e.table}, sd, wk, R, r, V, e)"


compute_forces = njit(cache=True, inline="always", _nrt=False)(_generate(
    "compute_forces", "def compute_forces(sd, wk, t, R, r, V, Q):",
    ["for i in range(sd.nb):",
     "    for k in range(6):",
     "        Q[i, k] = 0.0",
     "F = wk.v3[6]",
     "if sd.hasGravity:",
     "    gravity_forces(sd.gid, sd.mass, sd.com, sd.gravity, R, Q, F)",
     "if sd.loadIndex.shape[0] > 0:",
     "    load_forces(sd.gid, sd.loadIndex, sd.loadVectors, R, Q, F)"]
    + [x for k, e in enumerate(ELEMENTS) for x in _force_call(k, e)],
    ["inertial_forces(sd.gid, sd.M, sd.mass, sd.com, R, V, Q)"], dict(_ENV),
    """Applied and inertial generalised forces ``Q`` (nb, 6) at the state (R, r, V): gravity,
loads, then every registered force element the scene has (in registration order), then the
inertial terms."""))

spring_energy = njit(cache=True, inline="always", _nrt=False)(_generate(
    "spring_energy", "def spring_energy(sd, wk, R, r, V):", ["e = 0.0"]
    + [_energy_call(k, e) for k, e in enumerate(ELEMENTS) if e.energy is not None],
    ["return e"], dict(_ENV), """Potential energy of the registered force elements that have one."""))

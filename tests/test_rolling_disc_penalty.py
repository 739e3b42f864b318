"""``ObjectConnectorRollingDiscPenalty`` in the compiled kernel
(``mbs/rolling_disc_penalty_forces.py``): Exudyn's own ``ComputeODE2RHS`` at random states
(contact and no contact by the stored gap, the proportional ("sticking") zone and sliding by
the stored slip velocity, every friction option), the data-coordinate update after each step
against Exudyn's PostNewton, and the reader's refusals."""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerBodyRigid, MarkerNodeRigid, NodeGenericData, ObjectConnectorRollingDiscPenalty,
                              RotationMatrixX, RotationMatrixY, RotationMatrixZ)

from exudyn_lie.bridge import BridgeError, SceneFromExudyn
from test_bridge_common import INI, add_body, compare, new_mbs, random_state

TOL = 1e-11

# friction options: (dryFrictionAngle, viscousFriction, rollingViscousFriction, useLinearProportionalZone)
OPTIONS = {
    "plain": (0.0, [0.0, 0.0], 0.0, False),
    "viscous-linear": (0.0, [0.3, 0.7], 0.0, True),
    "angle": (0.4, [0.2, 0.1], 0.0, False),
    "rolling": (0.0, [0.0, 0.0], 0.05, False),
    "all": (-0.3, [0.1, 0.4], 0.08, True),
}


def disc_model(nodes=("RotVecLG", "EP"), plane="ground", option="all"):
    """A disc (body 0, nodes[0]) on the plane of the (rotated, shifted) ground or of a second
    rigid body (nodes[1]); a second penalty disc of body 1 on the ground.  Markers with offsets
    and rotations (the law uses marker positions and orientations)."""
    alpha, visc, roll, linear = OPTIONS[option]
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0.1, -0.2, 0.05], referenceRotationMatrix=RotationMatrixY(0.1))
    b0 = add_body(mbs, nodes[0], [0.2, 0.1, 0.3], RotationMatrixZ(0.3) @ RotationMatrixY(0.2), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [0.8, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    mDisc = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localHT=exu.HT(rotation=RotationMatrixX(0.3),
                                                                         translation=[0.05, -0.02, 0.01])))
    if plane == "ground":
        mPlane = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=RotationMatrixZ(0.5),
                                                                             translation=[0.0, 0.1, -0.05])))
    else:
        mPlane = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localHT=exu.HT(rotation=RotationMatrixX(-0.2),
                                                                              translation=[0.1, 0.0, -0.05])))
    discs = []
    for m0, m1, axis, normal in [(mPlane, mDisc, [1, 0, 0], [0, 0, 1]),
                                 (mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                  mbs.AddMarker(MarkerNodeRigid(nodeNumber=mbs.GetObject(b1)["nodeNumber"])),
                                  [0.6, 0.8, 0], list(np.array([0.1, 0, 1.0]) / np.sqrt(1.01)))]:
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
        discs.append(mbs.AddObject(ObjectConnectorRollingDiscPenalty(
            markerNumbers=[m0, m1], nodeNumber=nd, discRadius=0.15, discAxis=axis, planeNormal=normal,
            contactStiffness=2e4, contactDamping=30.0, dryFriction=[0.6, 0.4], dryFrictionProportionalZone=0.05,
            viscousFriction=visc, dryFrictionAngle=alpha, rollingViscousFriction=roll,
            useLinearProportionalZone=linear)))
    mbs.Assemble()
    return mbs, discs


def set_data(mbs, values):
    """The data coordinates (slip velocity, gap) of every disc's NodeGenericData, initial and current."""
    sd = mbs.systemData
    x = np.array(sd.GetDataCoordinates(configuration=INI), float)
    for o, v in values.items():
        x[np.asarray(sd.GetNodeLTGData(mbs.GetObject(o)["nodeNumber"]), np.int64)] = v
    for cfg in (INI, exu.ConfigurationType.Current):
        sd.SetDataCoordinates(x, configuration=cfg)


# stored data: (lateral slip, longitudinal slip, gap); the proportional zone is |slip| <= 0.05
DATA = {
    "no contact": (0.01, -0.02, 0.3),
    "zone": (0.01, -0.02, -0.1),
    "sliding": (0.4, -0.3, -0.1),
    "zero slip": (0.0, 0.0, -0.1),
}


@pytest.mark.parametrize("option", list(OPTIONS))
@pytest.mark.parametrize("nodes,plane", [(("RotVecLG", "EP"), "ground"), (("EP", "Rxyz"), "body"),
                                         (("Rxyz", "RotVecLG"), "body")], ids=["RotVecLG-ground", "EP-body",
                                                                                 "Rxyz-body"])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_forces_same_as_exudyn(option, nodes, plane, group, rng):
    mbs, discs = disc_model(nodes, plane, option)
    nonzero = 0
    for data in DATA.values():
        set_data(mbs, {discs[0]: data, discs[1]: DATA["zone"]})
        for trial in range(2):
            q, qt = random_state(mbs, rng, scale=0.1)
            qt *= 0.05 if trial == 0 else 1.0          # slip inside and beyond the proportional zone
            c = compare(mbs, group, q, qt, 0.1 + trial)
            assert c["f"] < TOL, f"{data}: relative deviation {c['f']:.3g} of f from Exudyn (trial {trial})"
            nonzero += np.max(np.abs(c["fvals"][1])) > 1.0
    assert nonzero == 2 * len(DATA)


def test_inactive_disc_has_no_force_and_keeps_its_data(rng):
    mbs, discs = disc_model()
    for o in discs:
        mbs.SetObjectParameter(o, "activeConnector", False)
    mbs.Assemble()
    set_data(mbs, {discs[0]: DATA["sliding"], discs[1]: DATA["zone"]})
    q, qt = random_state(mbs, rng, scale=0.1)
    c = compare(mbs, "SE3", q, qt)
    assert c["f"] < TOL


@pytest.mark.parametrize("case", ["disc on ground", "no data node", "two data coordinates"])
def test_bad_setups_are_refused(case):
    mbs, discs = disc_model()
    d = mbs.GetObject(discs[0])
    if case == "disc on ground":
        mbs.SetObjectParameter(discs[0], "markerNumbers", [d["markerNumbers"][1], d["markerNumbers"][0]])
        msg = "marker 1 \\(the disc\\) is on the ground"
    elif case == "no data node":
        mbs.SetObjectParameter(discs[0], "nodeNumber", 0)
        msg = "not a NodeGenericData"
    else:
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0], numberOfDataCoordinates=2))
        mbs.SetObjectParameter(discs[0], "nodeNumber", nd)
        msg = "3 finite data coordinates"
    with pytest.raises(BridgeError, match=msg):
        SceneFromExudyn(mbs, "items")

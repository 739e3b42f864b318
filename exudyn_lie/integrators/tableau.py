"""Explicit Runge-Kutta (Butcher) tableaus: the catalogue of methods, and the frozen,
self-checking type (:mod:`.butcher`, with Butcher's order conditions in
:mod:`.order_conditions`), re-exported here.

A :class:`ButcherTableau` holds the coefficients ``a_jl, b_j, c_j`` of an explicit
``s``-stage method (the coefficients of eq. (MK1) in appendix B of the paper).  On
construction it checks

* ``A`` is square ``s x s`` and strictly lower triangular (explicit method),
* the row-sum condition ``c_j = sum_l a_jl``,
* consistency ``sum_j b_j = 1``,
* every order condition up to the claimed ``order``: for each rooted tree ``t`` with
  ``|t| <= order`` the elementary weight must equal ``1 / gamma(t)`` (Butcher's theory;
  1, 1, 2, 4, 9, 20 trees of order 1..6, see :func:`rooted_trees`),

and raises :class:`ValueError` naming the method and the first violated condition.  The
check is done in exact rational arithmetic when every coefficient is given exactly
(``int``, :class:`fractions.Fraction` or a string such as ``"-56/15"``), otherwise in
floating point with a tolerance.

The arrays ``A``, ``b``, ``c`` (and the optional embedded weights ``b_hat``) are
``float64``, C-contiguous and read-only.  :meth:`ButcherTableau.arrays` returns writable
copies for code that wants plain arrays (e.g. to pass into numba kernels without the
read-only type signature).

Adding a method touches one place: append it to :data:`METHODS`.
"""
from fractions import Fraction

import numpy as np

from .butcher import ButcherTableau, ContinuousExtension
from .partitioned import PARTITIONED_METHODS, PartitionedTableau, VelocityVerlet  # noqa: F401
from .order_conditions import (MAX_CHECK_ORDER, achieved_order, continuous_order_residuals,  # noqa: F401
                               order_condition_residuals, quadrature_order, rooted_trees)

__all__ = [
    "ButcherTableau",
    "METHODS",
    "get_method",
    "method_names",
    "rooted_trees",
    "order_condition_residuals",
    "achieved_order",
    "quadrature_order",
    "ExplicitEuler",
    "ExplicitMidpoint",
    "Heun",
    "RK3",
    "RK4",
    "RK38",
    "DOPRI5",
    "RK6",
    "RK33",
    "RK67",
    "extrapolated_euler",
    # --- embedded pairs and continuous extensions ---
    "ContinuousExtension",
    "PAIRS",
    "continuous_order_residuals",
    "BS3",
    "Vern6",
    # --- implicit methods ---
    "IMPLICIT_METHODS",
    "ESDIRK3",
    # --- partitioned methods ---
    "PARTITIONED_METHODS",
    "PartitionedTableau",
    "VelocityVerlet",
]

def _F(*xs):
    return [Fraction(x) for x in xs]


# --------------------------------------------------------------------------- the catalogue
ExplicitEuler = ButcherTableau(
    name="ExplicitEuler", order=1,
    A=[[0]], b=[1], c=[0],
    aliases=("Euler", "RK1"),
    description="Forward Euler.",
)

ExplicitMidpoint = ButcherTableau(
    name="ExplicitMidpoint", order=2,
    A=[[0, 0],
       ["1/2", 0]],
    b=[0, 1], c=[0, "1/2"],
    aliases=("Midpoint", "RK2"),
    description="Explicit midpoint rule; the paper's two-stage illustration in section "
                "'significance of the configuration space' (called 'explicit trapezoidal' "
                "there): k1 = f(t, x), k2 = f(t + h/2, x + h/2 k1), x+ = x + h k2.",
)

Heun = ButcherTableau(
    name="Heun", order=2,
    A=[[0, 0],
       [1, 0]],
    b=["1/2", "1/2"], c=[0, 1],
    aliases=("ExplicitTrapezoidal",),
    description="Heun's method (explicit trapezoidal rule).",
)

RK3 = ButcherTableau(
    name="RK3", order=3,
    A=[[0, 0, 0],
       ["1/2", 0, 0],
       [-1, 2, 0]],
    b=["1/6", "2/3", "1/6"], c=[0, "1/2", 1],
    aliases=("Kutta3",),
    description="Kutta's third-order method (1901).",
)

RK4 = ButcherTableau(
    name="RK4", order=4,
    A=[[0, 0, 0, 0],
       ["1/2", 0, 0, 0],
       [0, "1/2", 0, 0],
       [0, 0, 1, 0]],
    b=["1/6", "1/3", "1/3", "1/6"], c=[0, "1/2", "1/2", 1],
    aliases=("RK44", "ClassicalRK4"),
    description="The classical fourth-order Runge-Kutta method (used in the paper's examples).",
)

RK38 = ButcherTableau(
    name="RK38", order=4,
    A=[[0, 0, 0, 0],
       ["1/3", 0, 0, 0],
       ["-1/3", 1, 0, 0],
       [1, -1, 1, 0]],
    b=["1/8", "3/8", "3/8", "1/8"], c=[0, "1/3", "2/3", 1],
    aliases=("ThreeEighths",),
    description="Kutta's 3/8 rule.",
)

# --- dense output of DOPRI5 -------------------------------------------------
# Shampine's order-4 continuous extension (L. F. Shampine, "Some practical Runge-Kutta
# formulas", Math. Comp. 46 (1986) 135-150), in the form Hairer's dopri5.f (CONTD5) uses:
# y(theta) = y0 + theta (y1 - y0) + theta (1 - theta) (h k1 - (y1 - y0))
#            + theta^2 (1 - theta) (2 (y1 - y0) - h k1 - h k7)
#            + theta^2 (1 - theta)^2 h sum_j d_j k_j,
# d = (-12715105075/11282082432, 0, 87487479700/32700410799, -10690763975/1880347072,
#      701980252875/199316789632, -1453857185/822651844, 69997945/29380423)
# (HNW I, sec. II.6), expanded below into b_j(theta) = sum_k P[j, k] theta^(k+1).  The
# tableau checks the continuous order conditions up to 4 exactly, and b(1) = b.
_DOPRI5_DENSE = ContinuousExtension(
    order=4,
    P=[[1, "-8048581381/2820520608", "8663915743/2820520608", "-12715105075/11282082432"],
       [0, 0, 0, 0],
       [0, "131558114200/32700410799", "-68118460800/10900136933", "87487479700/32700410799"],
       [0, "-1754552775/470086768", "14199869525/1410260304", "-10690763975/1880347072"],
       [0, "127303824393/49829197408", "-318862633887/49829197408", "701980252875/199316789632"],
       [0, "-282668133/205662961", "2019193451/616988883", "-1453857185/822651844"],
       [0, "40617522/29380423", "-110615467/29380423", "69997945/29380423"]],
    source="Shampine (1986); Hairer's dopri5.f CONTD5 coefficients d_j",
)


DOPRI5 = ButcherTableau(
    name="DOPRI5", order=5,
    A=[[0, 0, 0, 0, 0, 0, 0],
       ["1/5", 0, 0, 0, 0, 0, 0],
       ["3/40", "9/40", 0, 0, 0, 0, 0],
       ["44/45", "-56/15", "32/9", 0, 0, 0, 0],
       ["19372/6561", "-25360/2187", "64448/6561", "-212/729", 0, 0, 0],
       ["9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656", 0, 0],
       ["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0]],
    b=["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0],
    c=[0, "1/5", "3/10", "4/5", "8/9", 1, 1],
    b_hat=["5179/57600", 0, "7571/16695", "393/640", "-92097/339200", "187/2100", "1/40"],
    order_hat=4,
    dense=_DOPRI5_DENSE,
    aliases=("DormandPrince", "DP5", "RK45"),
    description="Dormand-Prince 5(4), used as a fixed-step method with the 5th-order "
                "weights (b_7 = 0, so the FSAL stage is not evaluated); the embedded "
                "4th-order weights are kept in b_hat.",
)

RK6 = ButcherTableau(
    name="RK6", order=6,
    A=[[0, 0, 0, 0, 0, 0, 0],
       ["1/3", 0, 0, 0, 0, 0, 0],
       [0, "2/3", 0, 0, 0, 0, 0],
       ["1/12", "1/3", "-1/12", 0, 0, 0, 0],
       ["-1/16", "9/8", "-3/16", "-3/8", 0, 0, 0],
       [0, "9/8", "-3/8", "-3/4", "1/2", 0, 0],
       ["9/44", "-9/11", "63/44", "18/11", 0, "-16/11", 0]],
    b=["11/120", 0, "27/40", "27/40", "-4/15", "-4/15", "11/120"],
    c=[0, "1/3", "2/3", "1/3", "1/2", "1/2", 1],
    aliases=("Butcher6",),
    description="Butcher's sixth-order, seven-stage explicit method (1964).",
)

# --- Exudyn's own explicit tableaus that differ from the classical ones above -----------
# (exudyn.DynamicSolverType.RK33 / RK67; Exudyn's main/src/Solver/CSolverExplicit.cpp,
# ComputeButcherTableau).  Exudyn's ExplicitEuler, ExplicitMidpoint, RK44 and DOPRI5 are
# the catalogue's ExplicitEuler, ExplicitMidpoint, RK4 and DOPRI5; its ODE23 is BS3.
RK33 = ButcherTableau(
    name="RK33", order=3,
    A=[[0, 0, 0],
       ["1/3", 0, 0],
       [0, "2/3", 0]],
    b=["1/4", 0, "3/4"], c=[0, "1/3", "2/3"],
    aliases=("Heun3",),
    description="Heun's third-order method; Exudyn's DynamicSolverType.RK33 (the same "
                "coefficients as CSolverExplicit.cpp).",
)

_S5 = np.sqrt(5.0)
# Butcher's 7-stage order-6 method with Lobatto nodes (J. C. Butcher, 'On Runge-Kutta
# processes of high order', J. Austral. Math. Soc. 4 (1964)); irrational coefficients,
# written as the same floating-point expressions as Exudyn's DynamicSolverType.RK67 so that
# the doubles are Exudyn's bit for bit (checked by tests/test_bridge_solvertype.py).
RK67 = ButcherTableau(
    name="RK67", order=6,
    A=[[0, 0, 0, 0, 0, 0, 0],
       [1. / 2 - 1. / 10 * _S5, 0, 0, 0, 0, 0, 0],
       [-1. / 10 * _S5, 1. / 2 + 1. / 5 * _S5, 0, 0, 0, 0, 0],
       [7. / 20 * _S5 - 3. / 4, 1. / 4 * _S5 - 1. / 4, 3. / 2 - 7. / 10 * _S5, 0, 0, 0, 0],
       [1. / 12 - 1. / 60 * _S5, 0, 1. / 6, 7. / 60 * _S5 + 1. / 4, 0, 0, 0],
       [1. / 60 * _S5 + 1. / 12, 0, 3. / 4 - 5. / 12 * _S5, 1. / 6, -1. / 2 + 3. / 10 * _S5, 0, 0],
       [1. / 6, 0, -55. / 12 + 25. / 12 * _S5, -7. / 12 * _S5 - 25. / 12, 5 - 2 * _S5,
        5. / 2 + 1. / 2 * _S5, 0]],
    b=[1. / 12, 0., 0., 0., 5. / 12, 5. / 12, 1. / 12],
    c=[0., 1. / 2 - 1. / 10 * _S5, 1. / 2 + 1. / 10 * _S5, 1. / 2 - 1. / 10 * _S5,
       1. / 2 + 1. / 10 * _S5, 1. / 2 - 1. / 10 * _S5, 1.],
    aliases=("ButcherLobatto6",),
    description="Butcher's seven-stage, sixth-order method on the Lobatto nodes (1964); "
                "Exudyn's DynamicSolverType.RK67 (coefficients as in CSolverExplicit.cpp).",
)

# --------------------------------------------------------------------------- embedded pairs
# (adaptive steps).  Each pair carries b_hat / order_hat; `fsal` and `dense` are
# derived / checked by the tableau type.  Coefficients are the published rationals; the
# type verifies every order condition of b (order), b_hat (order_hat) and of the dense
# weights exactly.
BS3 = ButcherTableau(
    name="BS3", order=3,
    A=[[0, 0, 0, 0],
       ["1/2", 0, 0, 0],
       [0, "3/4", 0, 0],
       ["2/9", "1/3", "4/9", 0]],
    b=["2/9", "1/3", "4/9", 0],
    c=[0, "1/2", "3/4", 1],
    b_hat=["7/24", "1/4", "1/3", "1/8"],
    order_hat=2,
    # cubic Hermite interpolation of y0, y1, y0' = k1, y1' = k4 (FSAL stage), written in
    # the stages: b_j(theta) = (3 theta^2 - 2 theta^3) b_j + theta (1 - theta)^2 [j = 1]
    # - theta^2 (1 - theta) [j = 4]; order 3 (Bogacki & Shampine 1989, sec. 3)
    dense=ContinuousExtension(
        order=3,
        P=[[1, "-4/3", "5/9"],
           [0, 1, "-2/3"],
           [0, "4/3", "-8/9"],
           [0, -1, 1]],
        source="cubic Hermite on the FSAL stages (Bogacki & Shampine 1989)"),
    aliases=("BogackiShampine", "ODE23", "RK23"),
    description="Bogacki-Shampine 3(2) pair, FSAL (P. Bogacki, L. F. Shampine, 'A 3(2) pair "
                "of Runge-Kutta formulas', Appl. Math. Lett. 2 (1989) 321-325); Exudyn's "
                "ODE23 (CSolverExplicit.cpp: the same A, b and b - delta) and scipy's RK23.",
)

Vern6 = ButcherTableau(
    name="Vern6", order=6,
    A=[[0, 0, 0, 0, 0, 0, 0, 0, 0],
       ["3/50", 0, 0, 0, 0, 0, 0, 0, 0],
       ["519479/27000000", "2070721/27000000", 0, 0, 0, 0, 0, 0, 0],
       ["1439/40000", 0, "4317/40000", 0, 0, 0, 0, 0, 0],
       ["109225017611/82828840000", 0, "-417627820623/82828840000", "43699198143/10353605000", 0, 0,
        0, 0, 0],
       ["-8036815292643907349452552172369/191934985946683241245914401600", 0,
        "246134619571490020064824665/1543816496655405117602368",
        "-13880495956885686234074067279/113663489566254201783474344",
        "755005057777788994734129/136485922925633667082436", 0, 0, 0, 0],
       ["-1663299841566102097180506666498880934230261/30558424506156170307020957791311384232000", 0,
        "130838124195285491799043628811093033/631862949514135618861563657970240",
        "-3287100453856023634160618787153901962873/20724314915376755629135711026851409200",
        "2771826790140332140865242520369241/396438716042723436917079980147600",
        "-1799166916139193/96743806114007800", 0, 0, 0],
       ["-832144750039369683895428386437986853923637763/15222974550069600748763651844667619945204887",
        0, "818622075710363565982285196611368750/3936576237903728151856072395343129",
        "-9818985165491658464841194581385463434793741875/61642597962658994069869370923196463581866011",
        "31796692141848558720425711042548134769375/4530254033500045975557858016006308628092",
        "-14064542118843830075/766928748264306853644",
        "-1424670304836288125/2782839104764768088217", 0, 0],
       ["382735282417/11129397249634", 0, 0, "5535620703125000/21434089949505429",
        "13867056347656250/32943296570459319", "626271188750/142160006043",
        "-51160788125000/289890548217", "163193540017/946795234", 0]],
    b=["382735282417/11129397249634", 0, 0, "5535620703125000/21434089949505429",
       "13867056347656250/32943296570459319", "626271188750/142160006043",
       "-51160788125000/289890548217", "163193540017/946795234", 0],
    c=[0, "3/50", "1439/15000", "1439/10000", "4973/10000", "389/400", "1999/2000", "1", "1"],
    b_hat=["124310637869885675646798613/2890072468789466426596827670", 0, 0,
           "265863151737164990361330921875/1113197271463372303940319369579",
           "3075493557174030806536302953125/6843749922042323876546949699876",
           "67798000008733879813263055/29532792147666737550036372",
           "-1099436585155390846238326375/15055706496446408859196167",
           "26171252653086373181571802/368794478890732346033505", "1/30"],
    order_hat=5,
    # order-6 interpolant with three extra stages (c = 1/2, 207/250, 7/25), evaluated only
    # for output (Verner's "bi6" coefficients, 12 stages)
    dense=ContinuousExtension(
        order=6,
        A_extra=[["35289331988986254405692535758830683/2135620454874580332949729350544993288", 0, 0,
                  "313937014583068512255490687992212890625/1028247080705354654473994781524199691557",
                  "1309307687253621245836726130885318359375/6321490412177191231557635904400612215708",
                  "-35295844079877524186147726060781875/27279088881521314684841470427640876",
                  "794353492803973228770716697389421875/13906777037439977359946774228636361",
                  "-15228408956329265381787438679500067/272520859345009876882656783678732",
                  "28587810357600962662801/1151340224617184234295192", 0, 0, 0],
                 ["2486392061981208591025761263164027224438868971/65173964076983042387381877152862343994140625000",
                  0, 0,
                  "2330654500023704838558579323179918419669/9313832252765893609365894760182968220625",
                  "5283259505481013273874688940942473187741/16258977397575080328080339260289640472500",
                  "9989685106081485386057729811605187743723/5481427003263510055949691042076757812500",
                  "-65815640423883764662985178413751186161/971969007022721623945108012714453125",
                  "183066350554023250298437927498791289370414247/2772225538584491748887703284492309570312500",
                  "-426178927623072052719640507155669/11712038417736656029207275390625000",
                  "3248339841/30517578125", 0, 0],
                 ["4676747786898097735038451956075910033997933945857/41838231186922043164464169766109251031526972656250",
                  0, 0,
                  "1320032412954312695441306548681592444623240/51248457773784347881352490499724836575577977",
                  "2087002134582726310861746540254017903014374710/551367099344274428347227263044005314054687829",
                  "3432932836484348829479408524345545011748570706/37176735450871998946806722732624135633015625",
                  "-2316434358511265475362584844804601519943610264/606481922490173339581866127622363581143375",
                  "82514605285282414051716141603447021470923168793/22107104196177512751528507591142367597656250",
                  "-7560161019374651900153317984708038834/7028170531590816328729091157353515625",
                  "-21655450552377696842870155771710589332/6701278878958685336695179940732421875",
                  "-3194830887993202085244614477336220/678662636676110315314332975245759", 0]],
        c_extra=["1/2", "207/250", "7/25"],
        P=[["1", "-940811006205413129/120948724610397495",
            "88342864458754360181/3265615564480732365", "-99667000922033025307/2177077042987154910",
            "7995049273203130972/217707704298715491", "-7303903485456272500/653123112896146473"],
       [0, 0, 0, 0, 0, 0],
       [0, 0, 0, 0, 0, 0],
       [0, "2214248281250000/133130993475189", "-49918013252500000000/578720428636646583",
        "1440368506953125000/8387252588936907", "-28873797587500000000/192906809545548861",
        "27678103515625000000/578720428636646583"],
       [0, "893038428789062500/32943296570459319", "-125047567320625000000/889469007402401613",
        "82988785418183593750/296489669134133871", "-72330565909375000000/296489669134133871",
        "69335281738281250000/889469007402401613"],
       [0, "40331864555500/142160006043", "-5647463071672000/3838320163161",
        "3747982556193250/1279440054387", "-3266630520520000/1279440054387",
        "3131355943750000/3838320163161"],
       [0, "-143250206750000/12603936879", "461347522996000000/7827044801859",
        "-13312037070125000/113435431911", "266854670860000000/2609014933953",
        "-255803940625000000/7827044801859"],
       [0, "3753451420391/338141155", "-3679035166143248/63908678295",
        "4883240297928691/42605785530", "-425608752364336/4260578553",
        "407983850042500/12781735659"],
       [0, "-69713/23220", "4685161/313470", "-135239/4860", "228046/10449", "-186250/31347"],
       [0, "-132664/6765", "17011336/182655", "-10067296/60885", "1579832/12177",
        "-1385000/36531"],
       [0, "-2734375000/149990751", "391796875000/4049750277", "-6250000000/31393413",
        "244140625000/1349916759", "-244140625000/4049750277"],
       [0, "-15453125/1139292", "1393796875/15380442", "-2092203125/10253628", "488281250/2563407",
        "-488281250/7690221"]],
        source="J. H. Verner, RKV65.IIIXb Efficient (rational coefficients, his web page)"),
    aliases=("Verner6", "Verner65"),
    description="Verner's 'most efficient' 6(5) pair, 9 stages, FSAL (J. H. Verner, "
                "'Numerically optimal Runge-Kutta pairs with interpolants', Numer. Algorithms "
                "53 (2010) 383-396; rational coefficients from his web page, verified here).",
)


# gamma: the root in (1/3, 1/2) of 6 g^3 - 18 g^2 + 9 g - 1 = 0, for which the stability function of
# a stiffly accurate order-3 ESDIRK vanishes at infinity (L-stability); the other coefficients follow
# from stage order 2 (c2 = 2 gamma, c3 = 3/5) and the order-3 conditions on b (Kennedy & Carpenter).
_G = 0.43586652150845899942
_A32 = 0.6 * (0.3 - _G) / (2.0 * _G)
_B = (0.18764102434672382516, -0.59529747357695494805, 0.97178992772177212347, _G)
ESDIRK3 = ButcherTableau(
    name="ESDIRK3", order=3,
    A=[[0, 0, 0, 0],
       [_G, _G, 0, 0],
       [0.6 - _A32 - _G, _A32, _G, 0],
       list(_B)],
    b=list(_B), c=[0, 2 * _G, 0.6, 1],
    # order 2, chosen here: b_hat_4 = 0.312 on the line of order-2 weights whose stability function
    # stays bounded at infinity (b_hat^T lim (I - zA)^-1 e = 0): A-stable, |R_hat(-inf)| = 0.26,
    # sum b_hat c^2 - 1/3 = 0.045 (not order 3)
    b_hat=[0.28587736813740375901, -0.19605116303150865333, 0.59817379489410489432, 0.312],
    order_hat=2,
    # dense output of order 3: b_j(theta) = p_j theta + q_j theta^2 + r_j theta^3, the least-norm q and r
    # of the continuous order conditions (stage order 2, A c = c^2 / 2, makes the tree [[o]] follow
    # from [o, o]) and p = b - q - r
    dense=ContinuousExtension(order=3, P=[
        [0.94996120479985362892, -1.311004143547217352, 0.54868396309408754823],
        [-0.86139203363418709111, 0.38438547775446642539, -0.11829091769723428232],
        [0.40131732530968042752, 1.9042504700179094588, -1.3337778676058177628],
        [0.51011350352465303467, -0.97763180422515853217, 0.90338482220896449691]],
        source="derived here (least-norm solution of the continuous order conditions up to order 3)"),
    aliases=("ESDIRK32", "ESDIRK3(2)4L[2]SA"),
    description="L-stable, stiffly accurate, singly diagonally implicit Runge-Kutta method of order 3 "
                "with an explicit first stage, 4 stages, stage order 2 (C. A. Kennedy, M. H. Carpenter, "
                "'Diagonally implicit Runge-Kutta methods for ordinary differential equations. A review', "
                "NASA/TM-2016-219173, ESDIRK3(2)4L[2]SA; coefficients recomputed here).",
)

#: The implicit methods, found by name (get_method) but not in METHODS (whose generic tests assume an
#: explicit tableau).  The stepper solves their stages by a simplified Newton iteration (mbs/implicit.py).
IMPLICIT_METHODS = (ESDIRK3,)

#: The catalogue.  Adding a method = appending a tableau here.
METHODS = (ExplicitEuler, ExplicitMidpoint, Heun, RK3, RK4, RK38, DOPRI5, RK6, RK67)

#: Found by name (get_method, so ``method='RK33'``) but not in METHODS: Exudyn's RK33 has, like
#: BS3 below, its largest evaluated node c = 2/3 < 1 and fails the SE3 fixed-axis "exact up to
#: the domain limit" test for the same reason (errors 1.3e-10 and 4e-9 at stage-argument gaps
#: 1e-6 and 1e-7 from 2 pi, where h |omega| = 3 pi), see PAIRS.
NAMED_EXTRA = (RK33,)

#: The embedded pairs.  BS3 and Vern6 are not (yet) in METHODS: the generic
#: fixed-step tests that iterate over METHODS assume round-off of a method with weights of
#: size ~1 (Vern6's weights of size 176 cancel: its round-off is ~350x larger), and BS3
#: fails the SE3 fixed-axis "exact up to the domain limit" test (errors 2e-11..3e-9 for steps
#: with h |omega| = 8.4 > 2 pi, where its largest evaluated node is c = 3/4); see docs/ADAPTIVE.md.
PAIRS = (DOPRI5, BS3, Vern6)


def extrapolated_euler(order, name=None):
    """Explicit Euler with polynomial (Aitken-Neville) extrapolation on the harmonic
    step sequence n_j = j, j = 1..order, written as one explicit RK tableau of the given
    order with 1 + order (order - 1)/2 stages, in exact rationals.

    Not part of the catalogue: a source of explicit methods of any order up to
    ``MAX_CHECK_ORDER``, e.g. to check that order-dependent code (order conditions,
    convergence tests) handles orders beyond the catalogue.  The result is
    ``sum_j gamma_j T_j`` with ``T_j`` the result of ``n_j`` Euler substeps of size
    ``h/n_j`` and the Lagrange weights at 0 of the nodes ``1/n_j``:
    ``gamma_j = prod_{i != j} n_j/(n_j - n_i)``.
    """
    k = int(order)
    if not 1 <= k <= MAX_CHECK_ORDER:
        raise ValueError(f"extrapolated_euler: order must be in 1..{MAX_CHECK_ORDER}")
    ns = list(range(1, k + 1))
    gam = []
    for j, nj in enumerate(ns):
        g = Fraction(1)
        for i, ni in enumerate(ns):
            if i != j:
                g *= Fraction(nj, nj - ni)
        gam.append(g)
    s = 1 + sum(n - 1 for n in ns)
    A = [[Fraction(0)] * s for _ in range(s)]
    b = [Fraction(0)] * s
    c = [Fraction(0)] * s
    row = 1
    for nj, gj in zip(ns, gam):
        w = Fraction(1, nj)
        b[0] += gj * w                     # the first Euler substep of every sequence
        first = row
        for m in range(1, nj):             # substeps 2..n_j: stage value after m substeps
            A[row][0] = w
            for l in range(first, row):
                A[row][l] = w
            c[row] = m * w
            b[row] = gj * w
            row += 1
    return ButcherTableau(name=name or f"ExtrapolatedEuler{k}", A=A, b=b, c=c, order=k,
                          description=f"explicit Euler extrapolated on n = 1..{k}")


def _check_catalogue(methods):
    seen = {}
    for m in methods:
        for key in (m.name, *m.aliases):
            k = key.lower()
            if k in seen:
                raise ValueError(f"method name '{key}' of '{m.name}' clashes with "
                                 f"'{seen[k]}'")
            seen[k] = m.name


_check_catalogue(METHODS)
_check_catalogue(METHODS + PAIRS[1:])     # embedded pairs: no name clashes
_check_catalogue(METHODS + NAMED_EXTRA + PAIRS[1:] + IMPLICIT_METHODS + PARTITIONED_METHODS)


def method_names():
    """Canonical names of the catalogue methods, in catalogue order."""
    return tuple(m.name for m in METHODS)


def _name_key(name):
    """A method name as compared: case, blanks, '-' and '_' ignored ('rk-4' = 'RK4')."""
    return "".join(ch for ch in name.lower() if ch not in " \t-_")


def get_method(name):
    """The catalogue tableau called ``name``: case-insensitive, ignoring blanks, '-' and
    '_', and accepting every tableau's aliases (``'rk4'``, ``'RK44'`` -> RK4, ``'RK45'``,
    ``'dopri5'`` -> DOPRI5).  An unknown name raises ValueError with the catalogue.

    A :class:`ButcherTableau` passed in is returned unchanged.
    """
    if isinstance(name, ButcherTableau):
        return name
    if not isinstance(name, str):
        raise TypeError(f"method name must be a string or ButcherTableau, got {type(name)}")
    key = _name_key(name)
    for m in METHODS + NAMED_EXTRA + IMPLICIT_METHODS + PARTITIONED_METHODS:
        if key in (_name_key(n) for n in (m.name,) + tuple(m.aliases)):
            return m
    raise ValueError(f"unknown integration method '{name}'; available: "
                     + ", ".join(method_names()) + ", " + ", ".join(m.name for m in PARTITIONED_METHODS)
                     + " (case-insensitive; aliases: "
                     + ", ".join(f"{a} = {m.name}" for m in METHODS for a in m.aliases) + ")")


def resolve_pair(method):
    """A tableau object, or the name / alias of an embedded pair (PAIRS, which holds pairs
    not yet in METHODS), or any catalogue name (get_method)."""
    if isinstance(method, str):
        for m in PAIRS:
            if m.matches(method):
                return m
    return get_method(method)

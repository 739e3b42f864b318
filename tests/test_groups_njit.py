"""Every public map of the group modules is callable from numba-compiled code, and the
allocation-free ``*_into`` variants neither allocate nor differ from the allocating maps.

* ``test_every_public_map_is_covered``: the call table below lists every public njit
  function of so3, se3, so3xr3, quaternion and dualquat (found by introspection), so a new
  map without an entry fails here.
* ``test_callable_from_njit``: each map is called from inside an ``@njit`` function (one
  generated caller per module that calls each of its maps once: one compile per module, where a
  caller per map cost about 90 compiles) and compared with the Python-level call; for ``*_into``
  maps the arrays written are compared.
* ``test_into_variants_equal_allocating_maps``: ``*_into`` == the allocating map, also with
  the documented aliasing (in-place group updates).
* ``test_into_variants_do_not_allocate``: numba's NRT allocation counters do not grow with
  the number of calls made inside a compiled loop.
"""
import numpy as np
import pytest
from numba import njit
from numba.core.registry import CPUDispatcher
from numba.core.runtime import rtsys

import dualquat_oracle as dualquat
from exudyn_lie.groups import quaternion, se3, so3, so3xr3

# not in the quick subset (pytest -m "not slow"): compiles every public group map inside an njit wrapper (about 25 s per run)
pytestmark = pytest.mark.slow

MODULES = {"so3": so3, "se3": se3, "so3xr3": so3xr3, "quaternion": quaternion,
           "dualquat": dualquat}


def public_maps(mod):
    """Names of the public njit functions defined in ``mod`` (not re-exported helpers)."""
    return sorted(n for n, v in vars(mod).items()
                  if isinstance(v, CPUDispatcher) and not n.startswith("_")
                  and v.py_func.__module__ == mod.__name__)


def inputs():
    """Fixed test inputs (random but reproducible; rotations of 1.9 rad, above every
    Taylor switch of exp; the scalar coefficient helpers get u on both branches below)."""
    rng = np.random.default_rng(7)
    n = rng.normal(size=3)
    x = 1.9 * n / np.linalg.norm(n)
    X = np.r_[x, rng.normal(size=3)]
    R, r = se3.exp(X)
    R2, r2 = se3.exp(rng.normal(size=6))
    Q = quaternion.from_matrix(R)
    Qh = dualquat.from_pose(R, r)
    return dict(x=x, y=rng.normal(size=3), X=X, Y=rng.normal(size=6), R=R, r=r, R2=R2, r2=r2,
                Q=Q, P=rng.normal(size=4), Qh=Qh, Ph=dualquat.from_pose(R2, r2),
                w=rng.normal(size=3), Qdot=quaternion.qdot_from_omega(Q, rng.normal(size=3)),
                V=rng.normal(size=6))


def out(*shape):
    return np.full(shape, np.nan)


def call_table(d):
    """{module: {name: args}}; output arrays of *_into maps are NaN-filled."""
    u_lo, u_hi = 0.04, 3.6     # |xi|^2 on the series / closed-form side of every switch
    rot = dict(
        hat=(d["x"],), vee=(so3.hat(d["x"]),), exp=(d["x"],), log=(d["R"],),
        dexp=(d["x"],), dexpinv=(d["x"],), ad=(d["x"],), Ad=(d["R"],),
        compose=(d["R"], d["R2"]), inverse=(d["R"],),
        exp_into=(d["x"], out(3, 3)), log_into=(d["R"], out(3)),
        dexp_apply_into=(d["x"], d["y"], out(3)), dexpinv_apply_into=(d["x"], d["y"], out(3)),
        compose_into=(d["R"], d["R2"], out(3, 3)), inverse_into=(d["R"], out(3, 3)),
        Ad_into=(d["R"], out(3, 3)),
        dexp_series=(d["x"], 30), dexpinv_series=(d["x"], 30),
        quat_from_matrix=(d["R"],), rotvec_from_quat=(d["Q"],),
    )
    for name in ("closed_ABC", "closed_D", "coef_AB", "coef_ABC", "coef_BC", "coef_D",
                 "series_ABC", "series_D"):
        rot[name] = (u_hi if name.startswith("closed") else u_lo,)
    pose = dict(R=d["R"], r=d["r"])

    def rigid(mod, dim):
        t = dict(
            hat=(d["X"],), vee=(mod.hat(d["X"]),), exp=(d["X"],), log=(d["R"], d["r"]),
            dexp=(d["X"],), dexpinv=(d["X"],), ad=(d["X"],), Ad=(d["R"], d["r"]),
            compose=(d["R"], d["r"], d["R2"], d["r2"]), inverse=(d["R"], d["r"]),
            exp_into=(d["X"], out(3, 3), out(3)), log_into=(d["R"], d["r"], out(6)),
            dexp_apply_into=(d["X"], d["Y"], out(6)),
            dexpinv_apply_into=(d["X"], d["Y"], out(6)),
            compose_into=(d["R"], d["r"], d["R2"], d["r2"], out(3, 3), out(3)),
            inverse_into=(d["R"], d["r"], out(3, 3), out(3)), Ad_into=(d["R"], d["r"], out(6, 6)),
            dexp_series=(d["X"], 30), dexpinv_series=(d["X"], 30),
            to_matrix=(d["R"], d["r"]), from_matrix=(mod.to_matrix(**pose),),
        )
        assert mod.to_matrix(**pose).shape == (dim, dim)
        return t

    tse3 = rigid(se3, 4)
    tse3.update(dexp_P=(d["X"],), dexpinv_U=(d["X"],), dexpinv_selig=(d["X"],))
    for name in ("closed_dexp", "closed_dexpinv", "closed_selig"):
        tse3[name] = (u_hi + 4.0,)                  # above the se3 switches (t = 2.8)
    for name in ("coef_dexp", "coef_dexpinv", "coef_selig",
                 "series_dexp", "series_dexpinv", "series_selig"):
        tse3[name] = (u_lo,)
    quat = dict(
        D=(d["Q"],), E=(d["Q"],), Hm=(d["Q"],), conjugate=(d["P"],), from_matrix=(d["R"],),
        from_rotvec=(d["x"],), hamilton_minus=(d["P"],), hamilton_plus=(d["P"],),
        multiply=(d["Q"], d["P"]), normalize=(d["P"],), omega_from_qdot=(d["Q"], d["Qdot"]),
        qdot_from_omega=(d["Q"], d["w"]), rate_from_mixed=(d["Q"], d["V"]),
        to_matrix=(d["Q"],), to_rotvec=(d["Q"],),
    )
    dual = dict(
        H=(d["Qh"],), Hm=(d["Qh"],), conjugate=(d["Ph"],), from_pose=(d["R"], d["r"]),
        from_screw=(d["X"],), minus=(d["Ph"],), multiply=(d["Qh"], d["Ph"]), plus=(d["Ph"],),
        qhdot_from_mixed=(d["Qh"], d["V"]), qhdot_from_twist=(d["Qh"], d["V"]),
        to_pose=(d["Qh"],), to_screw=(d["Qh"],),
    )
    return {"so3": rot, "se3": tse3, "so3xr3": rigid(so3xr3, 7), "quaternion": quat,
            "dualquat": dual}


TABLE = call_table(inputs())
CASES = [(m, name) for m, t in TABLE.items() for name in sorted(t)]


def _caller(modname):
    """An ``@njit`` function of a tuple of argument tuples, one per map of ``TABLE[modname]`` (sorted by
    name), that calls each map with its arguments from compiled code and returns the results of the
    maps that return one (an ``*_into`` map writes into its arguments)."""
    names = sorted(TABLE[modname])
    env = {f"f{k}": getattr(MODULES[modname], n) for k, n in enumerate(names)}
    lines, results = ["def call_all(args):"], []
    for k, n in enumerate(names):
        call = f"f{k}(*args[{k}])"
        if n.endswith("_into"):
            lines.append(f"    {call}")
        else:
            lines.append(f"    r{k} = {call}")
            results.append(f"r{k}")
    lines.append(f"    return ({', '.join(results)},)")
    exec("\n".join(lines), env)
    return njit(env["call_all"]), [n for n in names if not n.endswith("_into")]


_CALLED = {}


def called_from_njit(modname):
    """``(args, results)`` of one call of every map of ``modname`` from compiled code (made once): the
    arguments after the call (copies of the table's) and ``{name: result}``."""
    if modname not in _CALLED:
        call_all, returning = _caller(modname)
        args = tuple(copy_args(TABLE[modname][n]) for n in sorted(TABLE[modname]))
        res = call_all(args)
        _CALLED[modname] = ({n: a for n, a in zip(sorted(TABLE[modname]), args)}, dict(zip(returning, res)))
    return _CALLED[modname]


@njit
def njit_loop(f, args, n):
    for _ in range(n):
        f(*args)


def copy_args(args):
    return tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)


def flatten(res):
    if isinstance(res, (tuple, list)):
        return [y for x in res for y in flatten(x)]
    return [np.asarray(res, dtype=float)]


# ------------------------------------------------------------------------------ coverage
@pytest.mark.parametrize("modname", list(MODULES))
def test_every_public_map_is_covered(modname):
    names = public_maps(MODULES[modname])
    assert names == sorted(TABLE[modname]), \
        f"{modname}: maps without a call-table entry: {set(names) - set(TABLE[modname])}"


def test_interface_and_into_variants_exist():
    common = ["hat", "vee", "exp", "log", "dexp", "dexpinv", "ad", "Ad", "compose", "inverse",
              "exp_into", "log_into", "dexp_apply_into", "dexpinv_apply_into", "compose_into",
              "inverse_into", "Ad_into"]
    for mod in (so3, se3, so3xr3):
        missing = [n for n in common if not isinstance(getattr(mod, n, None), CPUDispatcher)]
        assert not missing, f"{mod.__name__} lacks {missing}"


# -------------------------------------------------------------------- callable from njit
@pytest.mark.parametrize("modname,name", CASES)
def test_callable_from_njit(modname, name):
    f = getattr(MODULES[modname], name)
    args = TABLE[modname][name]
    a_py = copy_args(args)
    r_py = f(*a_py)
    argsNb, resultsNb = called_from_njit(modname)
    a_nb, r_nb = argsNb[name], resultsNb.get(name)
    if name.endswith("_into"):
        assert r_py is None
        written = [k for k, a in enumerate(args) if isinstance(a, np.ndarray) and np.isnan(a).all()]
        assert written
        for k in written:
            assert np.all(np.isfinite(a_py[k])), f"{name} left part of output {k} unwritten"
        r_py, r_nb = [a_py[k] for k in written], [a_nb[k] for k in written]
    a, b = flatten(r_py), flatten(r_nb)
    assert len(a) == len(b)
    for u, v in zip(a, b):
        assert u.shape == v.shape
        assert np.all(np.isfinite(u))
        np.testing.assert_allclose(v, u, rtol=0, atol=4 * np.finfo(float).eps * (1 + np.abs(u).max()))


# ------------------------------------------------------- *_into == the allocating maps
D = inputs()
GROUP_ARGS = {      # pose arguments of the group operations, per module
    "so3": ((D["R"],), (D["R2"],)),
    "se3": ((D["R"], D["r"]), (D["R2"], D["r2"])),
    "so3xr3": ((D["R"], D["r"]), (D["R2"], D["r2"])),
}
ALG = {"so3": D["x"], "se3": D["X"], "so3xr3": D["X"]}


def fresh_pose(modname):
    return (out(3, 3),) if modname == "so3" else (out(3, 3), out(3))


def as_tuple(res):
    return res if isinstance(res, tuple) else (res,)


def assert_pose_equal(got, want):
    for g, w in zip(got, want):
        np.testing.assert_allclose(g, w, rtol=0, atol=4e-16 * (1 + np.abs(w).max()))


@pytest.mark.parametrize("modname", ["so3", "se3", "so3xr3"])
def test_into_variants_equal_allocating_maps(modname):
    mod = MODULES[modname]
    g1, g2 = GROUP_ARGS[modname]
    X = ALG[modname]
    # exp / log
    gx = fresh_pose(modname)
    mod.exp_into(X, *gx)
    assert_pose_equal(gx, as_tuple(mod.exp(X)))
    Xl = np.full(X.size, np.nan)
    mod.log_into(*g1, Xl)
    np.testing.assert_array_equal(Xl, mod.log(*g1))
    # compose / inverse / Ad
    go = fresh_pose(modname)
    mod.compose_into(*g1, *g2, *go)
    assert_pose_equal(go, as_tuple(mod.compose(*g1, *g2)))
    gi = fresh_pose(modname)
    mod.inverse_into(*g1, *gi)
    assert_pose_equal(gi, as_tuple(mod.inverse(*g1)))
    n = 3 if modname == "so3" else 6
    M = out(n, n)
    mod.Ad_into(*g1, M)
    np.testing.assert_array_equal(M, mod.Ad(*g1))
    # aliasing: in-place update g1 := g1 g2, g2 := g1 g2, g := g^-1, Y := dexpinv_X Y
    for target in (0, 1):
        a, b = copy_args(g1), copy_args(g2)
        o = a if target == 0 else b
        mod.compose_into(*a, *b, *o)
        assert_pose_equal(o, as_tuple(mod.compose(*g1, *g2)))
    a = copy_args(g1)
    mod.inverse_into(*a, *a)
    assert_pose_equal(a, as_tuple(mod.inverse(*g1)))
    # group axioms through the _into maps: g g^-1 = e
    e = fresh_pose(modname)
    mod.compose_into(*g1, *gi, *e)
    np.testing.assert_allclose(e[0], np.eye(3), atol=4e-16 * 8, rtol=0)
    if modname != "so3":
        np.testing.assert_allclose(e[1], 0.0, atol=4e-16 * 8, rtol=0)


# ------------------------------------------------------------------ no allocations
@pytest.fixture
def nrt_stats():
    """Enable numba's NRT allocation statistics for the test (internal switch; skip if
    this numba version lacks it)."""
    try:
        from numba.core.runtime import _nrt_python as nrt
        enable, disable = nrt.memsys_enable_stats, nrt.memsys_disable_stats
    except (ImportError, AttributeError):
        pytest.skip("numba NRT statistics not available")
    enable()
    yield rtsys.get_allocation_stats
    disable()


INTO = [(m, n) for m, n in CASES if n.endswith("_into")]


@pytest.mark.parametrize("modname,name", INTO)
def test_into_variants_do_not_allocate(modname, name, nrt_stats):
    f = getattr(MODULES[modname], name)
    args = TABLE[modname][name]
    njit_loop(f, args, 1)                       # compile

    def allocations(n):
        s0 = nrt_stats()
        njit_loop(f, args, n)
        s1 = nrt_stats()
        return s1.alloc - s0.alloc, s1.mi_alloc - s0.mi_alloc

    assert allocations(100) == allocations(1), f"{modname}.{name} allocates per call"


def test_allocation_check_detects_allocation(nrt_stats):
    """The check above is not vacuous: an allocating map is caught."""
    args = (D["X"],)
    njit_loop(se3.exp, args, 1)
    s0 = nrt_stats()
    njit_loop(se3.exp, args, 1)
    s1 = nrt_stats()
    njit_loop(se3.exp, args, 100)
    s2 = nrt_stats()
    assert s2.alloc - s1.alloc > s1.alloc - s0.alloc

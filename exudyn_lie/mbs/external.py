"""The right-hand side evaluated outside the compiled code: one seam of the stepper.

The compiled stepper (:mod:`.stepper`) calls the registered evaluator once per evaluated
stage when the scene has an external part (``SceneData.hasQext``), through :func:`call`
(one call through the C API): no Python stage loop, one Python call per stage.  The external
part is the generalised forces of Python callbacks (``Scene.AddPythonForce``, the
bridge's user functions), added to the compiled forces, and the moving offsets of rows
(:mod:`.row_drives`) and a whole right-hand side (``Scene.SetRightHandSide``, ``EXTERNAL_RATES``:
a problem implementation such as the bridge's evaluation of a whole model).

An evaluator is a Python callable ``f(t)``: the stage state and the output are arrays
of the evaluator's owner that the compiled code shares (``wk.Rs, wk.rs``, the world
velocities ``wk.Vw``, the items' kinematics ``wk.probe`` (:mod:`.external_probes`) and the
output ``wk.Qext``, see ``external_calls.external_forces``), so the call boxes no array and the
evaluator allocates nothing of its own.  It is registered under an integer token; the
compiled code holds its :func:`handle` (in ``Work.ext[0]``, as numba cannot hold a Python
object); an exception it raises is kept and the stepper returns ``STATUS_EXTERNAL``, after
which the caller re-raises it with :func:`reraise`.
"""
import itertools
import weakref

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

_EVALUATORS = {}
_ERRORS = {}
_TOKENS = itertools.count(1)


def register(owner, method_name):
    """Register ``getattr(owner, method_name)`` (held through a weak reference to
    ``owner``, so the registry does not keep a simulator alive); returns the token."""
    token = next(_TOKENS)
    ref = weakref.ref(owner)
    # the plain function and a weak reference to the owner: calling them costs less than a
    # WeakMethod, whose call is Python code, on every stage
    fn = getattr(type(owner), method_name)

    def evaluator(t):
        try:
            fn(ref(), t)
            return 0
        except BaseException as e:       # noqa: BLE001 - re-raised by the caller after the kernel returns
            _ERRORS[token] = e
            return 1
    _EVALUATORS[token] = evaluator
    weakref.finalize(owner, _EVALUATORS.pop, token, None)
    return token


def handle(token):
    """What the compiled code holds of the evaluator of ``token`` (``Work.ext[0]``,
    ``Work.drive[0]``) and passes to :func:`call`: the address of the evaluator ``f(t) -> 0 / 1``.
    It stays valid while the owner lives (the registry holds the evaluator until then), and
    the compiled stepper runs only inside its owner's methods (``Simulator.Advance``, ...)."""
    return id(_EVALUATORS[token])


def evaluate(token, t):
    """The evaluator of ``token`` called from Python: 0 on success, 1 if it raised (the
    exception is kept for :func:`reraise`)."""
    return _EVALUATORS[token](t)


@intrinsic
def call(typingctx, evaluator, t):
    """``evaluator(t)`` from compiled code (``evaluator`` a :func:`handle`): 0 on success, 1
    if it raised (the evaluator keeps the exception for :func:`reraise`).

    The GIL taken, ``t`` boxed, one call through the C API, the result unboxed.  Numba's
    ``objmode`` block costs ten times as much per call: before its call it rebuilds the
    lifted block's dispatcher from a pickle (a bytes copy and a Python-level memo lookup)
    at every call (a no-op evaluator called in a compiled loop: 33 ns here, 350-420 ns with
    ``objmode``; overhead per call of ``bench --sections userfunctions --quick``,
    interleaved: zero user load 1.07-1.16 -> 0.69-0.73 us, PD torque 1.32-1.38 -> 0.92-0.95 us)."""
    sig = types.int64(types.int64, types.float64)

    def codegen(context, builder, signature, args):
        address, tval = args
        pyapi = context.get_python_api(builder)
        out = cgutils.alloca_once_value(builder, ir.Constant(ir.IntType(64), 1))
        with builder.if_then(cgutils.is_not_null(builder, address)):      # no evaluator: 1, not a crash
            gil = pyapi.gil_ensure()
            targ = pyapi.float_from_double(tval)
            res = pyapi.call_function_objargs(builder.inttoptr(address, pyapi.pyobj), [targ])
            pyapi.decref(targ)
            with builder.if_else(cgutils.is_not_null(builder, res)) as (ok, failed):
                with ok:
                    builder.store(pyapi.long_as_longlong(res), out)
                    pyapi.decref(res)
                with failed:              # the evaluator catches everything; this is boxing failing
                    pyapi.err_clear()
            pyapi.gil_release(gil)
        return builder.load(out)
    return sig, codegen


def reraise(token):
    """Raise the exception kept for ``token`` (if any)."""
    e = _ERRORS.pop(token, None)
    if e is not None:
        raise e

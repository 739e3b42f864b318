"""The right-hand side evaluated outside the compiled code: one seam of the stepper.

The compiled stepper (:mod:`.stepper`) calls :func:`evaluate` once per evaluated stage
when the scene has an external part (``SceneData.hasQext``), from a numba ``objmode``
block: no Python stage loop, one Python call per stage.  Today the external part is
the generalised forces of Python callbacks (``Scene.AddPythonForce``, the bridge's
user functions), added to the compiled forces; a right-hand side that Exudyn evaluates
(issue 17) plugs in here as another kind of evaluator.

An evaluator is a Python callable ``f(t)``: the stage state and the output are arrays
of the evaluator's owner that the compiled code shares (``wk.Rs, wk.rs``, the world
velocities ``wk.Vw`` and the output ``wk.Qext``, see ``stepper.external_forces``), so
the objmode call boxes no array and the evaluator allocates nothing of its own.  It is
registered under an integer token (kept in ``Work.ext[0]``, as numba cannot hold a
Python object); an exception it raises is kept and the stepper returns
``STATUS_EXTERNAL``, after which the caller re-raises it with :func:`reraise`.
"""
import itertools
import weakref

_EVALUATORS = {}
_ERRORS = {}
_TOKENS = itertools.count(1)


def register(owner, method_name):
    """Register ``getattr(owner, method_name)`` (held through a weak reference to
    ``owner``, so the registry does not keep a simulator alive); returns the token."""
    token = next(_TOKENS)
    # (a weak reference to the owner and the plain function: calling them costs less
    # than a WeakMethod, whose call is Python code, on every stage)
    _EVALUATORS[token] = (weakref.ref(owner), getattr(type(owner), method_name))
    weakref.finalize(owner, _EVALUATORS.pop, token, None)
    return token


def evaluate(token, t):
    """Called by the compiled stepper (objmode): 0 on success, 1 if the evaluator raised
    (the exception is kept for :func:`reraise`)."""
    try:
        owner, fn = _EVALUATORS[token]
        fn(owner(), t)
        return 0
    except BaseException as e:       # noqa: BLE001 - re-raised by the caller after the kernel returns
        _ERRORS[token] = e
        return 1


def reraise(token):
    """Raise the exception kept for ``token`` (if any)."""
    e = _ERRORS.pop(token, None)
    if e is not None:
        raise e

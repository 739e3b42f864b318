"""An overload that is always inlined is not also compiled as a function of its own.

The kernel's compile-time choices are numba overloads with ``inline="always"``: the feature
guards of :mod:`exudyn_lie.mbs.presence`, the method and step-controller seams of
``stepper.mk_steps`` (the explicit stage's held the whole stage right-hand side until that moved
into ``stepper.stage_rhs_llvm_inlined``, which LLVM inlines). numba inlines the
*typed IR* of such an overload's implementation at the call site, which is all it needs. But
it first compiles the implementation completely, as a function nothing calls
(``_OverloadFunctionTemplate._build_impl``: "make sure that the implementation can be fully
compiled": typing, lowering and LLVM's optimisation), then types it again for the inlining.
Every guarded feature and the stage right-hand side were compiled twice on a first run.

Here the implementation dispatcher of this package's always-inlined overloads is made unable to
compile (``_can_compile``): numba's typing of the call still runs the inliner's own type
inference, and the code inlined is the same typed IR as before, so the machine code does not
change. Other overloads (numba's own, other packages') are left alone. Imported at the end of
:mod:`exudyn_lie._numba_cache`, before any compiled function is defined.

The compile numba skips here also bound a ``literally`` request of the implementation to the
argument folding (``ForceLiteralArg.bind_fold_arguments``, as ``Dispatcher.compile`` does);
:func:`install`'s ``generic`` binds it instead. Patched only on the numba versions it was read
and tested against (:data:`TESTED_NUMBA`); on any other, numba compiles as it does by itself.
"""
import numba
from numba.core import errors
from numba.core.typing import templates

_PACKAGE = __name__.rpartition(".")[0]
_Template = getattr(templates, "_OverloadFunctionTemplate", None)
#: numba versions (major, minor) whose ``_OverloadFunctionTemplate`` this patch was checked against
TESTED_NUMBA = ((0, 68),)


def _ours_and_always_inlined(template):
    inline = getattr(template, "_inline", None)
    module = getattr(template._overload_func, "__module__", None) or ""
    return (bool(_PACKAGE) and inline is not None and inline.is_always_inline
            and (module == _PACKAGE or module.startswith(_PACKAGE + ".")))


def _typing_only(jitter):
    """``jitter``, whose dispatchers never compile: only typed for inlining."""
    def decorator(*args, **options):
        make = jitter(*args, **options)

        def dispatcher_of(pyfunc):
            disp = make(pyfunc)
            if hasattr(disp, "_can_compile"):
                disp._can_compile = False
            return disp
        return dispatcher_of
    return decorator


def install():
    if (tuple(numba.version_info[:2]) not in TESTED_NUMBA or _Template is None
            or not all(hasattr(_Template, a) for a in ("_get_jit_decorator", "_get_impl", "generic"))):
        return
    original = _Template._get_jit_decorator
    if getattr(original, "_exudyn_lie", False):
        return
    typed = _Template.generic

    def _get_jit_decorator(self):
        jitter = original(self)
        return _typing_only(jitter) if _ours_and_always_inlined(self) else jitter

    def generic(self, args, kws):
        try:
            return typed(self, args, kws)
        except errors.ForceLiteralArg as e:
            if e.fold_arguments is not None or not _ours_and_always_inlined(self):
                raise
            disp, _ = self._get_impl(args, kws)
            raise e.bind_fold_arguments(lambda a, k: disp._compiler.fold_argument_types(a, k)[1])

    _get_jit_decorator._exudyn_lie = True
    _Template._get_jit_decorator = _get_jit_decorator
    _Template.generic = generic


install()

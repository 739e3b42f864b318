"""LLVM's inlining where numba's options cannot say it: the group maps stay calls (LLVM
``noinline``), the stage right-hand side is inlined by LLVM (``alwaysinline``).

numba has ``forceinline=True`` (LLVM ``alwaysinline``) but no way to say the opposite, and
without either attribute LLVM's inliner decides by the size of the caller.  The group maps
(``exudyn_lie.groups``: exp, dexp^-1, their Taylor branches) are then inlined into the stage
loop or not depending on how much else the loop holds, i.e. on which features the scene
compiles (mbs/presence.py).  Inlined, they made the heavy top's step 10-15 % slower (1.65 ->
1.91 us, measured interleaved), and they may change a state's last bits (their FMA
contractions are decided again in the caller).  So every function of ``exudyn_lie.groups``
that is not ``forceinline`` gets ``noinline`` where numba declares it.

``stepper.stage_rhs_llvm_inlined`` gets ``alwaysinline`` by name: numba's ``forceinline=True`` would
do the same for it but also for every function compiled on its behalf (numba's flags inherit
``forceinline`` unless a function sets it), and so change what the whole right-hand side inlines.

Imported at the end
of :mod:`exudyn_lie._numba_cache`, which every compiled module imports first, so the patch is in
place before any compiled function is defined.
"""
from numba.core import base

_PREFIX = __name__.rpartition(".")[0] + ".groups."
_ALWAYS = {(__name__.rpartition(".")[0] + ".mbs.stepper", "stage_rhs_llvm_inlined")}
_declare = base.BaseContext.declare_function


def _declare_function(self, module, fndesc):
    fn = _declare(self, module, fndesc)
    if not fndesc.inline and (fndesc.modname or "").startswith(_PREFIX):
        fn.attributes.add("noinline")
    elif (fndesc.modname, fndesc.qualname) in _ALWAYS:
        fn.attributes.add("alwaysinline")
    return fn


if not getattr(base.BaseContext.declare_function, "_exudyn_lie", False):
    _declare_function._exudyn_lie = True
    base.BaseContext.declare_function = _declare_function

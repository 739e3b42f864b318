"""The stage right-hand side called through its address: one compiled copy per kind of scene.

numba links the code of every compiled callee into each caller's module and optimises and
compiles the whole module again there (``CPUCodeLibrary.finalize`` links the callees' modules,
then runs LLVM over all of it).  The stage right-hand side (forces, joint rows, the index-1
solve: ``stepper.stage_rhs_at``) is the largest callee of the kernel, and each function outside
the stage loop that evaluated it carried it through LLVM once more: the Newton iteration's
Jacobian, its iterate, the grouped differences and their probe (mbs/implicit.py,
mbs/jacobian_groups.py) and the dense output's extra stages (mbs/adaptive.py).
``newton_jacobian`` alone took 9.8 s, 8.0 s of it in LLVM (by hand: its ``metadata['timers']``,
compiled with the rest cached).  Called through its address, the right-hand side is compiled once,
as ``stage_rhs_at`` itself, and those callers hold an indirect call.  The time loop itself keeps
its direct calls (the explicit stages' inlined copy, an implicit method's first stage, the fixed
steps' watch): ``stage_rhs_at`` loaded as a library of its own costs about 0.1 s per process (by
hand, warm cache), which a process that integrates fixed explicit steps would pay for nothing.

The address is data, so the callers stay cacheable: :func:`rhs_address` compiles (or loads from
the cache) ``stage_rhs_at`` for the types of a scene's ``SceneData`` and ``Work`` and returns the
address of its native function; the simulator writes it into ``wk.ext[EXT_RHS]`` of every
``Work`` it makes for an implicit method or adaptive steps (``Simulator._make_work``: no other
code makes one; ``AdaptiveRun``, when adaptive steps start).  A ``Work`` without it makes the call return ``STATUS_NO_RHS`` instead of
jumping to 0.
"""
from llvmlite import ir
from numba import njit, types, typeof
from numba.core import cgutils
from numba.core.callconv import excinfo_t
from numba.core.errors import TypingError
from numba.extending import intrinsic

from .codes import EXT_RHS, STATUS_NO_RHS

_STAGE_RATES = types.Array(types.float64, 2, "C")
_ADDRESSES = {}


def rhs_signature(sd, wk):
    """The argument types ``stage_rhs_at`` is compiled for (the callers' ``Vdot``: a C-contiguous
    (nb, 6) array)."""
    return (typeof(sd), typeof(wk), types.float64, _STAGE_RATES)


def rhs_address(sd, wk):
    """The address of ``stepper.stage_rhs_at`` compiled for ``sd`` and ``wk``'s types (compiled or
    loaded from the cache once per process and kind of scene)."""
    sig = rhs_signature(sd, wk)
    addr = _ADDRESSES.get(sig)
    if addr is None:
        from .stepper import stage_rhs_at
        stage_rhs_at.compile(sig)
        cres = stage_rhs_at.overloads[sig]
        if cres.signature.return_type != types.int64:
            raise TypeError(f"stage_rhs_at returns {cres.signature.return_type}, the call expects int64")
        addr = int(cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name))
        if not addr:
            raise RuntimeError(f"no native function {cres.fndesc.llvm_func_name} in stage_rhs_at's library")
        _ADDRESSES[sig] = addr
    return addr


def keep_rhs_address(sd, wk):
    """Write the address for ``sd`` into ``wk.ext[EXT_RHS]``."""
    wk.ext[EXT_RHS] = rhs_address(sd, wk)


@intrinsic
def _call_at(typingctx, addr, sd, wk, t, Vdot):
    """``stage_rhs_at(sd, wk, t, Vdot)`` through the native function at ``addr`` (numba's calling
    convention: return slot, exception slot, the flattened arguments; a status code)."""
    if Vdot != _STAGE_RATES:
        raise TypingError(f"the right-hand side by address writes a C-contiguous (nb, 6) array, got {Vdot}")
    sig = types.int64(types.int64, sd, wk, types.float64, _STAGE_RATES)

    def codegen(context, builder, signature, args):
        cc = context.call_conv
        argtys = signature.args[1:]
        fnty = cc.get_function_type(types.int64, argtys)
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        retty = cc.get_return_type(types.int64).pointee
        ret = cgutils.alloca_once(builder, retty)
        builder.store(cgutils.get_null_value(retty), ret)
        exc = cgutils.alloca_once(builder, ir.PointerType(excinfo_t), name="excinfo")
        code = builder.call(fn, [ret, exc] + list(cc._get_arg_packer(argtys).as_arguments(builder, args[1:])))
        status = cc._get_return_status(builder, code, builder.load(exc))
        with cgutils.if_unlikely(builder, status.is_error):
            cc.return_status_propagate(builder, status)
        return context.get_returned_value(builder, types.int64, builder.load(ret))
    return sig, codegen


@njit(cache=True, inline="always", _nrt=False)
def rhs_at(sd, wk, t, Vdot):
    """``stepper.stage_rhs_at(sd, wk, t, Vdot)`` through the address in ``wk.ext[EXT_RHS]``."""
    addr = wk.ext[EXT_RHS]
    if addr == 0:
        return STATUS_NO_RHS
    return _call_at(addr, sd, wk, t, Vdot)

"""Exudyn bridge: solve an ordinary Exudyn ``mbs`` with exudyn_lie's Lie group integrators.

>>> import exudyn as exu, exudyn_lie as exl
>>> mbs.Assemble()
>>> exl.SolveDynamic(mbs, simulationSettings, method='RK4', liegroup='SE3')
True

* :func:`SolveDynamic` - drop-in for ``exudyn.SolveDynamic`` (sensors, solution file,
  pre/post-step functions work as in a native solve);
* :func:`GetSolveTiming` - where the last call's time went (set-up, compilation, time loop);
* :class:`LieGroupSolver` - read the model once, solve many times (``Solve``, fast ``Run``);
* :func:`SceneFromExudyn` - the model as an exudyn_lie :class:`~exudyn_lie.mbs.Scene`;
* :data:`NODE_KINDS` - the node registry (RotVecLG, EP, Rxyz).
"""
from .. import _numba_cache  # noqa: F401  (first: the cache key of every compiled function)
from .nodes import NODE_KINDS, EPNode, NodeKind, RotVecLGNode, RxyzNode
from .reader import BridgeError, ExudynScene, SceneFromExudyn
from .solve_dynamic import SolveDynamic
from .solve_timing import GetSolveTiming
from .solver import LieGroupSolver

__all__ = ["SolveDynamic", "GetSolveTiming", "LieGroupSolver", "SceneFromExudyn", "ExudynScene", "BridgeError",
           "NODE_KINDS", "NodeKind", "RotVecLGNode", "EPNode", "RxyzNode"]

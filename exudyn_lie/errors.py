"""The package's run-time errors, below every layer: the adaptive controller of
``integrators`` raises :class:`StepSizeError` as the compiled driver of ``mbs`` does, and
neither layer imports the other for it.  Re-exported by ``exudyn_lie.mbs.simulator`` and
the package."""


class SimulationError(RuntimeError):
    """A run that cannot continue (singular constraints, blow-up, non-finite state)."""


class ConstraintError(SimulationError):
    """Singular or inconsistent constraints."""


class StepSizeError(SimulationError):
    """The step size is beyond the stability limit of the method, a stage rotation argument
    of the MK step left the domain of dexp^-1 (``kernel.STAGE_ARG_MAX``), or adaptive steps
    would fall below the minimum step (``.time``, ``.step``)."""


def raised_at_boundary(errors):
    """Decorator for the package's entry points: an error of the classes ``errors`` (input
    refused, a run that cannot go on) is raised again with a traceback that ends at the
    user's call, not 15 frames deep in the package; its message names the item and the
    cause.  Other exceptions (a user function's own, a bug) keep their whole traceback, and
    so does every error with the environment variable ``EXUDYN_LIE_TRACEBACK=1``."""
    import functools
    import os

    def wrap(fn):
        @functools.wraps(fn)
        def entry(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            except errors as e:
                if os.environ.get("EXUDYN_LIE_TRACEBACK"):
                    raise
                if e.__cause__ is None:
                    e.__suppress_context__ = True
                raise e.with_traceback(None)
        return entry
    return wrap

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


def step_size_error(method, h, t, what, why, advice):
    """The one StepSizeError text: ``what`` happened at time ``t`` with step size ``h`` (method
    name ``method``) because ``why``; ``advice``: the step size to try (a number) or what to
    change (a text).  ``.time`` and ``.step`` carry ``t`` and ``h``."""
    if not isinstance(advice, str):
        advice = f"try a step size of {advice:.3g} s or smaller"
    exc = StepSizeError(f"{what} at t = {t:.6g} s with step size {h:.3g} s (method {method}); {why}: {advice}")
    exc.time = float(t)
    exc.step = float(h)
    return exc


def minimum_step_error(method, t, h, hMin, err):
    """The StepSizeError of adaptive steps whose error control asks for a step ``h`` below the
    minimum ``hMin`` (``err``: the scaled error of the rejected step)."""
    exc = step_size_error(method, h, t, "adaptive steps stopped",
                          f"the error control asks for a step below the minimum step {hMin:.3g} s (scaled "
                          f"error {err:.3g} of the rejected step)",
                          "increase the tolerances or decrease the minimum step size")
    exc.setting = "minimumStep"          # the setting to change (a bridge names it in its own terms)
    return exc


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

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

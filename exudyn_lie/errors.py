"""The errors of a run, shared by every layer (the integrators raise them as well as the
multibody simulator and the bridge): one module below all others, so that no layer has to
import a higher one for them."""


class SimulationError(RuntimeError):
    """A run that cannot continue (singular constraints, blow-up, non-finite state)."""


class ConstraintError(SimulationError):
    """Singular or inconsistent constraints."""


class StepSizeError(SimulationError):
    """The step size is beyond the stability limit of the method, or a stage rotation
    argument of the MK step left the domain of dexp^-1 (``kernel.STAGE_ARG_MAX``), or an
    adaptive step fell below the minimum step size."""

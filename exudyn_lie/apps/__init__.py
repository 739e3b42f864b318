"""The applications built on the solver library: ``python -m exudyn_lie paper | bench | stress``.

They are apart from the library so that ``import exudyn_lie`` loads neither them nor
matplotlib.  Layers (each imports only the ones above it): the library
(``exudyn_lie.groups``, ``.integrators``, ``.mbs``, ``.bridge``), the paper's models
(``exudyn_lie.models``, with the measures computed from their descriptions:
``models.geometry``, ``models.energy``), then these applications:

* :mod:`.paper`  - the paper's comparison: :mod:`.runs` (MK-RK4 and Exudyn's native runs),
  :mod:`.claims` (the paper's claims judged), :mod:`.plots`, :mod:`.report`;
* :mod:`.bench`  - work-precision and per-step benchmarks: :mod:`.bench_runs`, :mod:`.bench_wp`,
  :mod:`.bench_micro`;
* :mod:`.stress` - the stress suite: :mod:`.stress_cases`, :mod:`.stress_models`, :mod:`.stress_theory`;
* :mod:`.generated` - the README's generated blocks; :func:`versions` the versions they name.
"""
from .. import _numba_cache  # noqa: F401  (first: the cache key of every compiled function)


def versions():
    """Versions of exudyn_lie and the packages its results depend on ('not installed' if absent)."""
    import importlib
    out = {}
    for mod in ("exudyn_lie", "exudyn", "numpy", "numba"):
        try:
            out[mod] = getattr(importlib.import_module(mod), "__version__", "?")
        except ImportError:
            out[mod] = "not installed"
    return out

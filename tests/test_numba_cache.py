"""The numba cache of the package is keyed on all of its compiled sources.

numba stamps a cached function with its own source file only; a caller that inlines a
callee of another module would keep running the old callee after an edit.  The
package's locators (``exudyn_lie._numba_cache``) add a hash of every module that uses
numba to the stamp."""
import os
import shutil

import pytest

from exudyn_lie import _numba_cache as nc
from exudyn_lie.groups import se3, so3
from exudyn_lie.mbs import kernel


def _locator(dispatcher):
    return dispatcher._cache._impl.locator


def test_package_functions_use_the_package_locators():
    for f in (kernel.mk_steps, so3.exp_into, se3.dexpinv_apply_into):
        loc = _locator(f)
        assert isinstance(loc, nc.LOCATORS), type(loc)
        stamp = loc.get_source_stamp()
        assert stamp[1] == nc.package_key()


def test_key_covers_callee_modules(tmp_path):
    root = tmp_path / "exudyn_lie"
    shutil.copytree(nc.PACKAGE_DIR, root, ignore=shutil.ignore_patterns("__pycache__"))
    rels = nc.compiled_sources(str(root))
    for rel in ("groups/so3.py", "groups/se3.py", "mbs/stepper.py", "mbs/codes.py", "mbs/linalg.py",
                "bridge/nodes.py"):
        assert rel.replace("/", os.sep) in rels
    k0 = nc.source_key(str(root))
    assert k0 == nc.source_key(nc.PACKAGE_DIR)
    # an edit of a callee (the group maps) changes the key of every compiled function
    p = root / "groups" / "so3.py"
    p.write_text(p.read_text() + "\n# edited\n")
    k1 = nc.source_key(str(root))
    assert k1 != k0
    # an application module without numba does not take part
    p = root / "apps" / "report.py"
    p.write_text(p.read_text() + "\n# edited\n")
    assert nc.source_key(str(root)) == k1


def test_other_packages_keep_numbas_locator(tmp_path):
    src = tmp_path / "other_mod.py"
    src.write_text("def f():\n    return 1\n")
    assert nc.PackageInTreeCacheLocator.from_function(None, str(src)) is None
    assert nc.PackageUserWideCacheLocator.from_function(None, str(src)) is None


_LOAD_SCRIPT = r"""
import sys
import numpy as np
from numba import njit
from exudyn_lie import _numba_cache as nc
from exudyn_lie.groups import so3

x = np.array([0.3, -0.2, 0.7])
R = np.zeros((3, 3))
so3.exp_into(x, R)                       # run 1: compiled and saved; run 2: loaded from the cache
loaded = bool(so3.exp_into.stats.cache_hits)
print("loaded", loaded, "pending", len(nc._LazyBitcode.pending))


@njit
def twice(x, R):                         # a new compile linking the cached library in
    so3.exp_into(x, R)
    so3.exp_into(2.0 * x, R)
    return R[0, 1]


R2 = np.zeros((3, 3))
so3.exp_into(2.0 * x, R2)
print("linked", twice(x, R) == R2[0, 1], "pending", len(nc._LazyBitcode.pending))
"""


def test_cache_load_defers_bitcode_and_runtime(tmp_path):
    """A function loaded from the cache (a second process) leaves its bitcode unparsed, and a
    new compile that links it in parses the bitcode and gives the same numbers as the loaded
    function."""
    import subprocess
    import sys
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = []
    for _ in range(2):
        p = subprocess.run([sys.executable, "-c", _LOAD_SCRIPT], env=env, capture_output=True, text=True,
                           timeout=600, cwd=os.path.dirname(nc.PACKAGE_DIR))
        assert p.returncode == 0, p.stderr[-2000:]
        out.append(p.stdout.split())
    first, second = out
    assert first[first.index("loaded") + 1] == "False"
    assert second[second.index("loaded") + 1] == "True"
    assert second[second.index("pending") + 1] == "1"          # loaded, bitcode not parsed
    assert second[second.index("linked") + 1] == "True"
    assert second[-1] == "0"                                   # linking parsed it


def test_an_index_that_names_a_removed_class_is_an_empty_index(tmp_path):
    """An index written by other sources, whose argument types include a class the package no longer
    has (methods.PartitionedMethod), is stale: numba unpickled it before comparing its stamp and
    raised at every load; the package's load_index takes it as empty (the function compiles)."""
    import pickle
    import sys
    import types
    from collections import namedtuple
    from numba.core import caching
    mod = types.ModuleType("exudyn_lie_test_gone_module")
    Gone = namedtuple("Gone", ["a"])
    Gone.__module__ = mod.__name__
    mod.Gone = Gone
    sys.modules[mod.__name__] = mod
    try:
        index = caching.IndexDataCacheFile(str(tmp_path), "fn-1.py311", ("stamp", "key"))
        index._save_index({(Gone(1), "signature"): "fn-1.py311.0.nbc"})
        assert index._load_index() == {(Gone(1), "signature"): "fn-1.py311.0.nbc"}
        del mod.Gone
        with pytest.raises((AttributeError, pickle.UnpicklingError)):
            nc._numba_load_index(index)                     # numba's own load
        assert caching.IndexDataCacheFile._load_index is nc.load_index
        assert index._load_index() == {}
    finally:
        del sys.modules[mod.__name__]

"""numba's on-disk cache keyed on every compiled source of the package, not one file.

numba validates a cached function by a stamp of *its own* source file only.  The
kernel inlines and calls functions of other modules (the group maps into the stage
loop, the joint rows into the right-hand side, ...), so editing a callee left the
caller's cached machine code in place and it silently ran the old callee.

This module registers two cache locators, in front of numba's own, for the functions
defined in this package: they store where numba would (the ``__pycache__`` beside the
module, or numba's user-wide cache directory when that is not writable) but add
:func:`source_key` to the stamp - a hash of every module of the solver library and of the
application modules that import numba (:func:`compiled_sources`).  Editing any of them invalidates every cached function of the package (numba
then recompiles on first use and overwrites the stale entries); other packages' numba
functions are not affected.  Imported by ``exudyn_lie/__init__.py`` before any
compiled function is defined.
"""
import hashlib
import os
import pickle
import re
import weakref

from numba.core import caching, codegen, dispatcher

PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))

_KEY = None
_APPLICATION_DIRS = ("apps", "models")
_IMPORTS_NUMBA = re.compile(rb"^[ \t]*(?:from|import)[ \t]+numba\b", re.M)


def compiled_sources(root=PACKAGE_DIR):
    """The modules whose edit may change compiled code (sorted paths relative to ``root``):
    every module of the solver library (compiled functions read module constants such as
    ``mbs/codes.py`` at compile time, so modules without numba count too), and the
    application modules that import numba.  The applications' other modules and the
    models do not take part."""
    out = []
    for d, dirs, files in os.walk(root):
        dirs[:] = sorted(x for x in dirs if x != "__pycache__")
        for f in sorted(files):
            if f.endswith(".py"):
                p = os.path.join(d, f)
                top = os.path.relpath(p, root).split(os.sep)[0]
                if top not in _APPLICATION_DIRS:
                    out.append(os.path.relpath(p, root))
                    continue
                with open(p, "rb") as fh:
                    if _IMPORTS_NUMBA.search(fh.read()):
                        out.append(os.path.relpath(p, root))
    return out


def source_key(root=PACKAGE_DIR):
    """sha256 over the paths and contents of :func:`compiled_sources` (hex)."""
    h = hashlib.sha256()
    for rel in compiled_sources(root):
        h.update(rel.replace(os.sep, "/").encode() + b"\0")
        with open(os.path.join(root, rel), "rb") as fh:
            h.update(fh.read())
        h.update(b"\0")
    return h.hexdigest()


def package_key():
    """:func:`source_key` of this installation, computed once per process."""
    global _KEY
    if _KEY is None:
        _KEY = source_key()
    return _KEY


def _in_package(py_file):
    try:
        return os.path.commonpath([os.path.abspath(py_file), PACKAGE_DIR]) == PACKAGE_DIR
    except ValueError:          # different drives
        return False


_WRITABLE_DIRS = set()


class _PackageKeyMixin:
    def ensure_cache_path(self):
        """numba's check that the cache directory is writable (it creates a temporary file
        there) once per directory and process, not once per function: the package defines
        300 of them at import (10 ms).  A directory that vanished is checked again."""
        path = self.get_cache_path()
        if path in _WRITABLE_DIRS and os.path.isdir(path):
            return
        super().ensure_cache_path()
        _WRITABLE_DIRS.add(path)

    def get_source_stamp(self):
        return (super().get_source_stamp(), package_key())

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _in_package(py_file):
            return None
        return super().from_function(py_func, py_file)


class PackageUserProvidedCacheLocator(_PackageKeyMixin, caching.UserProvidedCacheLocator):
    """numba's locator for NUMBA_CACHE_DIR with the package source key in the stamp."""


class PackageInTreeCacheLocator(_PackageKeyMixin, caching.InTreeCacheLocator):
    """numba's in-tree locator with the package source key in the stamp."""


class PackageUserWideCacheLocator(_PackageKeyMixin, caching.UserWideCacheLocator):
    """numba's user-wide locator with the package source key in the stamp."""


def shared_cache_root():
    """The cache shared by every copy of the package on this machine (a checkout and an
    installed copy): ``EXUDYN_LIE_CACHE_DIR``, else ``$XDG_CACHE_HOME/exudyn_lie`` (default
    ``~/.cache/exudyn_lie``)."""
    root = os.environ.get("EXUDYN_LIE_CACHE_DIR")
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "exudyn_lie")
    return root


def shared_cache_dir():
    """This version's part of :func:`shared_cache_root`: one folder per :func:`package_key`,
    so copies of the same sources share it and other versions do not touch it."""
    return os.path.join(shared_cache_root(), package_key()[:16])


class PackageSharedCacheLocator(_PackageKeyMixin, caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """The package's functions cached in :func:`shared_cache_dir`, under their module's folder
    relative to the package.  numba's own stamp is the source file's time and size, which
    differ between a checkout and an installed copy of the same sources; the package key
    (the hash of every compiled source's contents) is the whole stamp here.  Without a
    writable cache root, the in-tree locator takes over."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        rel = os.path.relpath(os.path.dirname(os.path.abspath(py_file)), PACKAGE_DIR)
        self._cache_path = os.path.normpath(os.path.join(shared_cache_dir(), "numba", rel))

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return ("any copy of the sources", package_key())


LOCATORS = (PackageUserProvidedCacheLocator, PackageSharedCacheLocator, PackageInTreeCacheLocator,
            PackageUserWideCacheLocator)

_numba_load_overload = caching.Cache.load_overload


def load_overload(self, sig, target_context):
    """numba's ``Cache.load_overload`` without the full context refresh for the package's
    functions.

    numba refreshes the target context before every cache load: it imports and installs
    all its lowering registries, and ``numba.np.arraymath`` imports ``scipy.linalg`` to
    probe for BLAS.  That was 0.23 s of a warm first solve (0.12 s the scipy import, 0.11 s
    the registries; wall time on an idle machine, each timed alone in a fresh process; the
    whole: ``python -m exudyn_lie bench --sections startup``), spent only for *compiling*: a
    cached function needs the NRT runtime's symbols when its object code is linked, and
    nothing of the registries.  So a package function initialises the runtime only, and
    a cache miss compiles as before (numba's compiler refreshes the contexts itself)."""
    if not isinstance(self._impl.locator, LOCATORS):
        return _numba_load_overload(self, sig, target_context)
    with self._guard_against_spurious_io_errors():
        return _load_package_overload(self, sig, target_context)


def _load_package_overload(self, sig, target_context):
    """numba's ``Cache._load_overload`` without parsing the library's bitcode at the load.

    numba keeps a cached library's bitcode beside its object code, for linking it into a
    later compile, and parses it at every load: for the large stage loop most of a warm
    first solve (heavy top through the kernel, first solve minus second: 0.067 s before, 0.038 s
    after, ``python -m exudyn_lie bench --sections startup --quick``).  Here it is parsed when something asks
    for it (:class:`_LazyBitcode`).  The NRT runtime is initialised as before: every
    CPython wrapper names its symbols (``NRT_adapt_ndarray_from_python``, ...)."""
    from numba.core.runtime import rtsys
    if not self._enabled:
        return None
    rtsys.initialize(target_context)
    key = self._index_key(sig, target_context.codegen())
    data = self._cache_file.load(key)
    if data is None:
        return None
    libdata, fndesc = data[0], data[1]
    name, kind, payload = libdata
    if kind == "object":
        obj, bitcode = payload
        data = ((name, _LAZY_KIND, (obj, bitcode, fndesc.llvm_cpython_wrapper_name)),) + tuple(data[1:])
    return self._impl.rebuild(target_context, data)


_LAZY_KIND = "exudyn_lie-object"


class _LazyBitcode:
    """The bitcode of libraries loaded from the cache, parsed on first need.

    numba parses a cached library's bitcode at once, for two uses: the names of the symbols
    it defines (the JIT engine answers ``is_symbol_defined`` from them) and the module that
    a later compile links in.  Here the library registers only its entry point (the
    CPython wrapper the dispatcher looks up) and waits in :data:`pending`; any question
    about another symbol, and any request of the module for linking, parses the waiting
    bitcode first, so every answer is the one numba would give."""
    pending = []

    @classmethod
    def unserialize(cls, library_class, codegen, state):
        name, kind, data = state
        if kind != _LAZY_KIND:
            return _numba_unserialize.__func__(library_class, codegen, state)
        obj, bitcode, entry = data
        lib = codegen.create_library(name)
        lib.enable_object_caching()
        lib._set_compiled_object(obj)
        lib._exl_bitcode = bitcode
        lib._finalize_final_module()
        codegen._engine._defined_symbols.add(entry)
        cls.pending.append(weakref.ref(lib))      # a library that is gone needs no parse
        return lib

    @classmethod
    def parse(cls, lib):
        from llvmlite import binding as ll
        bitcode = lib.__dict__.pop("_exl_bitcode", None)
        if bitcode is not None:
            lib._shared_module = ll.parse_bitcode(bitcode)
            lib._codegen._engine._load_defined_symbols(lib._shared_module)

    @classmethod
    def parse_all(cls):
        while cls.pending:
            lib = cls.pending.pop()()
            if lib is not None:
                cls.parse(lib)


def _is_symbol_defined(self, name):
    if name in self._defined_symbols:
        return True
    if _LazyBitcode.pending:
        _LazyBitcode.parse_all()
        return name in self._defined_symbols
    return False


def _get_module_for_linking(self):
    if "_exl_bitcode" in self.__dict__:
        _LazyBitcode.parse(self)
    return _numba_get_module_for_linking(self)


_numba_unserialize = codegen.CPUCodeLibrary._unserialize
_numba_get_module_for_linking = codegen.CPUCodeLibrary._get_module_for_linking


class LazyFunctionCache:
    """numba's ``FunctionCache`` of a package function, made when the dispatcher first uses
    it (a cache load, save or query) instead of when the function is defined: making it
    finds the locator, stats the source and reads nothing else, 0.1 ms per function and
    300 functions in an import of the solver (start-up)."""
    __slots__ = ("_py_func", "_real")

    def __init__(self, py_func):
        self._py_func = py_func
        self._real = None

    def __getattr__(self, name):
        if self._real is None:
            self._real = caching.FunctionCache(self._py_func)
        return getattr(self._real, name)


_numba_enable_caching = dispatcher.Dispatcher.enable_caching


def enable_caching(self):
    """``Dispatcher.enable_caching`` with a :class:`LazyFunctionCache` for the package's functions."""
    if getattr(self.py_func, "__module__", "").startswith(__package__ + "."):
        self._cache = LazyFunctionCache(self.py_func)
    else:
        _numba_enable_caching(self)


_numba_load_index = caching.IndexDataCacheFile._load_index


def load_index(self):
    """numba's ``IndexDataCacheFile._load_index``, an index that does not unpickle taken as empty.

    numba unpickles a cache index before it compares the index's source stamp, and the index
    names the argument types by their classes: an index written by other sources of the package
    (a namedtuple since removed, such as ``PartitionedMethod``) raised at every load of its
    function where the index's path stays the same between versions (``NUMBA_CACHE_DIR``, the
    ``__pycache__`` fallback), until the cache was deleted by hand.  Stale either way, so empty:
    the function compiles and its next save writes a fresh index."""
    try:
        return _numba_load_index(self)
    except (AttributeError, ImportError, EOFError, pickle.UnpicklingError):
        return {}


def install():
    """Put the package's locators in front of numba's (idempotent): NUMBA_CACHE_DIR if set,
    else the cache every copy of the package shares (:func:`shared_cache_dir`), else
    ``__pycache__``, else numba's user-wide cache; an unreadable index is an empty one (:func:`load_index`)."""
    classes = caching.CacheImpl._locator_classes
    for cls in LOCATORS:
        if cls in classes:
            classes.remove(cls)
    classes[0:0] = list(LOCATORS)
    caching.Cache.load_overload = load_overload
    caching.IndexDataCacheFile._load_index = load_index
    dispatcher.Dispatcher.enable_caching = enable_caching
    if not getattr(codegen.CPUCodeLibrary._unserialize, "_exudyn_lie", False):
        def _unserialize(cls, codegen_, state):
            return _LazyBitcode.unserialize(cls, codegen_, state)
        _unserialize._exudyn_lie = True
        codegen.CPUCodeLibrary._unserialize = classmethod(_unserialize)
        codegen.CPUCodeLibrary._get_module_for_linking = _get_module_for_linking
        codegen.JitEngine.is_symbol_defined = _is_symbol_defined


install()
from . import _noinline  # noqa: E402,F401  (LLVM noinline on the group maps, before any compile)
from . import _inline_overloads  # noqa: E402,F401  (inlined overloads compiled once, before any compile)

"""Packaging and layering: what ``import exudyn_lie`` loads, and no import cycles.

The layers are the solver library (``groups``, ``integrators``, ``mbs``, ``bridge``),
the paper's models (``exudyn_lie.models``, the repository's ``models/`` folder) and the
applications (``exudyn_lie.apps``: paper, bench, stress); an import from a lower layer
into a higher one would make a cycle."""
import ast
import re
import os
import subprocess
import sys

import exudyn_lie

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PKG = os.path.dirname(os.path.abspath(exudyn_lie.__file__))


def _run(code):
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout


def test_import_exudyn_lie_loads_neither_matplotlib_nor_the_applications():
    out = _run("import sys, exudyn_lie; exudyn_lie.Scene; "
               "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib' "
               "or m.startswith(('exudyn_lie.apps', 'exudyn_lie.models'))))")
    assert out.strip() == "[]", out


def test_solve_dynamic_loads_no_matplotlib():
    out = _run("import sys, exudyn_lie as exl; exl.SolveDynamic; exl.BridgeError; "
               "print('matplotlib' in sys.modules)")
    assert out.strip() == "False", out


def test_models_import_as_a_subpackage_of_exudyn_lie():
    import exudyn_lie.models as models
    assert models.__name__ == "exudyn_lie.models"
    assert os.path.realpath(os.path.dirname(models.__file__)) == os.path.realpath(os.path.join(ROOT, "models"))
    assert "heavy_top" in models.MODELS


def _module_name(path):
    rel = os.path.relpath(os.path.realpath(path), os.path.realpath(os.path.join(PKG, "..")))
    if rel.startswith("models" + os.sep):          # the repository's models/ is exudyn_lie.models
        rel = os.path.join("exudyn_lie", rel)
    parts = rel[:-3].split(os.sep)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts), parts[-1] == "__init__"


def _sources():
    seen = set()
    for base in (PKG, os.path.join(ROOT, "models")):
        for d, dirs, files in os.walk(base):
            dirs[:] = [x for x in dirs if x != "__pycache__" and not os.path.islink(os.path.join(d, x))]
            for f in files:
                if f.endswith(".py") and os.path.realpath(os.path.join(d, f)) not in seen:
                    seen.add(os.path.realpath(os.path.join(d, f)))
                    yield os.path.join(d, f)


def _imports(path):
    """Every module ``path`` imports (also inside functions), as absolute names."""
    name, is_pkg = _module_name(path)
    package = name if is_pkg else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(open(path, encoding="utf-8").read())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
    return name, out


def _unit(mod):
    """The layer unit of a module: exudyn_lie.<subpackage> (or the package itself)."""
    parts = mod.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 else parts[0]


def test_no_import_cycles_between_subpackages():
    units = {"exudyn_lie.groups", "exudyn_lie.integrators", "exudyn_lie.mbs", "exudyn_lie.bridge",
             "exudyn_lie.models", "exudyn_lie.apps"}
    edges = {u: set() for u in units}
    for path in _sources():
        name, imports = _imports(path)
        src = _unit(name)
        if src not in units:
            continue
        for mod in imports:
            dst = _unit(mod)
            if dst in units and dst != src:
                edges[src].add(dst)
    # depth-first search for a cycle
    state, stack = {}, []

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in sorted(edges[u]):
            if state.get(v) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(v):] + [v]))
            if v not in state:
                visit(v)
        stack.pop()
        state[u] = 2

    for u in sorted(units):
        if u not in state:
            visit(u)
    assert "exudyn_lie.apps" not in set().union(*(edges[u] for u in units - {"exudyn_lie.apps"}))
    assert "exudyn_lie.models" not in set().union(*(edges[u] for u in units - {"exudyn_lie.apps",
                                                                                 "exudyn_lie.models"}))


def test_no_top_level_models_import():
    """Everything imports the paper's models as exudyn_lie.models (the top-level name
    ``models`` is not installed)."""
    bad = []
    for path in list(_sources()) + [os.path.join(ROOT, "tests", f) for f in os.listdir(os.path.join(ROOT, "tests"))
                                    if f.endswith(".py")]:
        for node in ast.walk(ast.parse(open(path, encoding="utf-8").read())):
            if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "models" for a in node.names):
                bad.append(path)
            if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "models":
                bad.append(path)
    assert not bad, bad


def test_library_modules_and_functions_stay_small():
    """One job per module: no library file above 600 lines and no function above 100
    (the applications in exudyn_lie/apps and the paper's models aside)."""
    long_files, long_functions = [], []
    for d, dirs, files in os.walk(PKG):
        dirs[:] = [x for x in dirs if x not in ("__pycache__", "apps", "models")
                   and not os.path.islink(os.path.join(d, x))]
        for f in files:
            if not f.endswith(".py"):
                continue
            path = os.path.join(d, f)
            src = open(path, encoding="utf-8").read()
            rel = os.path.relpath(path, PKG)
            if len(src.splitlines()) > 600:
                long_files.append((rel, len(src.splitlines())))
            for node in ast.walk(ast.parse(src)):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    n = node.end_lineno - node.lineno + 1
                    if n > 100:
                        long_functions.append((rel, node.name, n))
    assert not long_files and not long_functions, (long_files, long_functions)


# Exudyn's item and node type names, its functions and the word itself (the package's own name
# exudyn_lie aside); LoadRow is the simulator's own method
EXUDYN_WORDS = (r"(?<![\w.])[Ee]xudyn(?!_lie)|RotVecLG|Rxyz|PostNewton|\bEP\b|\bC?(Object|Node|Marker|Sensor)[A-Z0-9]\w*"
                r"|\bLoad(?!Row\b)[A-Z]\w*")


def test_the_kernel_names_nothing_of_exudyn():
    """mbs/ is the kernel: it describes its models in its own terms; what an Exudyn item is
    and how it maps onto the kernel is the bridge's (bridge/reader*.py, bridge/nodes.py)."""

    found = []
    mbs = os.path.join(PKG, "mbs")
    for name in sorted(os.listdir(mbs)):
        if name.endswith(".py"):
            for i, line in enumerate(open(os.path.join(mbs, name), encoding="utf-8"), 1):
                m = re.search(EXUDYN_WORDS, line)
                if m:
                    found.append(f"mbs/{name}:{i}: {m.group(0)!r} in {line.strip()[:100]}")
    assert not found, "\n".join(found)

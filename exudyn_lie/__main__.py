"""Command line: ``python -m exudyn_lie {paper,bench,stress,corpus,items,warmup} [options]``.

* ``paper``  - reproduce the paper's comparison (SE3 vs SO3xR3 constraint satisfaction);
* ``bench``  - work-precision and per-step benchmarks against Exudyn's native solvers;
* ``stress`` - numerical stability stress suite;
* ``corpus`` - run Exudyn scripts natively and through ``exudyn_lie.SolveDynamic``, unedited;
* ``items``  - the Exudyn item types the bridge reads (from their registrations);
* ``warmup`` - compile the solver for the kinds of model real scripts need, with progress.

``--version`` prints the versions of exudyn_lie, exudyn, numpy and numba.

Each command lives in its own module (``exudyn_lie.apps.paper``, ``.bench``, ``.stress``, ``.corpus``, ``.items``)
with a ``main(argv)`` function; ``--help`` after a command lists its options.
"""
import importlib
import sys

COMMANDS = {
    "paper": ("exudyn_lie.apps.paper", "reproduce the paper's comparison, write REPRODUCTION.md and figures"),
    "bench": ("exudyn_lie.apps.bench", "work-precision / per-step benchmarks, write BENCHMARKS.md"),
    "stress": ("exudyn_lie.apps.stress", "numerical stability stress suite, write STRESS.md"),
    "items": ("exudyn_lie.apps.items", "list the Exudyn item types the bridge reads (--readme: the README block)"),
    "warmup": ("exudyn_lie.apps.warmup", "compile the solver for the kinds of model real scripts need, with "
                                         "progress (once per machine)"),
    "corpus": ("exudyn_lie.apps.corpus", "run Exudyn scripts natively and through exudyn_lie.SolveDynamic, "
                                         "write corpus.md"),
}


def usage():
    lines = ["usage: python -m exudyn_lie COMMAND [options]   (or: exudyn_lie COMMAND [options])", "",
             "commands:"]
    lines += [f"  {name:8s} {text}" for name, (_, text) in COMMANDS.items()]
    lines += ["", "options:", "  -h, --help     show this help", "  --version      print the versions of exudyn_lie,",
              "                 exudyn, numpy and numba", "",
              "Run 'python -m exudyn_lie COMMAND --help' for the options of a command."]
    return "\n".join(lines)


def version_text():
    from .apps import versions
    return ", ".join(f"{name} {v}" for name, v in versions().items())


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        return 0
    if argv[0] in ("-V", "--version"):
        print(version_text())
        return 0
    cmd = argv[0]
    if cmd not in COMMANDS:
        print(f"unknown command {cmd!r}\n\n{usage()}", file=sys.stderr)
        return 2
    module = importlib.import_module(COMMANDS[cmd][0])
    return module.main(argv[1:]) or 0


if __name__ == "__main__":
    sys.exit(main())

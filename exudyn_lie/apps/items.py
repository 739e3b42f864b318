"""``python -m exudyn_lie items [--readme docs/USING.md]``: the list of the Exudyn item types the
bridge reads, generated from their registrations (:mod:`exudyn_lie.bridge.items`).

Without options it prints the table; ``--readme PATH`` writes it as the generated block
``items`` of PATH (``tests/test_readme_items.py`` checks that docs/USING.md's block equals the
registrations)."""
from __future__ import annotations

import argparse

from .generated import update_file_block

COMMAND = "python -m exudyn_lie items --readme docs/USING.md"
BLOCK = "items"


def body():
    """The block's text: one table row per registered item type."""
    from ..bridge import items
    return "\n".join(items.readme_lines()) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m exudyn_lie items", description=__doc__.split("\n\n")[0])
    ap.add_argument("--readme", metavar="PATH", help="write the list as the generated block 'items' of PATH")
    args = ap.parse_args(argv)
    if args.readme:
        update_file_block(args.readme, BLOCK, COMMAND, body())
        print(f"wrote the '{BLOCK}' block of {args.readme}")
    else:
        print(body(), end="")
    return 0

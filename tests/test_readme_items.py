"""The README names every item type the bridge reads (its lists come from the registrations
in bridge/reader.py: SUPPORTED_NODES / SUPPORTED_OBJECTS / SUPPORTED_MARKERS / SUPPORTED_LOADS)."""
import os

from exudyn_lie.bridge import reader

README = os.path.join(os.path.dirname(__file__), "..", "README.md")


def _variants(name):
    """The forms the README uses: full name, or without the Object / ObjectConnector prefix."""
    name = name.split(" ")[0]
    out = {name}
    for prefix in ("ObjectConnector", "Object"):
        if name.startswith(prefix):
            out.add(name[len(prefix):])
    return out


def test_readme_names_every_supported_item():
    text = open(README, encoding="utf-8").read()
    names = reader.SUPPORTED_NODES + reader.SUPPORTED_OBJECTS + reader.SUPPORTED_MARKERS + reader.SUPPORTED_LOADS
    missing = [n for n in names if not any(f"`{v}`" in text for v in _variants(n))]
    assert not missing, f"README does not name {missing}"

"""The README's list of supported Exudyn items is generated from the one registration per
item type (bridge/items.py), and the reader, the parameter watch and the path choice use the
same registrations."""
import os

from exudyn_lie.apps import items as items_cmd
from exudyn_lie.apps.generated import read_block
from exudyn_lie.bridge import evaluated_dispatch, items, nodes, params, reader

README = os.path.join(os.path.dirname(__file__), "..", "docs", "USING.md")


def _readme():
    with open(README, encoding="utf-8") as f:
        return f.read()


def test_readme_items_block_equals_the_registrations():
    """Both ways: every registered type has its row, and no row is left of a removed one."""
    block = read_block(_readme(), items_cmd.BLOCK)
    assert block is not None, f"README.md has no '{items_cmd.BLOCK}' block: run `{items_cmd.COMMAND}`"
    cmd, ok, body = block
    assert cmd == items_cmd.COMMAND
    assert ok, "the README's items block was edited by hand (hash mismatch): regenerate it"
    assert body == items_cmd.body(), f"the README's items block is stale: run `{items_cmd.COMMAND}`"
    rows = [line.split("|")[1].strip().strip("`") for line in body.splitlines()[2:]]
    assert rows == [it.name for it in items.ITEMS.values()]


def _variants(name):
    """The forms the README's prose uses: full name, or without the Object / ObjectConnector prefix."""
    out = {name}
    for prefix in ("ObjectConnector", "Object"):
        if name.startswith(prefix):
            out.add(name[len(prefix):])
    return out


def test_readme_prose_names_every_supported_item():
    text = _readme().split("<!-- END items -->", 1)[1]
    missing = [it.name for it in items.ITEMS.values() if not any(f"`{v}`" in text for v in _variants(it.name))]
    assert not missing, f"README's description does not name {missing}"


def test_lists_derive_from_the_registrations():
    names = set(reader.SUPPORTED_OBJECTS) | set(reader.SUPPORTED_MARKERS) | set(reader.SUPPORTED_LOADS) | {
        n.split(" ")[0] for n in reader.SUPPORTED_NODES}
    assert names == {it.name for it in items.ITEMS.values()}
    assert set(params.FIELDS) == set(items.ITEMS)
    assert set(nodes.NODE_KINDS) == {it.typeName for it in items.of("node", "body")}
    for t in reader.JOINT_READERS.values():
        assert callable(getattr(reader._Reader, t))
    for t, (method, _) in reader.CONNECTOR_READERS.items():
        assert callable(getattr(reader._Reader, method)), t
    for it in items.ITEMS.values():
        if it.userFunction:
            assert it.userFunction in it.fields, (it.name, it.userFunction)


def test_an_unregistered_type_takes_the_evaluated_path():
    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2   # types with no registration
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.0],
                                        initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=[[1.0]]))
    mbs.Assemble()
    assert ("node", "GenericODE2") not in items.ITEMS
    assert evaluated_dispatch.foreign_items(mbs) == ["NodeGenericODE2 (node 0)", "ObjectGenericODE2 (object 0)"]

"""The type stub names what the compiled module has, so editors autocomplete the real API."""

import ast
import pathlib

import pyrograph
from pyrograph import _native

STUB = pathlib.Path(pyrograph.__file__).with_name("_native.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, classes = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    members.add(item.target.id)
            classes[node.name] = members
            top.add(node.name)
        elif isinstance(node, (ast.FunctionDef, ast.AnnAssign, ast.Assign)):
            names = [node.name] if isinstance(node, ast.FunctionDef) else [t.id for t in getattr(node, "targets", [getattr(node, "target", None)]) if isinstance(t, ast.Name)]
            top.update(names)
    return top, classes


def test_every_public_name_is_in_the_stub():
    top, classes = stub_names()
    runtime = {n for n in dir(_native) if not n.startswith("_") or n == "__version__"}
    assert runtime <= top, runtime - top
    for name, members in classes.items():
        cls = getattr(_native, name)
        public = {m for m in vars(cls) if not m.startswith("_")}
        if name == "GraphError":
            public = {"node", "port", "message"}
        assert public <= members | {"description"}, (name, public - members)
        assert members - {"__init__", "__len__", "__getitem__"} <= public | {"node", "port", "message"}, (name, members - public)

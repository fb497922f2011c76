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


def stub_signatures():
    """Parameter names per function and method of the stub: {"describe": [...], "Graph.cook": [...]}."""
    out = {}
    tree = ast.parse(STUB.read_text())
    for node in tree.body:
        items = [(node.name + ".", item) for item in node.body] if isinstance(node, ast.ClassDef) else [("", node)]
        for prefix, item in items:
            if isinstance(item, ast.FunctionDef) and not any(isinstance(d, ast.Name) and d.id == "property" for d in item.decorator_list):
                if any(isinstance(d, ast.Attribute) for d in item.decorator_list):
                    continue  # property setters
                args = [a.arg for a in item.args.args + item.args.kwonlyargs]
                out[prefix + item.name] = [a for a in args if a not in ("self", "cls")]
    return out


def test_stub_parameters_match_the_module():
    import inspect

    checked = 0
    for name, params in stub_signatures().items():
        if name.endswith("__init__") or name.split(".")[-1].startswith("__"):
            continue
        owner, _, attr = name.rpartition(".")
        obj = getattr(getattr(_native, owner) if owner else _native, attr)
        real = [p.name for p in inspect.signature(obj).parameters.values() if p.name not in ("self", "cls") and p.kind is not p.VAR_KEYWORD]
        stub = [p for p in params if p != "params"]
        assert real == stub, (name, real, stub)
        checked += 1
    assert checked >= 15

"""Hostile values from Python: every public function given wrong types, NaN, huge integers,
self-containing or deeply nested containers and huge strings raises an ordinary Python exception
at the call (TypeError, ValueError, OverflowError, GraphError, OSError...), never a Rust panic
(pyo3's PanicException, which is not an Exception) or a crash; and the limits Python sets confine
reads as the CLI's flags do."""

import math
import pathlib

import pytest

import pyrograph


def self_list():
    a = []
    a.append(a)
    return a


def self_dict():
    d = {}
    d["x"] = d
    return d


def deep(n):
    x = []
    for _ in range(n):
        x = [x]
    return x


class Hostile:
    """Raises from every dunder a converter might call."""

    def __float__(self):
        raise ZeroDivisionError("hostile __float__")

    def __index__(self):
        raise ZeroDivisionError("hostile __index__")

    def __fspath__(self):
        raise ZeroDivisionError("hostile __fspath__")

    def __iter__(self):
        raise ZeroDivisionError("hostile __iter__")


VALUES = [
    None,
    object(),
    1j,
    b"\xff\xfe",
    {"a": 1},
    {1, 2},
    math.nan,
    math.inf,
    -math.inf,
    2**64,
    -(2**1000),
    self_list(),
    self_dict(),
    deep(100_000),
    "x" * 2_000_000,
    "\x00\ud800",
    "keys([(0, nan)])",
    "expr(\"" + "(" * 50_000 + "\")",
    Hostile(),
    (math.nan, math.nan, math.nan),
    [1.0] * 100_000,
]


def calls(g, clip, v):
    """Every public entry point, with `v` in each argument position that takes a value."""
    return [
        lambda: pyrograph.Graph(v),
        lambda: pyrograph.Graph.load(v),
        lambda: pyrograph.Graph.from_ron(v),
        lambda: pyrograph.Graph.from_ron("(version: 4, nodes: {})", base_dir=v),
        lambda: g.save(v),
        lambda: g.check(out=v),
        lambda: g.check(allow_outside_out=v),
        lambda: g.add_node(v, "math.add"),
        lambda: g.add_node("new", v),
        lambda: g.add_node("new2", "math.add", b=v),
        lambda: g.set("add.b", v),
        lambda: g.set(v, 1.0),
        lambda: g.set_keys("add.b", v),
        lambda: g.set_keys("add.b", [(0, v), (10, 1.0)]),
        lambda: g.set_keys("add.b", [(v, 1.0)]),
        lambda: g.set_keys("add.b", [(0, 1.0, v)]),
        lambda: g.set_keys("add.b", [(0, 0.0), (5, 1.0)], extrapolation=v),
        lambda: g.set_expr("add.b", v),
        lambda: g.set_expr(v, "frame"),
        lambda: g.get(v),
        lambda: g.connect(v, "add.a"),
        lambda: g.connect("add.value", v),
        lambda: g.disconnect(v, v),
        lambda: g.remove_node(v),
        lambda: g.cook(v),
        lambda: g.cook("add.value", frames=v),
        lambda: g.cook("flame.clip", frames=v),
        lambda: g.cook("add.value", progress=v),
        lambda: g.render(out=v),
        lambda: g.render(frames=v),
        lambda: g.render(nodes=v),
        lambda: setattr(g, "description", v),
        lambda: clip[v],
        lambda: clip.frames(v),
        lambda: pyrograph.describe(v),
        lambda: pyrograph.set_limits(read_roots=v),
        lambda: pyrograph.set_limits(max_nodes=v),
        lambda: pyrograph.set_limits(max_pixels=v),
        lambda: pyrograph.set_limits(max_voxels=v),
    ]


def fresh():
    g = pyrograph.Graph()
    g.add_node("add", "math.add", a=1.0, b=2.0)
    g.add_node("flame", "imaging.turbulence_flame", width=16, height=16, frames=3)
    return g


def test_every_call_given_hostile_values_raises_a_python_exception_or_returns(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    outcomes = {}
    for i, v in enumerate(VALUES):
        g = fresh()
        clip = g.cook("flame.clip")
        for j, call in enumerate(calls(g, clip, v)):
            try:
                call()
                outcome = "returned"
            except Exception as e:  # noqa: BLE001 - any ordinary exception is the contract
                outcome = type(e).__name__
                assert "panicked" not in str(e) and "PanicException" not in outcome, (i, j, e)
            except BaseException as e:  # PanicException derives from BaseException
                pytest.fail(f"value {i} ({type(v).__name__}), call {j}: {type(e).__name__}: {e}")
            finally:
                pyrograph.set_limits(read_roots=[], max_nodes=0, max_pixels=0, max_voxels=0)
            outcomes[(i, j)] = outcome
        # Whatever was tried, the graph still cooks, or says clearly why not.
        try:
            g.cook("add.value")
        except pyrograph.GraphError:
            pass
    raised = [o for o in outcomes.values() if o != "returned"]
    assert len(raised) > len(outcomes) // 2, "most hostile values are refused"
    assert {"TypeError", "GraphError", "ValueError"} <= set(raised), set(raised)


def test_nan_and_infinite_parameters_are_refused_or_cook_without_a_panic():
    for bad in [math.nan, math.inf, -math.inf]:
        g = fresh()
        for endpoint in ["add.b", "flame.turbulence", "flame.fps", "flame.base_width"]:
            try:
                g.set(endpoint, bad)
                g.cook(endpoint.split(".")[0] + (".value" if endpoint.startswith("add") else ".clip"), frames=[0])
            except (pyrograph.GraphError, ValueError, TypeError) as e:
                assert endpoint.split(".")[1] in str(e) or "nan" in str(e).lower() or "inf" in str(e).lower(), e
            g = fresh()


def test_huge_integers_are_an_overflow_error_naming_nothing_internal():
    g = fresh()
    with pytest.raises((OverflowError, ValueError, TypeError)):
        g.set("flame.width", 2**80)
    g.set("flame.width", 2**40)
    with pytest.raises(pyrograph.GraphError, match="width"):
        g.cook("flame.clip", frames=[0])


def test_set_limits_confines_reads_like_the_cli(tmp_path):
    root, secret = tmp_path / "root", tmp_path / "secret"
    root.mkdir()
    secret.mkdir()
    (secret / "passwd").write_text("hunter2-top-secret\n")
    g = pyrograph.Graph.from_ron(
        '(version: 4, nodes: {"inc": (type: "graph.include", params: {"path": "../secret/passwd"})})',
        base_dir=root,
    )
    try:
        pyrograph.set_limits(read_roots=[root], max_nodes=5)
        assert pyrograph.limits()["read_roots"] == [str(root.resolve())]
        assert pyrograph.limits()["max_nodes"] == 5
        problems = g.check()
        assert len(problems) == 1 and "outside the folders pyrograph may read" in problems[0].message, problems
        assert "hunter2" not in problems[0].message
        with pytest.raises(ValueError, match="not a folder"):
            pyrograph.set_limits(read_roots=[secret / "passwd"])
    finally:
        pyrograph.set_limits(read_roots=[], max_nodes=0)
    assert pyrograph.limits()["read_roots"] == [] and pyrograph.limits()["max_nodes"] == 1_000_000
    problems = g.check()
    assert len(problems) == 1 and "is not a graph file" in problems[0].message and "hunter2" not in problems[0].message
    assert pathlib.Path(secret / "passwd").read_text() == "hunter2-top-secret\n"


def test_control_characters_in_ids_and_values_are_escaped_in_messages(tmp_path):
    raw = {"\x00", "\x07", "\r", "\x1b"}
    bad = tmp_path / "bad.ron"
    bad.write_text('(version: 3, nodes: {"a\\u{1b}]0;PWNED\\u{7}b\\r\\u{0}": (type: "imaging.no_such\\u{1b}[2J")}, edges: [])')
    graph = pyrograph.Graph.load(str(bad))
    problems = graph.check()
    assert problems, "an unknown node type is a problem"
    for p in problems:
        assert not raw & (set(str(p)) | set(p.location)), repr(p)
    text = " ".join(p.location + " " + str(p) for p in problems)
    assert "a\\u{1b}]0;PWNED\\u{7}b\\u{d}\\u{0}" in text and "imaging.no_such\\u{1b}[2J" in text, text
    with pytest.raises(pyrograph.GraphError) as e:
        graph.cook("a\x1b]0;PWNED\x07b\r\x00")
    text = str(e.value)
    assert not raw & set(text), repr(text)
    assert e.value.message == text
    # A cook error echoing a hostile path.
    g = tmp_path / "g.ron"
    g.write_text('(version: 3, nodes: {"load\\u{1b}": (type: "imaging.load_image", params: {"path": "x\\u{1b}[2J.png"})}, edges: [])')
    graph = pyrograph.Graph.load(str(g))
    with pytest.raises(pyrograph.GraphError) as e:
        graph.cook("load\x1b.image")
    text = str(e.value)
    assert not raw & set(text), repr(text)
    assert "x\\u{1b}[2J.png" in text and "load\\u{1b}" in text, text
    assert e.value.node == "load\x1b", "the attribute keeps the exact id"
    # A 100 kB id is cut.
    long = tmp_path / "long.ron"
    long.write_text('(version: 3, nodes: {"%s": (type: "nope")}, edges: [])' % ("x" * 100_000))
    problems = pyrograph.Graph.load(str(long)).check()
    assert problems and all(len(str(p)) + len(p.location) < 2_000 for p in problems)
    assert any("more characters]" in p.location + str(p) for p in problems), problems

"""Documents: load, check, save and build graphs from Python, against the CLI's own output."""

import pathlib
import subprocess

import pytest

import pyrograph

ROOT = pathlib.Path(__file__).resolve().parents[3]
GRAPHS = sorted(ROOT.glob("graphs/*.ron")) + sorted(ROOT.glob("graphs/presets/*.ron"))


def test_there_are_graphs_to_test():
    assert len(GRAPHS) >= 10


@pytest.mark.parametrize("path", GRAPHS, ids=lambda p: p.name)
def test_save_is_byte_identical_to_the_cli(path, cli, tmp_path):
    g = pyrograph.Graph.load(path)
    ours = tmp_path / "python.ron"
    g.save(ours)
    theirs = tmp_path / "cli.ron"
    subprocess.run([cli, "save", path, "-o", theirs], check=True, capture_output=True)
    assert ours.read_bytes() == theirs.read_bytes()
    # And what was saved loads back to the same document.
    assert pyrograph.Graph.load(ours) == g


@pytest.mark.parametrize("path", GRAPHS, ids=lambda p: p.name)
def test_check_agrees_with_the_cli(path, cli):
    problems = pyrograph.Graph.load(path).check()
    run = subprocess.run([cli, "check", path], capture_output=True, text=True)
    assert (run.returncode == 0) == (problems == []), (run.stderr, problems)


def test_set_then_save_matches_cli_set(cli, tmp_path):
    path = ROOT / "graphs" / "flame-cards.ron"
    g = pyrograph.Graph.load(path)
    g.set("calm.turbulence", 0.8)
    g.set("wild.background", (0.1, 0.0, 0.0, 1.0))
    g.save(tmp_path / "python.ron")
    subprocess.run(
        [cli, "save", path, "-o", tmp_path / "cli.ron", "--set", "calm.turbulence=0.8", "--set", "wild.background=(0.1, 0.0, 0.0, 1.0)"],
        check=True,
        capture_output=True,
    )
    assert (tmp_path / "python.ron").read_bytes() == (tmp_path / "cli.ron").read_bytes()


def test_save_refuses_to_overwrite_unless_asked(tmp_path):
    g = pyrograph.Graph.load(ROOT / "graphs" / "flame-cards.ron")
    target = tmp_path / "mine.ron"
    target.write_text("precious")
    with pytest.raises(FileExistsError):
        g.save(target)
    assert target.read_text() == "precious"
    g.save(target, overwrite=True)
    assert pyrograph.Graph.load(target) == g


FLAME_CARD = (ROOT / "graphs" / "presets" / "flame-card.ron").read_text()


def test_building_in_python_equals_loading_the_ron():
    g = pyrograph.Graph(description="Procedural flame over a solid background, resized: a quick stand-in flame card.")
    g.add_node("flame", "imaging.turbulence_flame", width=128, height=192, frames=24, seed=1)
    g.add_node("background", "imaging.constant_color", width=128, height=192, color=(0.0, 0.0, 0.0, 1.0))
    g.add_node("over", "imaging.composite", mode="over")
    g.add_node("size", "imaging.resize", width=64)
    g.connect("background.image", "over.a")
    g.connect("flame.clip", "over.b")
    g.connect("over.image", "size.image")
    loaded = pyrograph.Graph.from_ron(FLAME_CARD)
    loaded_without_interface = pyrograph.Graph.from_ron(FLAME_CARD.split("interface:")[0] + "nodes:" + FLAME_CARD.split("nodes:")[1])
    assert loaded.interface is not None and g.interface is None
    assert g == loaded_without_interface
    assert g.to_ron() == loaded_without_interface.to_ron()
    assert g.nodes == loaded.nodes and g.edges == loaded.edges
    # One changed parameter makes them differ.
    g.set("size.width", 65)
    assert g != loaded_without_interface


def test_nodes_lists_the_registry(cli):
    import json

    listed = pyrograph.nodes()
    from_cli = json.loads(subprocess.run([cli, "nodes", "--json"], check=True, capture_output=True, text=True).stdout)
    assert listed == from_cli
    blur = next(n for n in listed if n["type"] == "imaging.resize")
    assert blur["doc"] and {"name", "type", "default", "range", "options", "doc"} <= set(blur["inputs"][0])


def test_edits_are_validated():
    g = pyrograph.Graph()
    g.add_node("a", "imaging.constant_color")
    with pytest.raises(pyrograph.GraphError) as e:
        g.add_node("b", "imaging.constant_colour")
    assert e.value.node == "b" and "imaging.constant_color" in e.value.message
    with pytest.raises(pyrograph.GraphError) as e:
        g.set("a.colour", (1, 0, 0, 1))
    assert (e.value.node, e.value.port) == ("a", "colour")
    with pytest.raises(pyrograph.GraphError):
        g.add_node("a", "imaging.resize")
    with pytest.raises(pyrograph.GraphError):
        g.connect("a.image", "nowhere.image")
    with pytest.raises(TypeError):
        g.set("a.width", object())
    listed = next(n for n in pyrograph.nodes() if n["type"] == "imaging.constant_color")
    default = next(p["default"] for p in listed["inputs"] if p["name"] == "width")
    assert str(g.get("a.width")) == default
    g.set("a.width", 32)
    assert g.get("a.width") == 32
    g.add_node("r", "imaging.resize")
    g.connect("a.image", "r.image")
    g.remove_node("a")
    assert g.edges == [] and list(g.nodes) == ["r"]


def test_check_reports_problems_as_objects(tmp_path):
    g = pyrograph.Graph.from_ron(
        '(version: 1, nodes: {"load": (type: "imaging.load_image", params: {"path": "missing.png"})}, edges: [])',
        base_dir=tmp_path,
    )
    problems = g.check()
    assert len(problems) == 1
    p = problems[0]
    assert p.kind == "Cook" and p.node == "load" and "missing.png" in p.message
    # The repr writes Python values, never Rust's Some("load") and None.
    r = repr(p)
    assert r.startswith("Problem(kind='Cook', node='load', port=") and "Some(" not in r, r
    assert eval(r.replace("Problem(", "dict(")) == {"kind": p.kind, "node": p.node, "port": p.port, "message": p.message}


def test_describe_is_the_node_reference_section(root):
    text = pyrograph.describe("imaging.bloom")
    reference = (root / "docs" / "nodes.md").read_text()
    assert text.startswith("### `imaging.bloom`") and "§6.2" in text
    assert text in reference
    with pytest.raises(pyrograph.GraphError, match="did you mean 'imaging.bloom'"):
        pyrograph.describe("imaging.blom")


def saved_like_the_cli(g, cli, path, tmp_path, *sets):
    """Saves `g`, and `path` through `pyrograph save --set` for each of `sets`; asserts the two
    files are byte-identical and returns the text."""
    g.save(tmp_path / "python.ron")
    args = [arg for s in sets for arg in ("--set", s)]
    subprocess.run([cli, "save", path, "-o", tmp_path / "cli.ron", *args], check=True, capture_output=True)
    saved = (tmp_path / "python.ron").read_text()
    assert saved == (tmp_path / "cli.ron").read_text()
    return saved


def test_keys_and_expressions_set_from_python_save_like_the_cli(cli, tmp_path):
    path = ROOT / "graphs" / "flame-cards.ron"
    g = pyrograph.Graph.load(path)
    g.set_keys("calm.turbulence", [(0, 0.3), (11, 1.5, "ease")], extrapolation="cycle")
    g.set_expr("wild.turbulence", "2 + sin(time * 3)")
    saved = saved_like_the_cli(
        g, cli, path, tmp_path,
        "calm.turbulence=keys([(0, 0.3), (11, 1.5, ease)], cycle)",
        "wild.turbulence=expr(2 + sin(time * 3))",
    )
    assert "version: 4," in saved and "keys([(0, 0.3), (11, 1.5, ease)], cycle)" in saved, saved
    # What get() returns sets the same value again.
    written = g.get("calm.turbulence")
    assert written.startswith("keys(") and "ease" in written, written
    again = pyrograph.Graph.load(path)
    again.set("calm.turbulence", written)
    again.set("wild.turbulence", g.get("wild.turbulence"))
    assert again == g


def test_a_bad_expression_is_a_problem_naming_node_parameter_and_column():
    g = pyrograph.Graph.load(ROOT / "graphs" / "flame-cards.ron")
    g.set_expr("calm.turbulence", "1 +* 2")
    problems = g.check()
    assert any("calm" in str(p) and "turbulence" in str(p) and "column 4" in str(p) for p in problems), problems


def test_ignition_points_set_from_python_save_like_the_cli(cli, tmp_path):
    path = ROOT / "graphs" / "burning-cube.ron"
    g = pyrograph.Graph.load(path)
    g.set("spread.ignite", [(0.5, 0.2, -0.15), (1.5, "face(3, (0.2, 0.3, 0.5))"), "face(1)"])
    assert g.check() == [], g.check()
    saved = saved_like_the_cli(
        g, cli, path, tmp_path, "spread.ignite=[(0.5, 0.2, -0.15), (1.5, face(3, (0.2, 0.3, 0.5))), face(1)]"
    )
    assert "face(3, (0.2, 0.3, 0.5))" in saved and "face(1)" in saved, saved
    # A point that is not a place is a problem naming the parameter and the point.
    g.set("spread.ignite", [(0.5, 0.2, -0.15), (1.5, (0.2, 0.3))])
    problems = g.check()
    assert any("ignite" in str(p) and "point 2" in str(p) for p in problems), problems

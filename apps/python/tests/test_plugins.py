"""Python plugin nodes from the `pyrograph` module: a graph whose plugins/ folder holds a plugin
cooks it in a worker, and its frames equal the plugin function called directly on the frames
that feed it; an edited plugin re-cooks only its own node; a broken plugin is a GraphError."""

import importlib.util
import pathlib
import shutil
import sys

import numpy as np
import pytest

import pyrograph

ROOT = pathlib.Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "examples" / "plugins" / "heat_haze"


@pytest.fixture
def haze(tmp_path, monkeypatch):
    """The heat-haze example copied to a temporary folder, cooked with this Python (it has numpy)."""
    monkeypatch.setenv("PYROGRAPH_PYTHON", sys.executable)
    shutil.copytree(EXAMPLE, tmp_path / "example")
    return tmp_path / "example"


def plugin_function(path):
    """The plugin file's function, imported here as plain Python (the declaration module beside it)."""
    sys.path.insert(0, str(ROOT / "crates" / "plugin" / "host"))
    try:
        spec = importlib.util.spec_from_file_location("heat_haze_direct", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module.heat_haze
    finally:
        sys.path.pop(0)


def test_a_plugin_node_cooks_what_its_function_computes(haze):
    g = pyrograph.Graph.load(haze / "heat-haze.ron")
    flames = g.cook("flame.clip", frames=range(3))
    hazed = g.cook("haze.image", frames=range(3))
    heat_haze = plugin_function(haze / "plugins" / "heat_haze.py")
    for flame, out in zip(flames, hazed):
        want = heat_haze(np.array(flame), amount=3.0, wavelength=24.0, axis="vertical")
        assert out.dtype == np.float32 and out.shape == want.shape
        assert np.array_equal(out, want)


def test_an_edited_plugin_recooks_only_its_node(haze):
    g = pyrograph.Graph.load(haze / "heat-haze.ron")
    before = g.cook("haze.image", frames=[0])[0].copy()
    plugin = haze / "plugins" / "heat_haze.py"
    plugin.write_text(plugin.read_text().replace("return amount * np.sin", "return 0.5 * amount * np.sin"))
    after = g.cook("haze.image", frames=[0])[0]
    assert not np.array_equal(before, after)
    assert "haze" in g.last_cooked and "flame" not in g.last_cooked


def test_a_broken_plugin_is_a_graph_error_naming_its_file(haze):
    (haze / "plugins" / "heat_haze.py").write_text("def broken(:\n")
    g = pyrograph.Graph.load(haze / "heat-haze.ron")
    with pytest.raises(pyrograph.GraphError) as e:
        g.cook("haze.image", frames=[0])
    assert "heat_haze.py could not be loaded: SyntaxError" in str(e.value)


def test_a_whole_clip_plugin_cooks_its_median_over_frames(monkeypatch):
    monkeypatch.setenv("PYROGRAPH_PYTHON", sys.executable)
    g = pyrograph.Graph.load(ROOT / "examples" / "plugins" / "temporal_median" / "temporal-median.ron")
    flames = g.cook("flame.clip", frames=range(5))
    median = g.cook("median.clip", frames=[2])[0]
    want = np.median(np.stack([np.array(f) for f in flames]), axis=0).astype(np.float32)
    assert np.array_equal(median, want), "frame 2 is the median of frames 0..4"


def test_points_from_a_csv_plugin_feed_the_volume_simulation(monkeypatch):
    monkeypatch.setenv("PYROGRAPH_PYTHON", sys.executable)
    g = pyrograph.Graph.load(ROOT / "examples" / "plugins" / "csv_emitter" / "csv-emitter.ron")
    early, late = g.cook("view.image", frames=[4, 30])
    # Torches light one after another: more of the picture burns late than early.
    lit = lambda frame: int((frame[..., 0] > 0.2).sum())
    assert lit(late) > 2 * lit(early) > 0

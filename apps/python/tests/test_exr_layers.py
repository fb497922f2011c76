"""Multi-layer OpenEXR files read on the other side: `imaging.write_exr_layers` files opened with
the OpenEXR package (PyPI `OpenEXR`, the Academy Software Foundation's own bindings), each layer
checked against single-layer files of the same frame written by `imaging.write_sequence`."""

import os
import subprocess

import numpy as np
import pytest

if os.environ.get("CI") == "true":
    import OpenEXR  # CI installs it: a missing package fails the run instead of skipping the test
else:
    OpenEXR = pytest.importorskip("OpenEXR", reason="pip install OpenEXR (.ci/run installs it)")

GRAPH = """(
    version: 1,
    nodes: {
        "flame": (type: "imaging.turbulence_flame", params: {"width": 48, "height": 64, "frames": 3, "seed": 7}),
        "gray": (type: "imaging.to_gray"),
        "glow": (type: "imaging.gaussian_blur", params: {"sigma": 2.0}),
        "layers": (type: "imaging.write_exr_layers", params: {
            "pattern": "layered/f_####.exr", "exr_type": "float",
            "name1": "mask", "type1": "float", "name2": "glow", "type2": "half",
        }),
        "main": (type: "imaging.write_sequence", params: {"pattern": "main/f_####.exr", "exr_type": "float", "alpha": "premultiplied"}),
        "mask": (type: "imaging.write_sequence", params: {"pattern": "mask/f_####.exr", "exr_type": "float"}),
        "glow_out": (type: "imaging.write_sequence", params: {"pattern": "glow/f_####.exr", "exr_type": "half", "alpha": "premultiplied"}),
    },
    edges: [
        ("flame.clip", "layers.main"),
        ("flame.clip", "gray.image"),
        ("gray.image", "layers.layer1"),
        ("flame.clip", "glow.image"),
        ("glow.image", "layers.layer2"),
        ("flame.clip", "main.clip"),
        ("gray.image", "mask.clip"),
        ("glow.image", "glow_out.clip"),
    ],
)
"""


def channels(path):
    """Every channel of an EXR file's parts, by name, as float32 arrays (OpenEXR's own reader)."""
    out = {}
    with OpenEXR.File(str(path), separate_channels=True) as f:
        for part in f.parts:
            for name, channel in part.channels.items():
                out[name] = np.asarray(channel.pixels, dtype=np.float32)
    return out


def test_each_layer_equals_the_single_layer_file_of_the_same_frame(cli, tmp_path):
    graph = tmp_path / "layers.ron"
    graph.write_text(GRAPH)
    out = tmp_path / "out"
    subprocess.run([cli, "render", graph, "--out", out], check=True, capture_output=True)
    files = sorted((out / "layered").iterdir())
    assert [p.name for p in files] == ["f_0000.exr", "f_0001.exr", "f_0002.exr"]
    for p in files:
        layered = channels(p)
        assert sorted(layered) == sorted(["R", "G", "B", "A", "mask.Y", "glow.R", "glow.G", "glow.B", "glow.A"])
        main, mask, glow = (channels(out / d / p.name) for d in ("main", "mask", "glow"))
        for c in "RGBA":
            assert np.array_equal(layered[c], main[c]), (p.name, c)
            assert layered[f"glow.{c}"].shape == (64, 48)
            assert np.array_equal(layered[f"glow.{c}"], glow[c]), (p.name, c)
        assert np.array_equal(layered["mask.Y"], mask["Y"]), p.name
        # The layers differ from each other: the comparisons above are not trivially true.
        assert np.abs(layered["glow.R"] - layered["R"]).max() > 0.01
        assert layered["A"].max() > 0.5 and layered["A"].min() < 0.1
    # Sample types as asked: the main layer and the mask in float, the glow in half.
    with OpenEXR.File(str(files[0]), separate_channels=True) as f:
        kinds = {name: c.pixels.dtype for name, c in f.parts[0].channels.items()}
    assert kinds["R"] == np.float32 and kinds["mask.Y"] == np.float32 and kinds["glow.R"] == np.float16


PASSES = """(
    version: 3,
    nodes: {
        "roots": (type: "particles.roots", params: {"layout": "row", "count": 2, "spacing": 1.5}),
        "flame": (type: "particles.particle_flame", params: {"frames": 2, "steps": 12}),
        "beauty": (type: "particles.render_flames", params: {"width": 64, "height": 48, "ground": true, "background": (0.02, 0.02, 0.03, 1.0)}),
        "emission": (type: "particles.render_flames", params: {"width": 64, "height": 48, "ground": true, "pass": "emission"}),
        "depth": (type: "particles.render_flames", params: {"width": 64, "height": 48, "ground": true, "pass": "depth"}),
        "layers": (type: "imaging.write_exr_layers", params: {
            "pattern": "passes/f_####.exr", "exr_type": "float",
            "name1": "emission", "type1": "float", "name2": "depth", "type2": "float",
        }),
        "e": (type: "imaging.write_sequence", params: {"pattern": "emission/f_####.exr", "exr_type": "float", "alpha": "premultiplied"}),
        "z": (type: "imaging.write_sequence", params: {"pattern": "depth/f_####.exr", "exr_type": "float"}),
    },
    edges: [
        ("roots.roots", "flame.roots"),
        ("flame.flames", "beauty.flames"),
        ("flame.flames", "emission.flames"),
        ("flame.flames", "depth.flames"),
        ("beauty.image", "layers.main"),
        ("emission.image", "layers.layer1"),
        ("depth.image", "layers.layer2"),
        ("emission.image", "e.clip"),
        ("depth.image", "z.clip"),
    ],
)
"""


def test_a_particle_renders_passes_go_into_one_file(cli, tmp_path):
    """The flame renderer's beauty, emission and depth passes as the layers of one EXR a frame."""
    graph = tmp_path / "passes.ron"
    graph.write_text(PASSES)
    out = tmp_path / "out"
    subprocess.run([cli, "render", graph, "--out", out], check=True, capture_output=True)
    for p in sorted((out / "passes").iterdir()):
        layered = channels(p)
        assert {"R", "G", "B", "A", "emission.R", "emission.A", "depth.Y"} <= set(layered)
        emission, depth = channels(out / "emission" / p.name), channels(out / "depth" / p.name)
        for c in "RGBA":
            assert np.array_equal(layered[f"emission.{c}"], emission[c]), (p.name, c)
        assert np.array_equal(layered["depth.Y"], depth["Y"]), p.name
        # The ground is in the beauty and the depth, not in the emission: the bottom row.
        assert layered["A"][-1].min() > 0.99 and layered["emission.A"][-1].max() == 0.0
        assert 0 < layered["depth.Y"][-1].max() < 1000 and layered["depth.Y"][0].min() == 1000

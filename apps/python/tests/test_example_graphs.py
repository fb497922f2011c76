"""The shipped delivery examples in graphs/, rendered by the CLI and read on the other side:
`campfire-usd.ron` opened with Pixar's usd-core, `burning-house-layers.ron` with the OpenEXR
package, and `flipbook-unity.ron`'s sheets and side-car as Unity's importer would take them."""

import json
import os
import struct
import subprocess

import numpy as np
import pytest
from PIL import Image

if os.environ.get("CI") == "true":
    import OpenEXR  # CI installs both: a missing package fails the run instead of skipping
    from pxr import Usd, UsdGeom
else:
    OpenEXR = pytest.importorskip("OpenEXR", reason="pip install OpenEXR (.ci/run installs it)")
    pytest.importorskip("pxr", reason="pip install usd-core (.ci/run installs it)")
    from pxr import Usd, UsdGeom

from test_exr_layers import channels
from test_usd import validation_errors


def render(cli, root, graph, out, *args):
    run = subprocess.run([cli, "render", root / "graphs" / graph, "--out", out, *args], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return out


def test_campfire_usd_holds_the_flames_sparks_and_logs_over_48_frames(cli, root, tmp_path):
    out = render(cli, root, "campfire-usd.ron", tmp_path)
    flames = Usd.Stage.Open(str(out / "campfire/flames.usda"))
    assert flames.GetDefaultPrim().GetPath() == "/World" and UsdGeom.GetStageUpAxis(flames) == "Y"
    points = UsdGeom.Points(flames.GetPrimAtPath("/World/flames"))
    assert points, "/World/flames is a Points prim"
    assert points.GetPointsAttr().GetTimeSamples() == [float(t) for t in range(48)]
    at_24 = np.asarray(points.GetPointsAttr().Get(24))
    assert len(at_24) > 120, "120 flames, each a trajectory of points"
    # The flames rise from the logs: every point is above the ground and within a few units.
    assert at_24[:, 1].min() > -0.1 and np.abs(at_24).max() < 10
    colors = UsdGeom.PrimvarsAPI(points.GetPrim()).GetPrimvar("displayColor")
    assert colors and colors.GetInterpolation() == "vertex" and len(colors.Get(24)) == len(at_24)
    mesh = UsdGeom.Mesh(flames.GetPrimAtPath("/World/mesh"))
    assert mesh and len(mesh.GetPointsAttr().Get()) > 100, "the log pile is the stage's mesh"
    sparks_stage = Usd.Stage.Open(str(out / "campfire/sparks.usda"))
    sparks = UsdGeom.Points(sparks_stage.GetPrimAtPath("/World/sparks"))
    assert sparks and len(sparks.GetPointsAttr().GetTimeSamples()) == 48
    for stage in ("flames", "sparks"):
        assert validation_errors(out / f"campfire/{stage}.usda") == []


def test_burning_house_layers_hold_beauty_emission_and_depth(cli, root, tmp_path):
    out = render(cli, root, "burning-house-layers.ron", tmp_path, "--frames", "72")
    files = sorted((out / "burning-house-layers").iterdir())
    assert [p.name for p in files] == ["house_0072.exr"]
    layers = channels(files[0])
    assert sorted(layers) == ["A", "B", "G", "R", "depth.Y", "emission.A", "emission.B", "emission.G", "emission.R"]
    assert all(a.shape == (540, 960) and np.isfinite(a).all() for a in layers.values())
    # Half where the graph leaves the default, float where it asks for it.
    with OpenEXR.File(str(files[0]), separate_channels=True) as f:
        stored = {name: c.pixels.dtype for part in f.parts for name, c in part.channels.items()}
    assert stored["emission.R"] == np.float16 and stored["R"] == np.float16 and stored["depth.Y"] == np.float32
    assert (layers["A"] == 1).all(), "the beauty is opaque"
    depth = layers["depth.Y"]
    house = depth < 30
    assert 0.05 < house.mean() < 0.9, "the house fills part of the frame; the rest is at the far plane (30)"
    assert depth[0, 0] == 30 and 2 < depth[house].min() < depth[house].max() < 30
    glow = layers["emission.A"].astype(np.float32) > 0.05
    assert glow.sum() > 200, "at frame 72 both fires burn"
    # The emission pass is the flames alone: it lights nothing where the beauty is dark.
    beauty = layers["R"] + layers["G"] + layers["B"]
    assert beauty[glow].mean() > beauty[~glow].mean()


def png_bit_depth(path):
    """The bit depth a PNG's IHDR chunk declares (Pillow reads 16-bit RGBA as 8-bit)."""
    with open(path, "rb") as f:
        head = f.read(33)
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR"
    width, height, depth = struct.unpack(">IIB", head[16:25])
    return depth


def test_flipbook_unity_sheets_and_side_car_follow_unitys_conventions(cli, root, tmp_path):
    out = render(cli, root, "flipbook-unity.ron", tmp_path)
    folder = out / "flipbook-unity"
    assert sorted(p.name for p in folder.iterdir()) == ["fire_8x8.json", "fire_8x8.png", "fire_8x8_mv.png"]
    car = json.loads((folder / "fire_8x8.json").read_text())
    assert car["convention"] == "unity" and car["engine_setting"] == "Motion Vector Scale"
    assert car["rows"] == car["cols"] == 8 and car["frames"] == 64 and car["alpha"] == "premultiplied"
    assert 0 < car["engine_value"] < 8, "a scale that fits every vector, in cell units"
    # Two mip levels never mix frames: cells aligned to 4 px with at least 2 px of padding.
    assert car["cell_width"] % 4 == 0 and car["cell_height"] % 4 == 0 and car["padding"] >= 2
    sheet = np.asarray(Image.open(folder / "fire_8x8.png"))
    assert sheet.shape == (8 * car["cell_height"], 8 * car["cell_width"], 4)
    assert png_bit_depth(folder / "fire_8x8.png") == 8 and png_bit_depth(folder / "fire_8x8_mv.png") == 16
    # Premultiplied: no sample brighter than its alpha.
    assert (sheet[..., :3].max(axis=-1) <= sheet[..., 3].astype(int) + 1).all()
    motion = np.asarray(Image.open(folder / "fire_8x8_mv.png").convert("RGBA"))
    assert motion.shape == sheet.shape
    # Where nothing moves (the black sky above the fire in the first cell) the vectors encode 0.5.
    corner = motion[car["padding"] : car["padding"] + 8, car["padding"] : car["padding"] + 8, :2]
    assert np.abs(corner.astype(int) - 128).max() <= 1

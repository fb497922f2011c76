"""Makes docs/images/exr-layers.png: the layers of one multi-layer EXR frame written by
imaging.write_exr_layers from the flame renderer's passes, read back with the OpenEXR package, each
drawn with its channel names. Run from the repository root with the Python module and OpenEXR
installed: python docs/exr_layers_picture.py"""

import tempfile
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image, ImageDraw

import pyrograph

W, H = 320, 180
GRAPH = f"""(
    version: 3,
    nodes: {{
        "roots": (type: "particles.roots", params: {{"layout": "row", "count": 3, "spacing": 1.6}}),
        "wind": (type: "particles.wind_field", params: {{"large_scale": "constant", "wind": (0.6, 0.0, 0.0), "seed": 3}}),
        "flame": (type: "particles.particle_flame", params: {{"frames": 1, "steps": 16, "flicker": 0.3, "seed": 2}}),
        "lights": (type: "particles.flame_lights", params: {{"intensity": 3.0}}),
        "logs": (type: "particles.mesh_load", params: {{"source": "cylinder", "size": 0.5, "height": 2.2, "translate": (0.8, 0.0, 2.0)}}),
        "beauty": (type: "particles.render_flames", params: {{"width": {W}, "height": {H}, "ground": true, "background": (0.02, 0.02, 0.03, 1.0),
            "camera_position": (0.0, 2.5, 9.0), "camera_target": (0.0, 1.4, 0.0)}}),
        "emission": (type: "particles.render_flames", params: {{"width": {W}, "height": {H}, "ground": true, "pass": "emission",
            "camera_position": (0.0, 2.5, 9.0), "camera_target": (0.0, 1.4, 0.0)}}),
        "depth": (type: "particles.render_flames", params: {{"width": {W}, "height": {H}, "ground": true, "pass": "depth",
            "camera_position": (0.0, 2.5, 9.0), "camera_target": (0.0, 1.4, 0.0), "far": 30.0}}),
        "layers": (type: "imaging.write_exr_layers", params: {{"pattern": "fire_####.exr", "exr_type": "half",
            "name1": "emission", "name2": "depth", "type2": "float"}}),
    }},
    edges: [
        ("roots.roots", "flame.roots"), ("wind.wind", "flame.wind"),
        ("flame.flames", "beauty.flames"), ("flame.flames", "emission.flames"), ("flame.flames", "depth.flames"),
        ("flame.flames", "lights.flames"), ("lights.lights", "beauty.lights"), ("logs.mesh", "beauty.mesh"), ("logs.mesh", "emission.mesh"), ("logs.mesh", "depth.mesh"),
        ("beauty.image", "layers.main"), ("emission.image", "layers.layer1"), ("depth.image", "layers.layer2"),
    ],
)"""


def main():
    with tempfile.TemporaryDirectory() as tmp:
        pyrograph.Graph.from_ron(GRAPH).render(out=tmp)
        path = Path(tmp) / "fire_0000.exr"
        with OpenEXR.File(str(path), separate_channels=True) as f:
            channels = {n: np.asarray(c.pixels, dtype=np.float32) for n, c in f.parts[0].channels.items()}
    layers = {}
    order = {"(main)": 0, "emission": 1, "depth": 2}
    for name in sorted(channels, key=lambda n: (order.get(n.rsplit(".", 1)[0] if "." in n else "(main)", 9), n)):
        layer = name.rsplit(".", 1)[0] if "." in name else "(main)"
        layers.setdefault(layer, []).append(name)
    panels = []
    for layer, names in layers.items():
        if layer == "depth":
            z = channels["depth.Y"]
            shown = np.repeat((1 - np.clip(z / 30.0, 0, 1))[:, :, None], 3, axis=2)
        else:
            prefix = "" if layer == "(main)" else layer + "."
            shown = np.stack([channels[prefix + c] for c in "RGB"], axis=2)
        picture = Image.fromarray((np.clip(shown, 0, 1) * 255).astype(np.uint8))
        label = Image.new("RGB", (W, 36), (30, 30, 30))
        ImageDraw.Draw(label).text((6, 4), f"{layer}\n" + ", ".join(names), fill=(230, 230, 230))
        panel = Image.new("RGB", (W, H + 36))
        panel.paste(label, (0, 0))
        panel.paste(picture, (0, 36))
        panels.append(panel)
    sheet = Image.new("RGB", (len(panels) * (W + 6) - 6, H + 36), (60, 60, 60))
    for k, panel in enumerate(panels):
        sheet.paste(panel, (k * (W + 6), 0))
    out = Path("docs/images/exr-layers.png")
    sheet.save(out)
    print(f"{out}: layers {list(layers)}")


if __name__ == "__main__":
    main()

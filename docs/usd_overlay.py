"""Makes docs/images/usd-points-over-render.png: a particle fire rendered by pyrograph with the
points of the USD stage `particles.write_usd` wrote for the same frame, read back with Pixar's USD
(usd-core) and projected with the render's camera, drawn over it. Run from the repository root
with the Python module and usd-core installed: python docs/usd_overlay.py"""

import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw
from pxr import Usd, UsdGeom

import pyrograph

FRAME = 20
W, H = 640, 360
EYE, TARGET, FOV = np.array([0.0, 2.0, 9.0]), np.array([0.0, 1.6, 0.0]), 40.0

GRAPH = f"""(
    version: 3,
    nodes: {{
        "roots": (type: "particles.roots", params: {{"layout": "row", "count": 3, "spacing": 1.6}}),
        "wind": (type: "particles.wind_field", params: {{"large_scale": "constant", "wind": (0.8, 0.0, 0.0), "seed": 3}}),
        "flame": (type: "particles.particle_flame", params: {{"frames": 24, "steps": 16, "flicker": 0.3, "seed": 2}}),
        "render": (type: "particles.render_flames", params: {{"width": {W}, "height": {H},
            "camera_position": ({EYE[0]}, {EYE[1]}, {EYE[2]}), "camera_target": ({TARGET[0]}, {TARGET[1]}, {TARGET[2]}),
            "background": (0.02, 0.02, 0.03, 1.0)}}),
        "stage": (type: "particles.write_usd", params: {{"path": "fire.usda"}}),
    }},
    edges: [("roots.roots", "flame.roots"), ("wind.wind", "flame.wind"), ("flame.flames", "render.flames"), ("flame.flames", "stage.particles")],
)"""


def project(points):
    """World points to pixels: the renderer's right-handed look-at and perspective (glam)."""
    f = TARGET - EYE
    f /= np.linalg.norm(f)
    s = np.cross(f, [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    rel = points - EYE
    x, y, z = rel @ s, rel @ u, rel @ f
    t = 1.0 / np.tan(np.radians(FOV) / 2)
    ndc_x, ndc_y = x * t / (W / H) / z, y * t / z
    return np.stack([(ndc_x + 1) / 2 * W, (1 - ndc_y) / 2 * H], axis=1)


def main():
    graph = pyrograph.Graph.from_ron(GRAPH)
    with tempfile.TemporaryDirectory() as tmp:
        graph.render(out=tmp, nodes=["stage"])
        stage = Usd.Stage.Open(str(Path(tmp) / "fire.usda"))
        points = np.asarray(UsdGeom.Points(stage.GetPrimAtPath("/World/flames")).GetPointsAttr().Get(FRAME))
    frame = np.asarray(graph.cook("render.image")[FRAME])
    picture = Image.fromarray((np.clip(frame[:, :, :3], 0, 1) * 255).astype(np.uint8)).convert("RGB")
    draw = ImageDraw.Draw(picture)
    for x, y in project(points):
        draw.ellipse([x - 2, y - 2, x + 2, y + 2], outline=(80, 200, 255))
    out = Path("docs/images/usd-points-over-render.png")
    picture.save(out)
    print(f"{out}: {len(points)} points of frame {FRAME}")


if __name__ == "__main__":
    main()

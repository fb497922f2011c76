"""Cook a preset into numpy arrays and save them with imageio.

    python examples/python/cook_preset.py OUT_DIR [FRAMES]

Loads graphs/flame-cards.ron (two flame-card presets), makes the calm card warmer, cooks its
frames into float32 arrays and writes them as 8-bit PNGs.
"""

import pathlib
import sys

import imageio.v3 as iio
import numpy as np

import pyrograph

ROOT = pathlib.Path(__file__).resolve().parents[2]
out = pathlib.Path(sys.argv[1])
count = int(sys.argv[2]) if len(sys.argv) > 2 else 12
out.mkdir(parents=True, exist_ok=True)

graph = pyrograph.Graph.load(ROOT / "graphs" / "flame-cards.ron")
graph.set("calm.background", (0.08, 0.02, 0.0, 1.0))  # a warm backdrop instead of black
graph.set("calm.width", 128)

frames = graph.cook("calm.clip", frames=range(count), progress=lambda e: e["event"] == "frame" and print(f"\r{e['done']}/{e['total']}", end=""))
print()
for i, rgba in enumerate(frames):  # H×W×4 float32, straight alpha, read-only views
    iio.imwrite(out / f"calm_{i:04d}.png", (np.clip(rgba, 0, 1) * 255 + 0.5).astype(np.uint8))
print(f"wrote {len(frames)} frames of {frames[0].shape[1]}×{frames[0].shape[0]} to {out}")

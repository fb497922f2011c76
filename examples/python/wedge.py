"""A wedge in Python: one parameter swept over values, one frame of each variant side by side.

    python examples/python/wedge.py OUT.png

Sweeps the turbulence of the flame-card preset and writes a strip of frame 6 of each variant.
The graph keeps one evaluator, so each variant re-cooks only what the turbulence feeds.
"""

import pathlib
import sys

import imageio.v3 as iio
import numpy as np

import pyrograph

ROOT = pathlib.Path(__file__).resolve().parents[2]
graph = pyrograph.Graph.load(ROOT / "graphs" / "flame-cards.ron")

cells = []
for turbulence in [0.0, 0.5, 1.0, 2.0, 4.0]:
    graph.set("wild.turbulence", turbulence)
    frame = graph.cook("wild.clip", frames=[6])[0]
    print(f"turbulence {turbulence}: re-cooked {', '.join(graph.last_cooked)}")
    cells.append(frame)

strip = np.concatenate(cells, axis=1)
iio.imwrite(sys.argv[1], (np.clip(strip, 0, 1) * 255 + 0.5).astype(np.uint8))
print(f"wrote {sys.argv[1]}: {strip.shape[1]}×{strip.shape[0]}")

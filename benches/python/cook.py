"""The Python side of the binding benchmark: cook FRAMES frames of NODE.PORT into numpy arrays.

    python cook.py GRAPH NODE.PORT FRAMES

Prints the same JSON as examples/cook_to_memory.rs: seconds (load + cook, in process), frames and
a checksum of every sample, so the runner can assert both sides produced the same pixels.
"""

import json
import sys
import time

import numpy as np

import pyrograph

graph, endpoint, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
started = time.perf_counter()
g = pyrograph.Graph.load(graph)
arrays = g.cook(endpoint, frames=range(frames))
seconds = time.perf_counter() - started
checksum = float(sum(a.sum(dtype=np.float64) for a in arrays))
print(json.dumps({"seconds": seconds, "frames": len(arrays), "checksum": checksum}))

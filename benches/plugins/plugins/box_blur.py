# The benchmark's plugin node: a 5x5 box blur in numpy slicing (separable, edges repeated), as a
# technical artist would write it. benches/plugins/plain_loop.py imports the same function, so
# both sides of the benchmark run exactly this code on every frame.
import numpy as np
from pyrograph_plugin import Image, node


@node("bench.box_blur", category="Bench")
def box_blur(image: Image(doc="Frame to blur")) -> Image:
    """Blurs a frame with a 5x5 box (edges repeated): the plugin benchmark's per-frame filter."""
    pad = [(2, 2), (2, 2)] + [(0, 0)] * (image.ndim - 2)
    p = np.pad(image, pad, mode="edge")
    h, w = image.shape[:2]
    rows = p[:, 0:w] + p[:, 1 : w + 1] + p[:, 2 : w + 2] + p[:, 3 : w + 3] + p[:, 4 : w + 4]
    out = rows[0:h] + rows[1 : h + 1] + rows[2 : h + 2] + rows[3 : h + 3] + rows[4 : h + 4]
    return (out * np.float32(1 / 25)).astype(np.float32, copy=False)


@node("bench.pass", category="Bench")
def pass_through(image: Image(doc="Frame")) -> Image:
    """Returns its frame: what a call into Python costs, without any work in it."""
    return image

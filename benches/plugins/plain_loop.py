"""The plugin benchmark's peer: the same box_blur function (imported from plugins/box_blur.py) in
a plain Python loop over the same PNG frames, read and written with Pillow, one frame at a time.

    plain_loop.py FRAMES_DIR OUT_DIR
"""
import os
import pathlib
import sys

import numpy as np
from PIL import Image

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "crates" / "plugin" / "host"))  # pyrograph_plugin
sys.path.insert(0, str(HERE / "plugins"))
from box_blur import box_blur  # noqa: E402


def main(frames, out):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for i, path in enumerate(sorted(pathlib.Path(frames).glob("*.png"))):
        rgba = np.asarray(Image.open(path).convert("RGBA"), dtype=np.float32) / np.float32(255)
        blurred = box_blur(rgba)
        pixels = (np.clip(blurred, 0, 1) * 255 + 0.5).astype(np.uint8)
        Image.fromarray(pixels, "RGBA").save(out / f"blur_{i:04d}.png")


if __name__ == "__main__":
    main(*sys.argv[1:3])
    os._exit(0)

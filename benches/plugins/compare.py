"""Checks the two sides of the plugin benchmark made the same frames: every PNG of A has a PNG of
the same name in B whose pixels differ by at most 1/255 (rounding), and the counts match.

    compare.py DIR_A DIR_B
"""
import pathlib
import sys

import numpy as np
from PIL import Image

a, b = (pathlib.Path(p) for p in sys.argv[1:3])
names = sorted(p.name for p in a.glob("*.png"))
assert names and names == sorted(p.name for p in b.glob("*.png")), "the two sides wrote different files"
worst = 0
for n in names:
    x = np.asarray(Image.open(a / n).convert("RGBA"), dtype=np.int16)
    y = np.asarray(Image.open(b / n).convert("RGBA"), dtype=np.int16)
    worst = max(worst, int(np.abs(x - y).max()))
assert worst <= 1, f"frames differ by up to {worst}/255"
print(f"{len(names)} frames agree (largest difference {worst}/255)")

"""The Python examples run (all but the Blender one, which needs Blender)."""

import pathlib
import subprocess
import sys

import numpy as np
from PIL import Image

ROOT = pathlib.Path(__file__).resolve().parents[3]


def test_cook_preset_example(tmp_path):
    subprocess.run([sys.executable, ROOT / "examples/python/cook_preset.py", tmp_path, "4"], check=True, capture_output=True)
    files = sorted(tmp_path.glob("calm_*.png"))
    assert len(files) == 4
    frame = np.asarray(Image.open(files[2]))
    assert frame.shape == (192, 128, 4)
    # The warm backdrop it sets shows in the corner.
    assert tuple(frame[0, 0]) == (20, 5, 0, 255)


def test_wedge_example(tmp_path):
    run = subprocess.run([sys.executable, ROOT / "examples/python/wedge.py", tmp_path / "strip.png"], check=True, capture_output=True, text=True)
    strip = np.asarray(Image.open(tmp_path / "strip.png"))
    assert strip.shape == (96, 5 * 64, 4)
    cells = [strip[:, i * 64 : (i + 1) * 64] for i in range(5)]
    assert all(np.abs(cells[0].astype(int) - c.astype(int)).max() > 10 for c in cells[1:])
    # After the first variant only the wild card's flame and what follows it re-cook.
    assert run.stdout.count("re-cooked wild/flame, wild/over, wild/size") == 4

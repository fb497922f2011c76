"""Makes the plugin benchmark's input: COUNT 1920x1080 PNG frames from the shared candle footage
(its 854x480 frames scaled up, cycled), written once into OUT_DIR.

    make_frames.py FOOTAGE_FRAMES_DIR OUT_DIR [COUNT]
"""
import pathlib
import sys

from PIL import Image


def main(source, out, count=200):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    frames = sorted(pathlib.Path(source).glob("*.png"))
    for i in range(int(count)):
        target = out / f"frame_{i:04d}.png"
        if not target.exists():
            Image.open(frames[i % len(frames)]).convert("RGB").resize((1920, 1080), Image.BICUBIC).save(target)


if __name__ == "__main__":
    main(*sys.argv[1:])

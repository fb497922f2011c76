"""OpenCV peer of benches/maskchain/mask.ron: the same chain over a folder of PNG frames, one frame at a time.

imread -> BGR2HSV -> inRange blue (100,80,60)-(130,255,255) | red (0,100,80)-(15,255,255) |
yellow (15,80,100)-(35,255,255) -> open + close (5x5 ellipse) -> findContours(EXTERNAL, NONE) ->
area >= 100, largest -> filled -> mask_NNNN.png (8-bit gray, 0/255). Same thresholds as mask.ron
(which states hues in degrees, OpenCV's half-hues x2).

    python opencv_mask.py FRAMES_DIR OUT_DIR
"""
import os
import sys

import cv2
import numpy as np

RANGES = [((100, 80, 60), (130, 255, 255)), ((0, 100, 80), (15, 255, 255)), ((15, 80, 100), (35, 255, 255))]
LOWER = [np.array(lo, np.uint8) for lo, _ in RANGES]
UPPER = [np.array(hi, np.uint8) for _, hi in RANGES]
KERNEL = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def mask_of(bgr):
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    mask = cv2.inRange(hsv, LOWER[0], UPPER[0])
    for lo, hi in zip(LOWER[1:], UPPER[1:]):
        mask |= cv2.inRange(hsv, lo, hi)
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, KERNEL)
    mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, KERNEL)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    kept = [(cv2.contourArea(c), c) for c in contours]
    kept = [ac for ac in kept if ac[0] >= 100.0]
    out = np.zeros(mask.shape, np.uint8)
    if kept:
        largest = max(kept, key=lambda ac: ac[0])[1]
        cv2.drawContours(out, [largest], -1, 255, cv2.FILLED)
    return out


def main():
    src, dst = sys.argv[1], sys.argv[2]
    os.makedirs(dst, exist_ok=True)
    names = sorted(n for n in os.listdir(src) if n.endswith(".png"))
    for i, name in enumerate(names):
        bgr = cv2.imread(os.path.join(src, name), cv2.IMREAD_COLOR)
        if bgr is None:
            raise SystemExit(f"cannot read {name}")
        cv2.imwrite(os.path.join(dst, f"mask_{i:04d}.png"), mask_of(bgr))


if __name__ == "__main__":
    main()

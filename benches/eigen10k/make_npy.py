"""Writes the first M frames of a video as an (M, H, W) float32 .npy of gray values in 0..1
(OpenCV's BGR2GRAY, 0.299 R + 0.587 G + 0.114 B, as pyrograph's imaging.to_gray), for pca.py --input.

    python make_npy.py VIDEO M OUT.npy
"""
import sys

import cv2
import numpy as np


def main():
    video, m, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    cap = cv2.VideoCapture(video)
    w, h = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
    x = np.lib.format.open_memmap(out + ".part.npy", mode="w+", dtype=np.float32, shape=(m, h, w))
    for i in range(m):
        ok, bgr = cap.read()
        if not ok:
            sys.exit(f"{video} ends at frame {i}, before {m}")
        x[i] = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY).astype(np.float32) * np.float32(1 / 255)
    x.flush()
    del x
    import os
    os.replace(out + ".part.npy", out)


if __name__ == "__main__":
    main()

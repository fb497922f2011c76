# An example whole-clip pyrograph node type written in Python: studio.temporal_median, which gives
# each pixel its median over the neighbouring frames, so sparks and single-frame flicker vanish
# while the flame's slower motion stays. pyrograph finds the plugins/ folder beside a graph by
# itself, so this renders the example graph:
#
#     pyrograph render examples/plugins/temporal_median/temporal-median.ron --out pyrograph-out
from collections import deque

import numpy as np
from pyrograph_plugin import Clip, Int, node


@node("studio.temporal_median", category="Studio", time="whole_clip")
def temporal_median(
    clip: Clip(doc="Frames to clean"),
    radius: Int(range=(1, 8), doc="Frames on each side that vote") = 2,
) -> Clip:
    """Removes sparks and single-frame flicker: each pixel becomes its median over nearby frames.

    Frame i is the per-pixel median of frames i−radius … i+radius, clamped to the clip, so the
    first and last frames have fewer neighbours. The window slides forward one frame at a time:
    each input frame is fetched once, and at most 2·radius+1 are held, however long the clip.
    """
    last = len(clip) - 1
    window = deque()  # (index, frame) for the frames lo … hi of the current window, in order
    for i in range(len(clip)):
        lo, hi = max(0, i - radius), min(last, i + radius)
        while window and window[0][0] < lo:
            window.popleft()
        start = window[-1][0] + 1 if window else lo
        for j in range(start, hi + 1):
            window.append((j, clip[j]))
        # np.median of float32 frames stays float32, with the input's (H,W) or (H,W,4) shape.
        yield np.median(np.stack([frame for _, frame in window]), axis=0).astype(np.float32, copy=False)

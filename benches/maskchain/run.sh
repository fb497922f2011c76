#!/usr/bin/env bash
# Mask-chain benchmark (issue 23): 266 RGB PNG frames at 1920x1080 -> HSV mask, open, close,
# contours, largest blob filled -> mask PNGs; pyrograph (benches/maskchain/mask.ron) beside the
# OpenCV peer (opencv_mask.py, a Python loop, one frame at a time), alternating, whole processes timed
# by /usr/bin/time (wall seconds, peak RSS). Every round checks that the two mask sequences agree
# (intersection over union over all frames). Prints one line per run and a median table.
#
#   benches/maskchain/run.sh                 ROUNDS=3 FRAMES=266 WORK=/tmp/pyrograph-maskchain
#
# Needs ffmpeg, a release build (`cargo build --release`) and the peers' venv
# (../shared/peers/setup.sh -> /tmp/peers-venv, or PYTHON=...). The frames are the candle-black
# footage (854x480, 150 frames) looped and scaled to 1920x1080 by ffmpeg, made once in $WORK.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
bin="${PYROGRAPH_BIN:-$repo/target/release/pyrograph}"
python="${PYTHON:-/tmp/peers-venv/bin/python}"
footage="${PYROGRAPH_FOOTAGE:-$repo/../shared/footage}"
work="${WORK:-/tmp/pyrograph-maskchain}"
rounds="${ROUNDS:-3}"
n="${FRAMES:-266}"
[ -x "$bin" ] || { echo "build first: cargo build --release (no $bin)" >&2; exit 1; }
[ -x "$python" ] || { echo "no peer python at $python: run ../shared/peers/setup.sh" >&2; exit 1; }
frames="$work/frames_1080p_$n"
if [ ! -s "$frames/f_$(printf %04d $((n - 1))).png" ]; then
    rm -rf "$frames.part"; mkdir -p "$frames.part"
    ffmpeg -v error -nostdin -stream_loop -1 -i "$footage/candle-black/candle_flame.mp4" -an \
        -vf scale=1920:1080:flags=bicubic -frames:v "$n" -start_number 0 "$frames.part/f_%04d.png"
    rm -rf "$frames"; mv "$frames.part" "$frames"
fi
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $n frames 1920x1080"
echo "# pyrograph: rayon on $(nproc) threads; OpenCV: $("$python" -c 'import cv2; print(cv2.__version__, "threads", cv2.getNumThreads())')"
echo "# tool frames wall_s peak_rss_mib"
results="$work/results.txt"
: > "$results"
for r in $(seq "$rounds"); do
    rm -rf "$work/py" "$work/cv"; mkdir -p "$work/py" "$work/cv"
    t=$( { /usr/bin/time -f "%e %M" "$bin" render "$here/mask.ron" --out "$work/py" \
        --set "load.path=\"$frames\"" --set 'write.pattern="mask_####.png"' >/dev/null; } 2>&1 | tail -n1)
    echo "pyrograph $n $(echo "$t" | awk '{printf "%s %.0f", $1, $2/1024}')" | tee -a "$results"
    t=$( { /usr/bin/time -f "%e %M" "$python" "$here/opencv_mask.py" "$frames" "$work/cv"; } 2>&1 | tail -n1)
    echo "opencv $n $(echo "$t" | awk '{printf "%s %.0f", $1, $2/1024}')" | tee -a "$results"
    "$python" - "$work/py" "$work/cv" "$n" <<'PY'
import os, sys
import cv2, numpy as np
a, b, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
names = sorted(os.listdir(a))
if len(names) != n or len(os.listdir(b)) != n:
    sys.exit(f"frame counts differ: pyrograph {len(names)}, opencv {len(os.listdir(b))}, want {n}")
inter = union = 0
worst = (2.0, "")
for name in names:
    x = cv2.imread(os.path.join(a, name), cv2.IMREAD_GRAYSCALE) > 127
    y = cv2.imread(os.path.join(b, name), cv2.IMREAD_GRAYSCALE) > 127
    i, u = int((x & y).sum()), int((x | y).sum())
    inter, union = inter + i, union + u
    worst = min(worst, (i / u if u else 1.0, name))
iou = inter / union
print(f"# masks agree: IoU {iou:.5f} over {n} frames ({union} pixels in either), worst frame {worst[1]} {worst[0]:.4f}")
if iou < 0.99:
    sys.exit("masks disagree")
PY
done
rm -rf "$work/py" "$work/cv"
echo "# medians: pyrograph wall s / peak MiB, opencv wall s / peak MiB, wall ratio (median of per-round ratios)"
python3 - "$results" <<'PY'
import sys, statistics as st
rows = [l.split() for l in open(sys.argv[1])]
py = [r for r in rows if r[0] == "pyrograph"]
cv = [r for r in rows if r[0] == "opencv"]
ratios = [float(a[2]) / float(b[2]) for a, b in zip(py, cv)]
med = lambda rs, i: st.median(float(r[i]) for r in rs)
print(f"{py[0][1]} frames: pyrograph {med(py, 2):.2f} s / {med(py, 3):.0f} MiB, opencv {med(cv, 2):.2f} s / {med(cv, 3):.0f} MiB, "
      f"ratio {st.median(ratios):.2f} (rounds {', '.join(f'{x:.2f}' for x in ratios)})")
PY

#!/usr/bin/env bash
# Out-of-core Eigenfires benchmark (issue 23): 10,000 gray frames of 410x670 (11 GB as f32)
# trained by eigen.eigenfires (50 components) with default settings, which stream the frames from
# the video in blocks; then the same data trained in memory (train.memory_mb raised) and the two
# bases compared (principal angles of the first 50 eigenfires, angles.py); then numpy's gram trick
# (../shared/peers/pca.py) beside pyrograph on the largest size numpy can hold (NUMPY_FRAMES,
# default 8,000: numpy holds the frames and their centred copy, 2 x 8.8 GB). Whole processes,
# timed by /usr/bin/time (wall seconds, peak RSS).
#
#   benches/eigen10k/run.sh [STEPS...]     steps: ooc inmem angles numpy ours-at-numpy (default: all)
#   FRAMES=10000 NUMPY_FRAMES=8000 WORK=/tmp/pyrograph-eigen10k benches/eigen10k/run.sh
#
# Needs ffmpeg, a release build and the peers' venv (../shared/peers/setup.sh). The video is the
# tealight footage (480x480, 796 frames) cropped to 294x480, scaled to 410x670 and looped to
# FRAMES frames (x264 crf 16), made once in $WORK. Disk: about 9 GB for numpy's .npy.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
bin="${PYROGRAPH_BIN:-$repo/target/release/pyrograph}"
python="${PYTHON:-/tmp/peers-venv/bin/python}"
footage="${PYROGRAPH_FOOTAGE:-$repo/../shared/footage}"
peers="${PEERS:-$repo/../shared/peers}"
work="${WORK:-/tmp/pyrograph-eigen10k}"
n="${FRAMES:-10000}"
nn="${NUMPY_FRAMES:-8000}"
steps=("$@")
[ ${#steps[@]} -gt 0 ] || steps=(ooc inmem angles numpy ours-at-numpy)
[ -x "$bin" ] || { echo "build first: cargo build --release (no $bin)" >&2; exit 1; }
mkdir -p "$work"
video="$work/tealight_410x670_$n.mp4"
if [ ! -s "$video" ]; then
    ffmpeg -v error -nostdin -stream_loop -1 -i "$footage/tealight-candle/candle.mp4" -an \
        -vf "crop=294:480:93:0,scale=410:670:flags=bicubic" -frames:v "$n" -c:v libx264 -preset veryfast -crf 16 -g 48 \
        -pix_fmt yuv420p "$video.part.mp4"
    mv "$video.part.mp4" "$video"
fi
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); pyrograph on $(nproc) rayon threads"
train() { # name last memory_mb
    local t
    rm -rf "$work/$1.db"
    t=$( { /usr/bin/time -f "%e %M" "$bin" render "$here/train.ron" --out "$work" --json \
        --set "load.path=\"$video\"" --set "range.last=$2" --set "train.memory_mb=$3" --set "save.path=\"$1.db\"" \
        > "$work/$1.json"; } 2>&1 | tail -n1)
    echo "pyrograph $1: $(( $2 + 1 )) frames of 410x670, memory_mb $3: wall $(echo "$t" | awk '{printf "%s s, peak RSS %.0f MiB", $1, $2/1024}')"
}
for step in "${steps[@]}"; do
    case "$step" in
        ooc) train ooc $((n - 1)) 4096 ;;
        inmem) train inmem $((n - 1)) 1000000 ;;
        angles) "$python" "$here/angles.py" "$work/ooc.db" "$work/inmem.db" 50 ;;
        numpy)
            [ -s "$work/frames_$nn.npy" ] || "$python" "$here/make_npy.py" "$video" "$nn" "$work/frames_$nn.npy"
            t=$( { (cd "$peers" && /usr/bin/time -f "%e %M" "$python" pca.py --input "$work/frames_$nn.npy" --e 50 \
                --skip-randomized --repeats 1 --warmup 0 > "$work/numpy_$nn.jsonl"); } 2>&1 | tail -n1)
            echo "numpy gram trick: $nn frames: process wall $(echo "$t" | awk '{printf "%s s, peak RSS %.0f MiB", $1, $2/1024}')"
            "$python" -c 'import json,sys
for l in open(sys.argv[1]):
    r = json.loads(l)
    if r["op"] == "gram_eigenfaces": print("  gram_eigenfaces", round(r["median_s"], 1), "s", r.get("breakdown_median_s"))' "$work/numpy_$nn.jsonl"
            ;;
        ours-at-numpy) train "ours$nn" $((nn - 1)) 4096 ;;
        *) echo "unknown step $step" >&2; exit 2 ;;
    esac
done

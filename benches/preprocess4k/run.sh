#!/usr/bin/env bash
# 4K preprocess benchmark (issue 23): a 3840x2160 video of 600 frames through
# graphs/presets/preprocess.ron (HSV mask, morphology, contours, hole removal, Douglas-Peucker,
# Hermite background removal, pose normalization), writing gray and mask PNGs. One whole process
# per round, timed by /usr/bin/time (wall seconds, peak RSS), with the render's own --json report
# (frame cache counters). Target: peak RSS <= 3 GiB with default settings.
#
#   benches/preprocess4k/run.sh              ROUNDS=1 FRAMES=600 WORK=/tmp/pyrograph-4k
#
# Needs ffmpeg and a release build. The video is the candle-black footage (854x480, 150 frames)
# looped and scaled to 3840x2160 (x264, a keyframe every 48 frames), made once in $WORK.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
bin="${PYROGRAPH_BIN:-$repo/target/release/pyrograph}"
footage="${PYROGRAPH_FOOTAGE:-$repo/../shared/footage}"
work="${WORK:-/tmp/pyrograph-4k}"
rounds="${ROUNDS:-1}"
n="${FRAMES:-600}"
[ -x "$bin" ] || { echo "build first: cargo build --release (no $bin)" >&2; exit 1; }
mkdir -p "$work"
video="$work/candle_4k_$n.mp4"
if [ ! -s "$video" ]; then
    ffmpeg -v error -nostdin -stream_loop -1 -i "$footage/candle-black/candle_flame.mp4" -an \
        -vf scale=3840:2160:flags=bicubic -frames:v "$n" -c:v libx264 -preset veryfast -g 48 -pix_fmt yuv420p "$video.part.mp4"
    mv "$video.part.mp4" "$video"
fi
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $n frames 3840x2160"
for r in $(seq "$rounds"); do
    rm -rf "$work/out"; mkdir -p "$work/out"
    t=$( { /usr/bin/time -f "%e %M" "$bin" render "$here/preprocess.ron" --out "$work/out" --json \
        --set "load.path=\"$video\"" > "$work/report.json"; } 2>&1 | tail -n1)
    gray=$(ls "$work/out/gray" | wc -l); mask=$(ls "$work/out/mask" | wc -l)
    [ "$gray" = "$n" ] && [ "$mask" = "$n" ] || { echo "wrote $gray gray and $mask mask frames, want $n" >&2; exit 1; }
    echo "round $r: $n frames, wall $(echo "$t" | awk '{printf "%s s, peak RSS %.0f MiB", $1, $2/1024}')"
    python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print("  report:", {k: r[k] for k in r if k in ("peak_rss_mib", "frame_cache")})' "$work/report.json"
done
rm -rf "$work/out"

#!/usr/bin/env bash
# graphs/preprocess-auto.ron on long 1080p footage (issue 47): the auto-tuning nodes read the clip
# in one pass without holding frames, so peak memory does not grow with the clip's length. One
# whole process per round, timed by /usr/bin/time (wall seconds, peak RSS), with the render's own
# --json report. Target: peak RSS under 1 GiB at any length.
#
#   benches/preprocess-auto/run.sh            ROUNDS=1 LENGTHS="266 1000" WORK=/tmp/pyrograph-auto
#   BASELINE=/path/to/old/pyrograph BASELINE_GRAPH=old.ron benches/preprocess-auto/run.sh
#
# With BASELINE (a binary of another commit, and its graph), each round runs both, alternating,
# on the same clip. Needs ffmpeg and a release build. The clips are the candle-black footage
# (854x480, 150 frames) looped and scaled to 1920x1080 (x264 veryfast, CRF 18), made once in $WORK.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
bin="${PYROGRAPH_BIN:-$repo/target/release/pyrograph}"
graph="$repo/graphs/preprocess-auto.ron"
footage="${PYROGRAPH_FOOTAGE:-$repo/../shared/footage}"
work="${WORK:-/tmp/pyrograph-auto}"
rounds="${ROUNDS:-1}"
[ -x "$bin" ] || { echo "build first: cargo build --release (no $bin)" >&2; exit 1; }
mkdir -p "$work"
run() { # label binary graph video frames
    rm -rf "$work/out"; mkdir -p "$work/out"
    t=$( { /usr/bin/time -f "%e %M" "$2" render "$3" --out "$work/out" --json \
        --set "frames.path=\"$4\"" > "$work/report.json"; } 2>&1 | tail -n1)
    gray=$(ls "$work/out/preprocess-auto" | grep -c '^gray_')
    [ "$gray" = "$5" ] || { echo "$1 wrote $gray gray frames, want $5" >&2; exit 1; }
    echo "  $1: wall $(echo "$t" | awk '{printf "%s s, peak RSS %.0f MiB", $1, $2/1024}')"
}
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), load $(cut -d' ' -f1-3 /proc/loadavg)"
for n in ${LENGTHS:-266 1000}; do
    video="$work/candle_1080_$n.mp4"
    if [ ! -s "$video" ]; then
        ffmpeg -v error -nostdin -stream_loop -1 -i "$footage/candle-black/candle_flame.mp4" -an \
            -vf scale=1920:1080:flags=bicubic -frames:v "$n" -c:v libx264 -preset veryfast -crf 18 -pix_fmt yuv420p "$video.part.mp4"
        mv "$video.part.mp4" "$video"
    fi
    echo "$n frames 1920x1080:"
    for r in $(seq "$rounds"); do
        if [ -n "${BASELINE:-}" ]; then run "baseline round $r" "$BASELINE" "${BASELINE_GRAPH:-$graph}" "$video" "$n"; fi
        run "round $r" "$bin" "$graph" "$video" "$n"
    done
done
rm -rf "$work/out"

#!/usr/bin/env bash
# Streaming-memory benchmark (issue 23): synthetic 1080p video -> gray -> 8-bit PNG sequence,
# pyrograph (benches/stream/gray.ron) beside `ffmpeg -vf format=gray`, alternating, whole processes
# timed by /usr/bin/time (wall seconds, peak RSS). Prints one line per run and a median table.
#
#   benches/stream/run.sh [LENGTHS...]     default lengths: 100 1000 3000
#   ROUNDS=3 WORK=/tmp/pyrograph-stream benches/stream/run.sh 100 1000
#
# Needs ffmpeg and a release build (`cargo build --release`). The videos are made once with
# ffmpeg's testsrc2 (1920x1080, 24 fps, x264, a keyframe every 48 frames) in $WORK.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
bin="${PYROGRAPH_BIN:-$repo/target/release/pyrograph}"
work="${WORK:-/tmp/pyrograph-stream}"
rounds="${ROUNDS:-3}"
lengths=("$@")
[ ${#lengths[@]} -gt 0 ] || lengths=(100 1000 3000)
[ -x "$bin" ] || { echo "build first: cargo build --release (no $bin)" >&2; exit 1; }
mkdir -p "$work"
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(ffmpeg -version | head -n1 | cut -d' ' -f1-3)"
echo "# tool frames wall_s peak_rss_mib"
results="$work/results.txt"
: > "$results"
for n in "${lengths[@]}"; do
    video="$work/testsrc2_1080p_$n.mp4"
    if [ ! -s "$video" ]; then
        ffmpeg -v error -nostdin -f lavfi -i "testsrc2=size=1920x1080:rate=24" -frames:v "$n" \
            -c:v libx264 -preset veryfast -g 48 -pix_fmt yuv420p "$video.part.mp4"
        mv "$video.part.mp4" "$video"
    fi
    for r in $(seq "$rounds"); do
        rm -rf "$work/py" "$work/ff"; mkdir -p "$work/py" "$work/ff"
        t=$( { /usr/bin/time -f "%e %M" "$bin" render "$here/gray.ron" --out "$work/py" \
            --set "load.path=\"$video\"" --set 'write.pattern="f_####.png"' >/dev/null; } 2>&1 | tail -n1)
        echo "pyrograph $n $(echo "$t" | awk '{printf "%s %.0f", $1, $2/1024}')" | tee -a "$results"
        t=$( { /usr/bin/time -f "%e %M" ffmpeg -v error -nostdin -i "$video" -vf format=gray -start_number 0 \
            "$work/ff/f_%04d.png"; } 2>&1 | tail -n1)
        echo "ffmpeg $n $(echo "$t" | awk '{printf "%s %.0f", $1, $2/1024}')" | tee -a "$results"
        # Same frames out: count and a middle frame's PSNR (full-range gray vs swscale's).
        a=$(ls "$work/py" | wc -l); b=$(ls "$work/ff" | wc -l)
        [ "$a" = "$n" ] && [ "$b" = "$n" ] || { echo "frame counts differ: pyrograph $a, ffmpeg $b, want $n" >&2; exit 1; }
        mid=$(printf "f_%04d.png" $((n / 2)))
        psnr=$(ffmpeg -nostdin -i "$work/py/$mid" -i "$work/ff/$mid" -lavfi psnr -f null - 2>&1 | grep -o 'average:[0-9.inf]*' | cut -d: -f2)
        echo "# round $r: frame $mid agrees at PSNR $psnr dB"
    done
done
rm -rf "$work/py" "$work/ff"
echo "# medians: frames, pyrograph wall s / peak MiB, ffmpeg wall s / peak MiB, wall ratio (median of per-round ratios)"
python3 - "$results" <<'PY'
import sys, statistics as st
rows = [l.split() for l in open(sys.argv[1])]
for n in sorted({int(r[1]) for r in rows}):
    py = [r for r in rows if r[0] == "pyrograph" and int(r[1]) == n]
    ff = [r for r in rows if r[0] == "ffmpeg" and int(r[1]) == n]
    ratios = [float(a[2]) / float(b[2]) for a, b in zip(py, ff)]
    med = lambda rs, i: st.median(float(r[i]) for r in rs)
    print(f"{n} frames: pyrograph {med(py, 2):.2f} s / {med(py, 3):.0f} MiB, ffmpeg {med(ff, 2):.2f} s / {med(ff, 3):.0f} MiB, "
          f"ratio {st.median(ratios):.2f} (rounds {', '.join(f'{x:.2f}' for x in ratios)})")
PY

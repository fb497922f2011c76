#!/usr/bin/env bash
# The plugin benchmark (issue 63): 200 1080p PNG frames (the shared candle footage scaled up)
# through a 5x5 numpy box blur written as a Python plugin node, cooked by `pyrograph render`,
# against the same function in a plain Python loop over the same PNGs (Pillow reads and writes).
# Both sides use one interpreter (PYROGRAPH_BENCH_PYTHON, numpy + Pillow); their frames are
# compared first (at most 1/255 apart), then farm-bench alternates them. Then the cost of one call
# into Python: 2000 tiny frames through bench.pass (which returns its frame) against the same
# graph without it.
#
#   PYROGRAPH_FOOTAGE=… benches/plugins/run.sh [RUNS]   (default 5; builds the release binary)
set -euo pipefail
cd "$(dirname "$0")/../.."
runs="${1:-5}"
py="${PYROGRAPH_BENCH_PYTHON:-$PWD/target/py-venv/bin/python}"
footage="${PYROGRAPH_FOOTAGE:-$(cd ../shared/footage && pwd)}"
work=target/bench-plugins
frames="$PWD/$work/frames"
"$py" benches/plugins/make_frames.py "$footage/candle-black/frames" "$frames" 200
cargo build -q --release --bin pyrograph
bin="$PWD/target/release/pyrograph"
export PYROGRAPH_BENCH_FRAMES="$frames" PYROGRAPH_PYTHON="$py"
threads="${RAYON_NUM_THREADS:-$(nproc)}"
export RAYON_NUM_THREADS="$threads"
echo "host: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $threads cook threads, $(date -u +%F)"

# One checked run of each side: the same frames.
rm -rf "$work/pyro" "$work/plain"
"$bin" render benches/plugins/box-blur.ron --out "$work/pyro" >/dev/null
"$py" benches/plugins/plain_loop.py "$frames" "$work/plain/blur"
"$py" benches/plugins/compare.py "$work/pyro/blur" "$work/plain/blur"

farm-bench -n "$runs" --timeout 3000 --vs "$py benches/plugins/plain_loop.py $frames $work/plain/blur" -- \
    "$bin" render benches/plugins/box-blur.ron --out "$work/pyro"
farm-bench -n "$runs" --timeout 1200 --vs "$bin render benches/plugins/overhead-none.ron --out $work/none" -- \
    "$bin" render benches/plugins/overhead.ron --out "$work/pass"

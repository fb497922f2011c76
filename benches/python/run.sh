#!/usr/bin/env bash
# The Python-binding benchmark: the same cook (100 frames of a 512×512 flame card into memory)
# through the Rust API and through `import pyrograph`, alternating Rust and Python over ROUNDS
# rounds in one sitting, each round a fresh process. Prints per-round times and ratios, their
# medians, peak RSS of each side, and fails if the two sides' pixel checksums differ.
#
#   benches/python/run.sh [ROUNDS]     (default 7; needs a release build of the wheel, see BENCHMARKS.md)
set -euo pipefail
cd "$(dirname "$0")/../.."
rounds="${1:-7}"
py="${PYROGRAPH_BENCH_PYTHON:-target/py-bench/bin/python}"
graph=benches/python/flame-card-512.ron
cargo build -q --release --example cook_to_memory
rust=target/release/examples/cook_to_memory
echo "host: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) threads, $(date -u +%F)"
field() { python3 -c "import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])" "$1" "$2"; }
peak() { grep 'Maximum resident' "$1" | awk '{print $6}'; }
ratios=(); rs=(); ps=(); rrss=(); prss=()
for i in $(seq 1 "$rounds"); do
    r=$(/usr/bin/time -v -o /tmp/pyro-bench-rust.time "$rust" "$graph" card.image 100)
    p=$(/usr/bin/time -v -o /tmp/pyro-bench-py.time "$py" benches/python/cook.py "$graph" card.image 100)
    rc=$(field "$r" checksum); pc=$(field "$p" checksum)
    python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); sys.exit(0 if abs(a-b) <= 1e-9*abs(a) else 1)" "$rc" "$pc" \
        || { echo "round $i: checksums differ: rust $rc, python $pc"; exit 1; }
    rt=$(field "$r" seconds); pt=$(field "$p" seconds)
    ratio=$(python3 -c "import sys; print(f'{float(sys.argv[2])/float(sys.argv[1]):.3f}')" "$rt" "$pt")
    rs+=("$rt"); ps+=("$pt"); ratios+=("$ratio"); rrss+=("$(peak /tmp/pyro-bench-rust.time)"); prss+=("$(peak /tmp/pyro-bench-py.time)")
    printf 'round %d: rust %.3f s (%s MiB)  python %.3f s (%s MiB)  ratio %s\n' "$i" "$rt" "$(( ${rrss[-1]} / 1024 ))" "$pt" "$(( ${prss[-1]} / 1024 ))" "$ratio"
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
echo "median: rust $(median "${rs[@]}") s, python $(median "${ps[@]}") s, ratio $(median "${ratios[@]}") (python / rust); peak RSS rust $(( $(median "${rrss[@]}") / 1024 )) MiB, python $(( $(median "${prss[@]}") / 1024 )) MiB"

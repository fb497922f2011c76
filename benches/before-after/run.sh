#!/usr/bin/env bash
# Whole-process render times of shipped graphs with two pyrograph binaries (a refactor's before
# and after), alternating in one sitting with the order flipped every round; prints per-round
# after/before ratios and their median.
#   BEFORE=/path/to/old/pyrograph AFTER=target/release/pyrograph ROUNDS=7 benches/before-after/run.sh
# Needs PYROGRAPH_FOOTAGE for the footage graphs (default: ../shared/footage beside the checkout).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
: "${BEFORE:?set BEFORE to the old binary}"
AFTER="${AFTER:-$root/target/release/pyrograph}"
export PYROGRAPH_FOOTAGE="${PYROGRAPH_FOOTAGE:-$(cd "$root/../shared/footage" && pwd)}"
rounds="${ROUNDS:-7}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cd "$root/graphs"
for g in ${GRAPHS:-demo mass-spring-9 preprocess-candle learning-flames-candle}; do
  ratios=()
  for r in $(seq 1 "$rounds"); do
    if [ $((r % 2)) -eq 1 ]; then order="before after"; else order="after before"; fi
    declare -A t
    for side in $order; do
      bin="$BEFORE"; [ "$side" = after ] && bin="$AFTER"
      s=$(date +%s.%N)
      "$bin" render "$g.ron" --out "$out/$side/$g" --overwrite >/dev/null
      t[$side]=$(echo "$(date +%s.%N) - $s" | bc)
    done
    ratios+=("$(echo "scale=4; ${t[after]} / ${t[before]}" | bc)")
    echo "$g round $r before ${t[before]} s after ${t[after]} s"
  done
  med=$(printf '%s\n' "${ratios[@]}" | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
  echo "$g ratios ${ratios[*]} median $med"
done

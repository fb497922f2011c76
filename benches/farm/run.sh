#!/usr/bin/env bash
# Farm overheads, whole processes, one sitting, rounds alternating their order:
#  - per-task overhead: `render --frames N` of graphs/burning-cube.ron alone (process start, graph
#    load, the fire-spread simulation up to frame N with nothing cached) for N = 0 and 47;
#  - one process rendering frames 0-47 against `openjd run` of the same job cut into 4 tasks
#    (one local session runs its tasks one after another), and against two such sessions at
#    once, each running 2 of the 4 tasks (two workers sharing this machine).
# Every variant's frames are compared with the single process's (cmp) each round.
#   OPENJD=path/to/openjd ROUNDS=7 benches/farm/run.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
bin="$root/target/release/pyrograph"
openjd="${OPENJD:-openjd}"
rounds="${ROUNDS:-7}"
graph="$root/graphs/burning-cube.ron"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }
"$bin" job "$graph" --out "$work/farm" --frames 0-47 --chunk 12 -o "$work/job" >/dev/null
params="file://$work/job/job_params.yaml"
declare -A sum
for r in $(seq 1 "$rounds"); do
  order="single frame0 frame47 openjd4 openjd2x2"
  [ $((r % 2)) -eq 0 ] && order="openjd2x2 openjd4 frame47 frame0 single"
  declare -A t
  for v in $order; do
    rm -rf "$work/out" "$work/farm"
    s=$(now)
    case $v in
      single) "$bin" render "$graph" --out "$work/single" --frames 0-47 --overwrite >/dev/null ;;
      frame0) "$bin" render "$graph" --out "$work/out" --frames 0 >/dev/null ;;
      frame47) "$bin" render "$graph" --out "$work/out" --frames 47 >/dev/null ;;
      openjd4) "$openjd" run "$work/job/template.yaml" --step Render -p "$params" >/dev/null ;;
      openjd2x2)
        "$openjd" run "$work/job/template.yaml" --step Render -p "$params" --tasks '[{"Frame": "0-11"}, {"Frame": "24-35"}]' >/dev/null &
        "$openjd" run "$work/job/template.yaml" --step Render -p "$params" --tasks '[{"Frame": "12-23"}, {"Frame": "36-47"}]' >/dev/null
        wait ;;
    esac
    t[$v]=$(echo "$(now) - $s" | bc)
    if [[ $v == openjd* ]]; then
      diff -r -x .pyrograph-job "$work/single" "$work/farm" >/dev/null || { echo "round $r $v: frames differ from the single render"; exit 1; }
    fi
  done
  echo "round $r: single ${t[single]} frame0 ${t[frame0]} frame47 ${t[frame47]} openjd4 ${t[openjd4]} openjd2x2 ${t[openjd2x2]}" \
    "ratios openjd4/single $(echo "scale=3; ${t[openjd4]} / ${t[single]}" | bc) openjd2x2/single $(echo "scale=3; ${t[openjd2x2]} / ${t[single]}" | bc)"
done

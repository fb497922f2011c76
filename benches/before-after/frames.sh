#!/usr/bin/env bash
# Do two pyrograph binaries (a refactor's before and after) cook the same bytes? Renders every
# shipped graph (graphs/*.ron, graphs/readme/*.ron) and cooks every preset's thumbnail (graphs/presets)
# with each binary, then compares every file written, byte for byte. Exits 1 on any difference,
# naming the files; prints how many files and graphs agreed.
#   BEFORE=/path/to/old/pyrograph AFTER=target/debug/pyrograph benches/before-after/frames.sh
#   FRAMES=0-11 limits each render to those frames (whole-clip nodes still read their whole clips).
#   KEEP=DIR keeps the renders in DIR; with SKIP_RENDER=1 as well, only compares what DIR holds.
#   BEFORE_ROOT=DIR renders the before side from another checkout's graphs (a change that migrates
#   graph files: `git worktree add /tmp/old <commit>`); graphs that checkout lacks are new, and skipped.
# OpenEXR files are compared by their pixels when their bytes differ: binaries before 2026-11-27
# let the exr crate compress chunks in parallel and write them in the order they finished (the
# offset table says where each is), so two runs of one such binary wrote the same pixels in
# different byte orders. That needs Python with numpy and OpenEXR (PYTHON, default python3;
# `pip install OpenEXR numpy`).
# Needs PYROGRAPH_FOOTAGE for the footage graphs (default: ../shared/footage beside the checkout).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
: "${BEFORE:?set BEFORE to the old binary}"
AFTER="${AFTER:-$root/target/release/pyrograph}"
export PYROGRAPH_FOOTAGE="${PYROGRAPH_FOOTAGE:-$(cd "$root/../shared/footage" && pwd)}"
out="${KEEP:-$(mktemp -d)}"
mkdir -p "$out"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$out"' EXIT
frames=()
[ -n "${FRAMES:-}" ] && frames=(--frames "$FRAMES")

failed=0
cd "$root"
graphs=$(ls graphs/*.ron graphs/readme/*.ron | wc -l)
before_root="${BEFORE_ROOT:-$root}"
[ -n "${SKIP_RENDER:-}" ] || for g in graphs/*.ron graphs/readme/*.ron; do
  name="$(basename "$(dirname "$g")")-$(basename "$g" .ron)"
  if [ ! -e "$before_root/$g" ]; then
    echo "new graph, not compared: $g"; graphs=$((graphs - 1)); continue
  fi
  for side in before after; do
    bin="$BEFORE"; dir="$before_root"; [ "$side" = after ] && { bin="$AFTER"; dir="$root"; }
    if ! (cd "$dir" && "$bin" render "$g" --out "$out/$side/$name" "${frames[@]}") >"$out/$side-$name.log" 2>&1; then
      echo "$side: $g failed to render:"; tail -n 3 "$out/$side-$name.log"; failed=1
    fi
  done
done
[ -n "${SKIP_RENDER:-}" ] || for side in before after; do
  bin="$BEFORE"; dir="$before_root"; [ "$side" = after ] && { bin="$AFTER"; dir="$root"; }
  (cd "$dir" && "$bin" presets --dir graphs/presets --thumbnails --out "$out/$side/thumbs") >"$out/$side-thumbs.log" 2>&1 \
    || { echo "$side: preset thumbnails failed:"; tail -n 3 "$out/$side-thumbs.log"; failed=1; }
done

# Every file either side wrote, with its hash; the two listings must be the same.
(cd "$out/before" && find . -type f -print0 | sort -z | xargs -0 sha256sum) >"$out/before.sums"
(cd "$out/after" && find . -type f -print0 | sort -z | xargs -0 sha256sum) >"$out/after.sums"
# Files whose bytes differ: EXR files whose pixels agree are only reordered (see above).
join -j 2 -o 1.1,2.1,0 <(sort -k2 "$out/before.sums") <(sort -k2 "$out/after.sums") | awk '$1 != $2 {print $3}' >"$out/changed.txt"
only=$(diff <(awk '{print $2}' "$out/before.sums") <(awk '{print $2}' "$out/after.sums") || true)
[ -z "$only" ] || { echo "files written by one side only:"; echo "$only"; failed=1; }
reordered=0
if [ -s "$out/changed.txt" ]; then
  verdict=$("${PYTHON:-python3}" - "$out" <<'PY'
import sys, pathlib
out = pathlib.Path(sys.argv[1])
try:
    import numpy as np, OpenEXR
except ImportError as e:
    print(f"cannot compare EXR pixels ({e}); install OpenEXR and numpy"); sys.exit(1)
def pixels(p):
    with OpenEXR.File(str(p)) as f:
        return {k: np.asarray(v.pixels) for k, v in f.channels().items()}
bad, same = [], 0
for name in (out / "changed.txt").read_text().split():
    a, b = out / "before" / name, out / "after" / name
    if name.endswith(".exr"):
        pa, pb = pixels(a), pixels(b)
        if pa.keys() == pb.keys() and all(np.array_equal(pa[k], pb[k]) for k in pa):
            same += 1
            continue
    bad.append(name)
print(same)
for n in bad:
    print("differs:", n)
sys.exit(1 if bad else 0)
PY
) || { echo "$verdict" | tail -n +2; failed=1; }
  reordered=$(echo "$verdict" | head -n 1)
fi
files=$(wc -l <"$out/after.sums")
echo "$graphs graphs and the preset thumbnails: $files files written by each binary ($reordered EXR files with equal pixels in another byte order), $( [ $failed = 0 ] && echo identical || echo NOT identical)"
exit $failed

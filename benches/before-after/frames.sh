#!/usr/bin/env bash
# Do two pyrograph binaries (a refactor's before and after) cook the same bytes? Renders every
# shipped graph (graphs/*.ron, graphs/readme/*.ron) and cooks every preset's thumbnail (graphs/presets)
# with each binary, then compares every file written, byte for byte. Exits 1 on any difference,
# naming the files; prints how many files and graphs agreed.
#   BEFORE=/path/to/old/pyrograph AFTER=target/debug/pyrograph benches/before-after/frames.sh
#   FRAMES=0-11 limits each render to those frames (whole-clip nodes still read their whole clips).
# Needs PYROGRAPH_FOOTAGE for the footage graphs (default: ../shared/footage beside the checkout).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
: "${BEFORE:?set BEFORE to the old binary}"
AFTER="${AFTER:-$root/target/release/pyrograph}"
export PYROGRAPH_FOOTAGE="${PYROGRAPH_FOOTAGE:-$(cd "$root/../shared/footage" && pwd)}"
out="${KEEP:-$(mktemp -d)}"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$out"' EXIT
frames=()
[ -n "${FRAMES:-}" ] && frames=(--frames "$FRAMES")

failed=0
graphs=0
cd "$root"
for g in graphs/*.ron graphs/readme/*.ron; do
  name="$(basename "$(dirname "$g")")-$(basename "$g" .ron)"
  for side in before after; do
    bin="$BEFORE"; [ "$side" = after ] && bin="$AFTER"
    if ! "$bin" render "$g" --out "$out/$side/$name" "${frames[@]}" >"$out/$side-$name.log" 2>&1; then
      echo "$side: $g failed to render:"; tail -n 3 "$out/$side-$name.log"; failed=1
    fi
  done
  graphs=$((graphs + 1))
done
for side in before after; do
  bin="$BEFORE"; [ "$side" = after ] && bin="$AFTER"
  "$bin" presets --dir graphs/presets --thumbnails --out "$out/$side/thumbs" >"$out/$side-thumbs.log" 2>&1 \
    || { echo "$side: preset thumbnails failed:"; tail -n 3 "$out/$side-thumbs.log"; failed=1; }
done

# Every file either side wrote, with its hash; the two listings must be the same.
(cd "$out/before" && find . -type f -print0 | sort -z | xargs -0 sha256sum) >"$out/before.sums"
(cd "$out/after" && find . -type f -print0 | sort -z | xargs -0 sha256sum) >"$out/after.sums"
if ! diff "$out/before.sums" "$out/after.sums" >"$out/diff.txt"; then
  echo "files that differ or exist on one side only:"; cat "$out/diff.txt"; failed=1
fi
files=$(wc -l <"$out/after.sums")
echo "$graphs graphs and the preset thumbnails: $files files written by each binary, $( [ $failed = 0 ] && echo identical || echo NOT identical)"
exit $failed

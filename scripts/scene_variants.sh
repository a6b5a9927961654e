#!/usr/bin/env bash
# Renders variants of every suite and held-out scene, for measuring a change beyond the
# scenes it was made on (BENCHMARKS.md). Hand-run only; no test or CI uses it.
#
#   scripts/scene_variants.sh sparse OUT   # each scene with a path walked at a spacing,
#                                          # at 2.5 and 4 times that spacing (3-12 stops)
#   scripts/scene_variants.sh draws OUT    # each scene with its seed + 100 and + 200
#
# Writes OUT/scenes/*.toml and OUT/data/<scene>_<variant>/ (`iasm simulate`); an existing
# data set is kept. `two_talkers_one_leaves` is left out of `sparse` (its talker's
# `at_stops` no longer fit). IASM names the binary (default: target/release/iasm). Then, e.g.:
#   iasm eval --dataset OUT/data/D --method gcc-phat --num 3 --runs 10 --json --threads 1
set -euo pipefail
kind=${1:?sparse or draws}; out=${2:?output folder}
cd "$(dirname "$0")/.."
iasm=${IASM:-target/release/iasm}
mkdir -p "$out/scenes" "$out/data"
# The scenes name their WAVs relative to their folder (../audio/...).
ln -sfn "$PWD/fixtures/audio" "$out/audio"
for f in fixtures/rooms/*.toml fixtures/heldout/*.toml; do
  n=$(basename "$f" .toml)
  case $kind in
    sparse)
      [ "$n" = two_talkers_one_leaves ] && continue
      grep -q '^spacing' "$f" || continue
      variants="x2.5 x4" ;;
    draws) variants="s100 s200" ;;
    *) echo "unknown kind: $kind" >&2; exit 2 ;;
  esac
  for v in $variants; do
    scene="$out/scenes/${n}_$v.toml"
    case $v in
      x*) awk -v m="${v#x}" '/^spacing[ \t]*=/ { split($0, a, "="); printf "spacing = %g\n", a[2] * m; next } { print }' "$f" > "$scene" ;;
      s*) awk -v k="${v#s}" '!done && /^seed[ \t]*=/ { split($0, a, "="); printf "seed = %d\n", a[2] + k; done = 1; next } { print }' "$f" > "$scene" ;;
    esac
    [ -d "$out/data/${n}_$v" ] || "$iasm" simulate "$scene" --out "$out/data/${n}_$v" > /dev/null
  done
done

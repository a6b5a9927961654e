#!/usr/bin/env bash
# The front end's time per recording beside pyroomacoustics', side by side in one run on
# one core (hand-run; BENCHMARKS.md). Each round runs pyroomacoustics' methods once, then
# iasm's methods on the default grid (13 elevations) and like for like (pyroomacoustics'
# grid and analysis: one elevation, 1024-point frames, one spectrum per recording, the same
# band). Prints every round's figures; take the medians.
#
#     scripts/ssl_beside_pra.sh DATASET_DIR [ROUNDS] [PYTHON]
set -euo pipefail
D="$1"; ROUNDS="${2:-3}"; PY="${3:-python3}"
cd "$(dirname "$0")/.."
IASM="${IASM:-target/release/iasm}"
LIKE="$(mktemp -d)/like.toml"
cat > "$LIKE" <<'TOML'
[ssl]
frame_len = 1024
hop = 512
block_frames = 100000
elevation = { min_deg = 0.0, max_deg = 0.0, step_deg = 10.0 }
TOML
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
for r in $(seq "$ROUNDS"); do
    echo "== round $r"
    taskset -c 0 "$PY" scripts/pra_baseline.py "$D" | sed 's/^/pyroomacoustics /'
    for m in gcc-phat mvdr srp-phat normmusic music tops; do
        for grid in default like; do
            args=(ssl --dataset "$D" --method "$m" --threads 1)
            [ "$grid" = like ] && args+=(--config "$LIKE")
            ms=$(taskset -c 0 "$IASM" "${args[@]}" 2>&1 >/dev/null | sed -n 's/.*(\([0-9.]*\) ms per recording).*/\1/p')
            echo "iasm $m $grid $ms ms per recording"
        done
    done
done

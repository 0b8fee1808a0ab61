#!/usr/bin/env bash
# Reproduces docs/results.md: the speed comparison on 7-Scenes (3 runs; the docs quote
# the median of the runs' per-frame medians) and the accuracy comparison on a noisy render of
# the Replica office0 mesh (the paper's Table III, extended with Open3D's TSDF), then the plots.
# Then the odometry peers of `bench --poses track`.
# Usage: scripts/results.sh [OUT_DIR]   (from the checkout, after building; ~60 min)
set -euo pipefail
VDMAP=${VDMAP:-build/bin/vdmap}
PLOT=${PLOT:-build/bin/plot_bench}
DATA=${DATA:-../shared/data}
OUT=${1:-results}
mkdir -p "$OUT"

# Speed: the first 100 frames of 7-Scenes RedKitchen, every method on the same decoded frames
# (OctoMap at 0.02 m takes ~1 s per frame: more frames make the run long, not the medians better).
speed() {
  for run in 1 2 3; do
    mkdir -p "$OUT/speed-$run"
    "$VDMAP" bench "$DATA/7scenes-redkitchen" --frames 0:100 --out "$OUT/speed-$run" > "$OUT/speed-$run/stdout.txt"
  done
}

# Accuracy: every 6th pose of the 2000-pose office0 trajectory (333 frames around the whole
# room), rendered at 640x480 with the 7-Scenes camera and Kinect noise (nguyen2012).
MESH="$DATA/replica-office0/reference/office0_mesh.ply"
awk 'NR % 6 == 1' "$DATA/replica-office0/reference/groundtruth_full_2000.txt" > "$OUT/office0_every6.txt"
rm -rf "$OUT/replica-seq"
"$VDMAP" synth --mesh "$MESH" --trajectory "$OUT/office0_every6.txt" --camera 7scenes --noise nguyen2012 \
  --out "$OUT/replica-seq"
# Every method on all 333 frames in one process (~15 min on one core; accuracy does not need
# repeats: the maps are deterministic).
accuracy() {
  mkdir -p "$OUT/accuracy"
  "$VDMAP" bench "$OUT/replica-seq" --frames 0:333 --mesh "$MESH" --accuracy-cell-sizes 3,5,9,15 \
    --out "$OUT/accuracy" > "$OUT/accuracy/stdout.txt"
}
# Both at once (the accuracy run's times are not quoted); set SEQUENTIAL=1 on a quiet machine.
# `wait PID` passes the speed runs' failure on (a bare `wait` returns 0).
if [ -n "${SEQUENTIAL:-}" ]; then speed; accuracy; else speed & speed_pid=$!; accuracy; wait "$speed_pid"; fi

# Tracking peers: the odometry peers of `bench --poses track` on 7-Scenes frames
# 0:500, 3 runs for the time medians (~7 CPU minutes each, most of it Open3D's odometry; OctoMap
# is skipped, it is timed in the speed runs). Alone, so the times are not disturbed.
for run in 1 2 3; do
  mkdir -p "$OUT/tracking-$run"
  "$VDMAP" bench "$DATA/7scenes-redkitchen" --frames 0:500 --poses track --no-octomap --out "$OUT/tracking-$run" \
    > "$OUT/tracking-$run/stdout.txt"
done
"$PLOT" --tracking "$OUT"/tracking-*/bench.json

# Tables (medians over the speed runs) and plots.
"$PLOT" --speed "$OUT"/speed-*/bench.json --accuracy "$OUT/accuracy/bench.json" --png-dir "$OUT"

#!/usr/bin/env bash
# Regenerate docs/figures/ (every figure of README.md and docs/) with the commands the docs show.
# Runs in a scratch folder with a copy of configs/; flow fields come from (and go to) the
# repository's cache, .fibersweep-cache/. About six minutes on two free cores with cached fields
# (the array sweeps: about three).
#   bash scripts/tools/make_figures.sh
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
out="$repo/docs/figures"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out" "$repo/.fibersweep-cache"
cp -rL "$repo/configs" "$work/configs"
ln -s "$repo/.fibersweep-cache" "$work/.fibersweep-cache"
cd "$work"
fs() { PYTHONPATH="$repo${PYTHONPATH:+:$PYTHONPATH}" python3 -m fibersweep "$@"; }

fs flow configs/quick.yaml --plot "$out/flow.png"
fs simulate configs/quick.yaml --theta0 -8 --y0 0.39 --length 1 --plot "$out/vault.png"
fs simulate configs/quick.yaml --theta0 8 --y0 0.30 --length 1 --plot "$out/trap.png"
fs run configs/quick.yaml
fs plot-phase results/quick -o "$out"
fs plot-tracks results/quick --where 'theta0 == -8' -o "$out/tracks.png"
fs animate results/quick --where 'theta0 == -8 and y0 == 0.39' -o "$out/vault.gif" --frames 60
fs run configs/quick.yaml 'sweep.y0={start: 0.01, stop: 0.8, num: 80}' -o results/dense
fs plot-phase results/dense -o "$work/dense"
cp "$work/dense/phase.png" "$out/phase_dense.png"
fs run configs/quick.yaml 'sweep.length=[0.6, 0.8, 1.0, 1.2]' -o results/lengths
fs plot-fractions results/lengths --by length -o "$out/fractions_length.png"
fs plot-delta results/lengths --by length -o "$out/delta_length.png"
fs run configs/friction_axis.yaml
fs plot-phase results/friction_axis -o "$work/friction"
cp "$work/friction/phase.png" "$out/phase_friction.png"
fs run configs/shapes.yaml
fs plot-phase results/shapes -o "$work/shapes"
cp "$work/shapes/phase.png" "$out/shapes_phase.png"
fs run configs/refine.yaml
fs plot-phase results/refine -o "$work/refine"
cp "$work/refine/phase.png" "$out/phase_refine.png"
fs run configs/array.yaml
fs sort-report results/array
cp results/array/figures/migration.png "$out/array-migration.png"
cp results/array/figures/sort-tracks.png "$out/array-overlay.png"
# the row-shift design of docs/arrays.md, after the check (384 runs, three more cell fields)
fs run configs/array.yaml 'sweep.flow.array.shift=[0.1, 0.125, 0.15, 0.2]' \
  'sweep.length=[4, 8, 12, 16, 20, 24, 32, 40]' run.output=results/array-shift
fs sort-report results/array-shift --target-length 22
cp results/array-shift/figures/critical-shift.png "$out/array-critical-shift.png"
fs explore results/quick
# a screenshot of the explorer after a click (needs chromium, chromium-driver and selenium)
PYTHONPATH="$repo" python3 "$repo/scripts/tools/explore_screenshot.py" results/quick/explore.html \
  "$out/explore.png" --cls Pole-vaulting || echo "explore.png not made (no browser)" >&2
ls -l "$out"

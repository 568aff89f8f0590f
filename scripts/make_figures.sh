#!/usr/bin/env bash
# Regenerate docs/figures/ (every figure of README.md and docs/) with the commands the docs show.
# Runs in a scratch folder with a copy of configs/; flow fields come from (and go to) the
# repository's cache, .fibersweep-cache/. About two minutes on two free cores with cached fields.
#   bash scripts/make_figures.sh
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
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
fs run configs/friction_axis.yaml
fs plot-phase results/friction_axis -o "$work/friction"
cp "$work/friction/phase.png" "$out/phase_friction.png"
fs run configs/refine.yaml
fs plot-phase results/refine -o "$work/refine"
cp "$work/refine/phase.png" "$out/phase_refine.png"
ls -l "$out"

#!/bin/bash
# The band-pass study in one go, sized for a 16-core machine and about 9 minutes of wall time
# (docs/validation/bandpass.md, "The map"):
#   - the map at b = a: geometries G0 G1 G2 G4, five moduli 10-100 kPa, nine lengths
#     0.2-2.05 period_x, six starts per length (~5 200 CPU s expected), on CORES - 3 workers;
#   - the spacing check on the long side at 10 kPa: b = a (1 worker) against b = a/2
#     (2 workers), 8 starts at 100 and 128 µm (~100 and ~350 CPU s expected).
# Every part stops at DEADLINE seconds and is summarised from what it stored; running the
# script again into the same OUT resumes the runs.
#   bash scripts/studies/flexible/bandpass_full.sh [OUT]        (CORES=16 DEADLINE=500 by default)
set -u
OUT=${1:-results/bandpass}
CORES=${CORES:-16}
DEADLINE=${DEADLINE:-500}
MAP="python3 scripts/studies/flexible/bandpass_map.py"
LONG=(--geometries G0 --moduli 1e4 --fractions 1.25 1.6 --count 8)
mkdir -p "$OUT"
start=$(date +%s)
$MAP run "$OUT/map" --cores $((CORES - 3)) --deadline "$DEADLINE" --cache "$OUT/cache" \
    > "$OUT/map.log" 2>&1 &
$MAP run "$OUT/long-b0.5" "${LONG[@]}" --spacing 0.5 --cores 1 --deadline "$DEADLINE" \
    --cache "$OUT/cache" > "$OUT/long-b0.5.log" 2>&1 &
$MAP run "$OUT/long-b0.25" "${LONG[@]}" --spacing 0.25 --cores 2 --deadline "$DEADLINE" \
    --cache "$OUT/cache" > "$OUT/long-b0.25.log" 2>&1 &
wait
$MAP converge "$OUT/long-b0.5" "$OUT/long-b0.25" > "$OUT/converge.log" 2>&1
echo "wall $(( $(date +%s) - start )) s"
tail -n 40 "$OUT/map.log"
cat "$OUT/converge.log"

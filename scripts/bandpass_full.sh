#!/bin/bash
# The band-pass study in one go, sized for a 16-core machine and about 9 minutes of wall time
# (docs/validation/bandpass.md, "The map"):
#   - the map at b = a: geometries G0 G1 G2 G4, five moduli 10-100 kPa, nine lengths
#     0.2-2.05 period_x, six starts per length (~5 200 CPU s expected), on CORES - 3 workers;
#   - the spacing check at 31.6 kPa around the period: b = a (1 worker) against b = a/2
#     (2 workers), 16 starts at 60, 80, 100 µm (~110 and ~360 CPU s expected).
# Every part stops at DEADLINE seconds and is summarised from what it stored; running the
# script again into the same OUT resumes the runs.
#   bash scripts/bandpass_full.sh [OUT]        (CORES=16 DEADLINE=500 by default)
set -u
OUT=${1:-results/bandpass}
CORES=${CORES:-16}
DEADLINE=${DEADLINE:-500}
MAP="python3 scripts/bandpass_map.py"
C30=(--geometries G0 --moduli 3.16e4 --fractions 0.75 1.0 1.25 --count 16)
mkdir -p "$OUT"
start=$(date +%s)
$MAP run "$OUT/map" --cores $((CORES - 3)) --deadline "$DEADLINE" --cache "$OUT/cache" \
    > "$OUT/map.log" 2>&1 &
$MAP run "$OUT/c30-b0.5" "${C30[@]}" --spacing 0.5 --cores 1 --deadline "$DEADLINE" \
    --cache "$OUT/cache" > "$OUT/c30-b0.5.log" 2>&1 &
$MAP run "$OUT/c30-b0.25" "${C30[@]}" --spacing 0.25 --cores 2 --deadline "$DEADLINE" \
    --cache "$OUT/cache" > "$OUT/c30-b0.25.log" 2>&1 &
wait
$MAP converge "$OUT/c30-b0.5" "$OUT/c30-b0.25" > "$OUT/converge.log" 2>&1
echo "wall $(( $(date +%s) - start )) s"
tail -n 40 "$OUT/map.log"
cat "$OUT/converge.log"

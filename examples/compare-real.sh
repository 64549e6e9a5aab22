#!/usr/bin/env bash
# Is the simulation like the real receiver? Simulates the first hour of the IGS station NYA1
# (Ny-Alesund, a Trimble NetR9 on a choke ring, 2024-05-03) from its own broadcast ephemerides
# (examples/validation/nya1-realistic.yaml) and compares it with the station's real recording in
# ../shared/data: per signal, tracked-set overlap, code, phase and Doppler residuals and C/N0
# differences above 10 degrees (docs/validation.md explains the columns and the limits).
# Usage: examples/compare-real.sh [OUT]   (default out/compare-real; OUT/compare.json as well)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/compare-real}"
skytrace="${SKYTRACE:-build/bin/skytrace}"
data="${SKYTRACE_SHARED_DATA:-../shared/data}/real/nya1_2024124"
"$skytrace" run examples/validation/nya1-realistic.yaml --out "$out" --quiet --no-truth
"$skytrace" compare "$data/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx" "$out/obs.rnx" \
  --nav "$data/NYA100NOR_S_20241240000_01D_GN.rnx" --nav "$data/NYA100NOR_S_20241240000_01D_EN.rnx" \
  --min-elevation-deg 10 --json "$out/compare.json"

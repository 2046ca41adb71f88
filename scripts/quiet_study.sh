#!/usr/bin/env bash
# The 6-DoF runs of docs/derivations/quiet_stiffness.md section 2: each remedy on and off on the
# built-in scenes and on static presses and a slide written by scripts/quiet_study.py, measured by
# `quiet_study.py measure`. Usage: scripts/quiet_study.sh [OUT_DIR] (default /tmp/quiet_study);
# DENTSIM (default build/release/cli/dentsim), PY (default python3 with numpy) override.
# Prints one line per run: name, then the measures.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/quiet_study}
dentsim=${DENTSIM:-build/release/cli/dentsim}
py=${PY:-python3}
study=scripts/quiet_study.py
mkdir -p "$out"

run() {  # name scene-file
  "$dentsim" run "$2" --out "$out/$1" > "$out/$1.log" 2>&1 || { echo "$1: run failed"; cat "$out/$1.log"; return; }
  echo "$1 $("$py" "$study" measure "$out/$1")"
}

# The built-in scenes as section 2 measured them (K_tooth 12000 N/m, filter off: the gains before
# section 7 changed them).
for scene in probe probe-groove drill; do
  "$dentsim" run "$scene" --show \
    | "$py" "$study" patch tooth.k_tooth_n_per_m=12000 method.encoder_kalman=false > "$out/$scene.json"
  run "$scene" "$out/$scene.json"
  "$py" "$study" patch method.encoder_kalman=true < "$out/$scene.json" > "$out/$scene-kalman.json"
  run "$scene-kalman" "$out/$scene-kalman.json"
done

for k in 3000 6000 12000; do
  for press in 0.5 2; do
    "$py" "$study" scene --k "$k" --press "$press" > "$out/press-$k-$press.json"
    run "press-$k-$press" "$out/press-$k-$press.json"
    "$py" "$study" patch method.encoder_kalman=true < "$out/press-$k-$press.json" \
      > "$out/press-$k-$press-kalman.json"
    run "press-$k-$press-kalman" "$out/press-$k-$press-kalman.json"
  done
done
"$py" "$study" scene --k 3000 --quantize 0 > "$out/press-3000-0.5-exact.json"
run press-3000-0.5-exact "$out/press-3000-0.5-exact.json"
"$py" "$study" scene --k 3000 --slide > "$out/slide-3000.json"
run slide-3000 "$out/slide-3000.json"
"$py" "$study" patch method.encoder_kalman=true < "$out/slide-3000.json" > "$out/slide-3000-kalman.json"
run slide-3000-kalman "$out/slide-3000-kalman.json"

#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the embedded default
# (simulated Phantom, procedural molar, scripted hand; no device or data file needed). It writes
# its report, time series, plots and tooth pictures under out/ (or the directory given as $1).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
scripts/setup.sh
scripts/build.sh release dentsim
bin=build/release/cli/dentsim
"$bin" --help
mkdir -p "$out"
echo
echo "== main job: the dental simulator, built-in scene 'drill' (simulated Phantom Premium 1.5/6DoF,"
echo "   procedural molar, scripted hand, PMI + passive decomposition + momentum observer)"
"$bin" run drill --out "$out"
echo "report: $out/report.json (plots and tooth pictures beside it)"

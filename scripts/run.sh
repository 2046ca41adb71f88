#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the embedded default
# (no device attached, no data files needed). It writes its report under out/ (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
scripts/setup.sh
scripts/build.sh release dentsim
bin=build/release/cli/dentsim
"$bin" --help
mkdir -p "$out"
echo
echo "== main job: reference pipeline demo (rigid-body device, hand pressing on a stiff wall)"
"$bin" demo --json "$out/demo.json"
echo "report: $out/demo.json"

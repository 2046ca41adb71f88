#!/usr/bin/env bash
# Issue #29's static-press and sliding targets on the simulated Phantom as dentsim runs by default
# (quantised encoders, fast pipeline, pmi-pd with the grip detector, the hand's mass and the
# encoder Kalman filter, saturation_passive on): the static presses and slides of
# scripts/quiet_study.py (the procedural molar, a grip hand holding 0.5 / 1 / 2 N for 2.5 s) at
# K_tooth 3000 and 6000 N/m, on the "sdf" and the smooth "field" tooth, measured by the run
# report's own quiet measures (report.json `quiet.phases[0]`, sim/quiet_measures.h).
# Usage: scripts/quiet_targets.sh [OUT_DIR]   (default /tmp/quiet_targets; 16 runs, ~1 min)
# DENTSIM (default build/release/cli/dentsim) and PY (default /usr/bin/python3, with numpy)
# override. Prints one table row per run (docs/derivations/quiet_stiffness.md section 9).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/quiet_targets}
dentsim=${DENTSIM:-build/release/cli/dentsim}
py=${PY:-/usr/bin/python3}
study=scripts/quiet_study.py
[ -x "$dentsim" ] || { echo "quiet_targets.sh: $dentsim not found (build it: scripts/build.sh release dentsim)" >&2; exit 2; }
mkdir -p "$out"
echo "| run | K_tooth [N/m] | model | press [N] | mean contact force [N] | contact / device ripple [%] | contact fraction | losses | oscillation [quanta] | static stiffness [N/m] | observer RMS error [N] | quiet |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for kind in press slide; do
  for model in sdf field; do
    [ "$kind" = press ] && [ "$model" = field ] && continue  # a press sits on one point: sdf = field there
    for k in 3000 6000; do
      for f in 0.5 1 2; do
        name="$kind-$model-$k-$f"
        extra=()
        [ "$kind" = slide ] && extra=(--slide)
        "$py" "$study" scene --k "$k" --press "$f" "${extra[@]}" \
          | "$py" "$study" patch method.encoder_kalman=true method.saturation_passive=true \
                  "tooth.contact_model=\"$model\"" > "$out/$name.json"
        if ! nice "$dentsim" run "$out/$name.json" --out "$out/$name" > "$out/$name.log" 2>&1; then
          echo "| $name | run failed: see $out/$name.log |"
          continue
        fi
        "$py" - "$out/$name/report.json" "$kind" "$model" "$k" "$f" <<'EOF'
import json, sys
path, kind, model, k, f = sys.argv[1:]
q = json.load(open(path))["quiet"]
if not q["phases"]:
    print(f"| {kind} | {k} | {model} | {f} | no steady contact phase |")
    sys.exit(0)
p = q["phases"][0]
pct = lambda key: f"{100 * p[key]:.1f}" if key in p else "-"
stiff = f"{p['static_stiffness_n_per_m']:.0f}" if "static_stiffness_n_per_m" in p else "-"
obs = f"{p['observer_rms_error_n']:.3f}" if "observer_rms_error_n" in p else "-"
print(f"| {kind} | {k} | {model} | {f} | {p['mean_contact_force_n']:.2f} | "
      f"{pct('ripple_contact_force')} / {pct('ripple_device_force')} | {p['contact_fraction']:.3f} | "
      f"{p['contact_losses']} | {p['oscillation_amplitude_quanta']:.2f} | {stiff} | {obs} | "
      f"{'yes' if p['quiet'] else 'no'} |")
EOF
      done
    done
  done
done

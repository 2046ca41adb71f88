#!/usr/bin/env python3
"""Calibration on seeded held-out perturbations of the default simulated Phantom (issue #17).

For each seed: the default model (`dentsim device show`) with every body's mass and inertia, and
each joint's armature, damping and Coulomb friction scaled by U(0.75, 1.35) (Python's seeded
random); `dentsim excite` on that device (MuJoCo's frictionloss, quantised encoders, the driver's
velocity estimate); `dentsim calibrate --truth` with the model-mismatch term and without it
(`--no-model-mismatch`). Prints one line per fit and the summary table of docs/calibration.md:
identifiable parameters checked, those outside both 5 % and 3 reported std, the fitted M(q)
error against the truth.

Superseded by `dentsim calibrate-seeds` (calibration/seeds.h; docs/calibration.md), which runs
the same chain in C++ and spreads the seeds over MPI ranks. Its perturbation draws from
std::mt19937_64, not Python's random, so seed S is a different device there and here: this script
stays only to re-run the table docs/calibration.md measured with it.

Usage: scripts/calibration_seeds.py [--dentsim build/release/cli/dentsim] [--first 1]
                                    [--count 20] [--out /tmp/dentsim_calibration_seeds]
"""
import argparse
import json
import os
import random
import statistics
import subprocess
import sys

GIMBAL_COULOMB = ("coulomb_n_m.4", "coulomb_n_m.5", "coulomb_n_m.6")


def perturbed(base, seed):
    rng = random.Random(seed)
    m = json.loads(json.dumps(base))
    for body in m["bodies"].values():
        body["mass_kg"] *= rng.uniform(0.75, 1.35)
        s = rng.uniform(0.75, 1.35)
        body["inertia_kg_m2"] = [x * s for x in body["inertia_kg_m2"]]
    for key in ("armature_kg_m2", "damping_n_m_s_per_rad", "coulomb_n_m"):
        m["joints"][key] = [x * rng.uniform(0.75, 1.35) for x in m["joints"][key]]
    m["name"] = "perturbed default Phantom, seed %d" % seed
    return m


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dentsim", default="build/release/cli/dentsim")
    ap.add_argument("--first", type=int, default=1)
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--out", default="/tmp/dentsim_calibration_seeds")
    a = ap.parse_args()
    if a.count < 1:
        sys.exit("calibration_seeds.py: --count must be >= 1")
    status, text = run([a.dentsim, "device", "show"])
    if status != 0:
        sys.exit("calibration_seeds.py: `%s device show` failed:\n%s" % (a.dentsim, text))
    base = json.loads(text)
    stats = {tag: {"runs": 0, "checked": 0, "outside": 0, "outside_gimbal": 0, "M": [],
                   "mismatch": 0} for tag in ("without", "with")}
    for seed in range(a.first, a.first + a.count):
        d = os.path.join(a.out, "seed%d" % seed)
        os.makedirs(d, exist_ok=True)
        truth = os.path.join(d, "truth.json")
        with open(truth, "w") as f:
            json.dump(perturbed(base, seed), f, indent=1)
        log = os.path.join(d, "log.csv")
        status, text = run([a.dentsim, "excite", "--device", truth, "-o", log, "--duration", "20",
                            "--seed", str(seed)])
        if status != 0:
            print("seed %d: excite failed: %s" % (seed, text.strip()[-300:]), flush=True)
            continue
        for tag, extra in (("with", []), ("without", ["--no-model-mismatch"])):
            fit = os.path.join(d, "fit_%s.json" % tag)
            status, text = run([a.dentsim, "calibrate", log, "--truth", truth, "--json", fit, "-o",
                                os.path.join(d, "model_%s.json" % tag)] + extra)
            if status not in (0, 1) or not os.path.exists(fit):
                print("seed %d: calibrate failed: %s" % (seed, text.strip()[-300:]), flush=True)
                continue
            with open(fit) as f:
                j = json.load(f)
            st = stats[tag]
            st["runs"] += 1
            st["M"].append(j["truth_model_error"]["fitted"]["mass_matrix"])
            st["mismatch"] += bool(j["model_mismatch"])
            bad = []
            for p in j["parameters"]:
                if not p["identifiable"] or "rel_error" not in p:
                    continue
                st["checked"] += 1
                if p["rel_error"] > 0.05 and p["error_over_std"] > 3.0:
                    st["outside"] += 1
                    st["outside_gimbal"] += p["name"] in GIMBAL_COULOMB
                    bad.append("%s %.0f %% (%.1f std)" % (p["name"], 100 * p["rel_error"],
                                                          p["error_over_std"]))
            print("seed %d, %s the model-mismatch term: %d identifiable, M(q) error %.2f %%, "
                  "outside 5 %% and 3 std: %s" % (seed, tag, j["identifiable_count"],
                                                   100 * st["M"][-1], ", ".join(bad) or "none"),
                  flush=True)
    print()
    print("| std reported | fits | identifiable parameters checked | outside 5 % and 3 std "
          "| of which gimbal Coulomb | fitted M(q) error median / max | M(q) within 2 % "
          "| model_mismatch flagged |")
    print("|---|---|---|---|---|---|---|---|")
    for tag in ("without", "with"):
        st = stats[tag]
        if not st["runs"]:
            continue
        print("| %s the model-mismatch term | %d | %d | %d | %d | %.2f %% / %.2f %% | %d | %d |" % (
            "statistical (Newey-West), without" if tag == "without" else "total, with", st["runs"],
            st["checked"], st["outside"], st["outside_gimbal"], 100 * statistics.median(st["M"]),
            100 * max(st["M"]), sum(m <= 0.02 for m in st["M"]), st["mismatch"]))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The quiet-stiffness study of docs/derivations/quiet_stiffness.md (issue #29, items 2-3).

Two jobs, both small and dependency-light (python3 + numpy):

  quiet_study.py scene [--k N/M] [--quantize 0|1] [--press N] [--preset NAME] [--slide]
                       [--friction MU] [--method-extra JSON] > scene.json
      writes a static-press (or slide) scene on the procedural molar: approach 0-1 s, press down
      to the anchor 1.0-1.5 s, hold 1.5-4.0 s (phase "press"; with --slide the hand moves 3 mm
      along x meanwhile, phase "slide"), retract 4.0-4.5 s. The hand's reference sits on the
      anchor (the surface), so the press is the feed-forward force.

  quiet_study.py patch KEY=VALUE ... < scene.json > variant.json
      sets dotted keys of a scene (VALUE is JSON), e.g.
      `dentsim run probe --show | quiet_study.py patch method.encoder_kalman=true`
      (a list element by its index: hand.script.2.force_n='[0, 0, -3]')

  quiet_study.py measure DIR [--from S] [--to S] [--json] [--detail]
      reads DIR/timeseries.csv of `dentsim run SCENE --out DIR` and prints the quiet measures
      over the window [from, to] (default: the press/slide/probe phase minus its first 0.5 s):
        ripple_contact   RMS(F - F averaged over 0.1 s) / mean F, F the contact force
        ripple_device    the same for the force on the device (what the hand feels)
        contact_fraction ticks with a contact / ticks in the window
        losses           contact -> no-contact transitions in the window
        k_static         mean contact force / mean device penetration [N/m]
        free_rms         RMS force on the device over ticks without contact before the
                         window, while the hand moves (0.2 s to the first contact) [N]
      These are this study's own measures; the run report's (device/quiet_measures.h) are the
      product's.

  quiet_study.py gains DENTSIM OUT [--scenes NAME ...] [--k N/M ...] [--kalman 0 1]
      the built-in scenes' gains (docs/derivations/quiet_stiffness.md section 7): runs each
      built-in scene (`DENTSIM run NAME --show`) with tooth.k_tooth_n_per_m = K and
      method.encoder_kalman on/off for every candidate, measures each run from its report.json
      (the run report's quiet measures, sim/quiet_measures.h: the issue's measures), and picks per scene by one rule (RULE below), the same for every scene. Prints one JSON line per
      run and one per scene with the pick. --reuse: measure OUT/TAG/report.json where present.

RULE (`gains`): a candidate is quiet when both ripples <= 5 %, contact on every tick of the
window, no loss, free RMS <= 0.03 N and no fault (issue #29's targets). The pick is the stiffest
quiet candidate; when none is quiet, the candidate that fails the fewest of those five criteria,
then has the fewest losses, then the smallest worst ripple (contact or device), ties to the
stiffer. Among equal K the same order decides between the filter on and off.
"""
import argparse
import csv
import json
import sys

import numpy as np


def scene(args):
    method = {"name": "pmi-pd", "k_vc_n_per_m": 1200, "b_vc_n_s_per_m": 4,
              "k_vc_ang_n_m_per_rad": 0.3, "b_vc_ang_n_m_s_per_rad": 0.001,
              "observer_gain_per_s": 30, "friction_mu": args.friction,
              "grasp_mass_scale": 1.0, "grip_detector": True}
    if args.method_extra:
        method.update(json.loads(args.method_extra))
    f = -abs(args.press)
    x_end = 3.0 if args.slide else 0.0
    hold = "slide" if args.slide else "press"
    doc = {
        "dentsim_scene": 1,
        "name": "quiet-study",
        "description": "Static press (or slide) on the molar for the quiet-stiffness study.",
        "duration_s": 4.5,
        "tick_hz": 1000,
        "tooth": {"source": "procedural", "resolution": 128, "k_tooth_n_per_m": args.k,
                  "b_tooth_n_s_per_m": args.b_tooth, "anchor_offset_mm": [0, 0, -6],
                  "contact_model": "sdf"},
        "tool": {"preset": args.preset, "bur_radius_mm": 0.4, "bur_speed_rpm": 0},
        "device": {"type": "simulated-phantom", "jitter_us": 0, "quantize": bool(args.quantize),
                   "saturate": True},
        "method": method,
        "proxy": {"mass_kg": 0.05, "inertia_kg_m2": 1e-5, "damping_n_s_per_m": 0.0,
                  "damping_ang_n_m_s_per_rad": 0.0},
        "hand": {"script": [
            {"t_s": 0.0, "offset_mm": [0, 0, 6], "force_n": [0, 0, 0], "phase": "approach"},
            {"t_s": 1.0, "offset_mm": [0, 0, 1], "force_n": [0, 0, 0], "phase": "approach"},
            {"t_s": 1.5, "offset_mm": [0, 0, 0], "force_n": [0, 0, f], "phase": hold},
            {"t_s": 4.0, "offset_mm": [x_end, 0, 0], "force_n": [0, 0, f], "phase": hold},
            {"t_s": 4.5, "offset_mm": [x_end, 0, 6], "force_n": [0, 0, 0], "phase": "retract"},
        ]},
    }
    json.dump(doc, sys.stdout, indent=1)
    sys.stdout.write("\n")


def patch(args):
    doc = json.load(sys.stdin)
    for kv in args.set:
        key, value = kv.split("=", 1)
        node = doc
        parts = key.split(".")
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node[p]
        last = parts[-1]
        node[int(last) if isinstance(node, list) else last] = json.loads(value)
    json.dump(doc, sys.stdout, indent=1)
    sys.stdout.write("\n")


def read_series(path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    cols = {}
    for k in rows[0]:
        if k == "phase":
            cols[k] = np.array([r[k] for r in rows])
        else:
            cols[k] = np.array([float(r[k]) for r in rows])
    return cols


def ripple(x, n_avg):
    """RMS of x minus its centred moving average over n_avg ticks, over the mean of x."""
    if len(x) <= n_avg:
        return float("nan")
    kern = np.ones(n_avg) / n_avg
    avg = np.convolve(x, kern, mode="valid")
    half = n_avg // 2
    core = x[half:half + len(avg)]
    mean = np.mean(core)
    return float(np.sqrt(np.mean((core - avg) ** 2)) / mean) if mean > 0 else float("nan")


def report_faults(d):
    try:
        with open(d + "/report.json") as fh:
            rep = json.load(fh)
    except (OSError, ValueError):
        return []
    f = rep.get("faults", [])
    return [x if isinstance(x, str) else json.dumps(x) for x in f] if isinstance(f, list) else [str(f)]


def measure(args):
    out = measure_dict(args)
    if args.json:
        print(json.dumps(out))
    else:
        print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                       for k, v in out.items() if k != "window_s"))


def measure_dict(args):
    s = read_series(args.dir + "/timeseries.csv")
    t = s["t_s"]
    dt = float(np.median(np.diff(t)))
    if args.t_from is None:
        held = np.isin(s["phase"], ["press", "slide", "probe", "drill"])
        if not held.any():
            sys.exit("quiet_study: no press/slide/probe/drill phase in " + args.dir)
        t0 = t[held][0] + 0.5
        t1 = t[held][-1]
    else:
        t0, t1 = args.t_from, args.t_to
    w = (t >= t0) & (t <= t1)
    inc = s["contacts"][w] > 0
    fc = s["contact_force_n"][w]
    fd = s["device_force_n"][w]
    pen = s["device_penetration_m"][w]
    n_avg = int(round(0.1 / dt))
    first_contact = t[s["contacts"] > 0][0] if (s["contacts"] > 0).any() else t[-1]
    free = (t >= 0.2) & (t < first_contact - 0.05) & (s["contacts"] == 0)
    out = {
        "window_s": [float(t0), float(t1)],
        "ripple_contact": ripple(fc, n_avg),
        "ripple_device": ripple(fd, n_avg),
        "contact_fraction": float(np.mean(inc)),
        "losses": int(np.sum(inc[:-1] & ~inc[1:])),
        "mean_contact_force_n": float(np.mean(fc)),
        "k_static_n_per_m": float(np.mean(fc) / np.mean(pen)) if np.mean(pen) > 0 else float("nan"),
        "free_rms_n": float(np.sqrt(np.mean(s["device_force_n"][free] ** 2))) if free.any() else float("nan"),
        "energy_virtual_j": float(s["energy_virtual_j"][-1]),
        "hand_work_min_j": float(np.min(s["hand_work_j"])),
        # over the whole run (saturation, issue #29 section 6): the proxy's deepest penetration,
        # the largest contact force, and whether the run ended in a fault (report.json)
        "proxy_depth_max_m": float(np.max(s["penetration_m"])),
        "contact_force_max_n": float(np.max(s["contact_force_n"])),
        "faults": ",".join(report_faults(args.dir)) or "none",
    }
    if getattr(args, "detail", False):
        # section 8.4: what moves in the window: the RMS of the device's tip z [m] and orientation
        # [rad] about their 0.1 s centred moving average, and the frequency of the largest peak
        # (above 2 Hz) of the contact force's spectrum (Hann window)
        for k in ("device_z_m", "device_rx_rad", "device_ry_rad", "device_rz_rad"):
            x = s[k][w]
            avg = np.convolve(x, np.ones(n_avg) / n_avg, mode="valid")
            core = x[n_avg // 2:n_avg // 2 + len(avg)]
            out["fluct_" + k] = float(np.sqrt(np.mean((core - avg) ** 2)))
        x = fc - np.mean(fc)
        spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
        f = np.fft.rfftfreq(len(x), dt)
        sel = f > 2.0
        out["contact_force_peak_hz"] = float(f[sel][np.argmax(spec[sel])]) if sel.any() else float("nan")
    return out


QUIET_RIPPLE = 0.05
QUIET_FREE_RMS_N = 0.03


def failed_criteria(m):
    """The quiet criteria of RULE a measured run fails (a faulted run fails them all)."""
    if m.get("fault"):
        return ["fault"]
    bad = []
    for key in ("ripple_contact", "ripple_device"):
        if not (m[key] <= QUIET_RIPPLE):  # nan fails
            bad.append(key)
    if not (m["contact_fraction"] >= 1.0):
        bad.append("contact_fraction")
    if m["losses"] > 0:
        bad.append("losses")
    if not (m["free_rms_n"] <= QUIET_FREE_RMS_N):
        bad.append("free_rms")
    return bad


def pick(cands):
    """RULE: the stiffest quiet candidate, else the one failing the fewest criteria, then the
    fewest losses, then the smallest worst ripple, ties to the stiffer."""
    def worst(m):
        r = max(m.get("ripple_contact", float("nan")), m.get("ripple_device", float("nan")))
        return r if r == r else float("inf")
    quiet = [m for m in cands if not failed_criteria(m)]
    if quiet:
        return max(quiet, key=lambda m: (m["k"], -worst(m)))
    return min(cands, key=lambda m: (len(failed_criteria(m)), m.get("losses", 1 << 30), worst(m), -m["k"]))


def report_measures(rep):
    """RULE's measures from a run's report.json (the product's, sim/quiet_measures.h): over the
    scene's steady phases (from first contact + 0.3 s to the phase's last key) the worst ripple of
    the contact force and of the device force, the smallest contact fraction, the losses summed,
    the static stiffness (mean device force / mean device penetration, the first phase), and the
    free-space force the hand feels while moving."""
    q = rep["quiet"]
    ph = q["phases"]
    nan = float("nan")

    def worst(key):
        vals = [p[key] if p[key] is not None else nan for p in ph]
        return max(vals) if vals and all(v == v for v in vals) else nan
    return {
        "fault": bool(rep.get("faults")) or not ph,
        "ripple_contact": worst("ripple_contact_force"),
        "ripple_device": worst("ripple_device_force"),
        "contact_fraction": min(p["contact_fraction"] for p in ph) if ph else 0.0,
        "losses": sum(p["contact_losses"] for p in ph),
        "k_static_n_per_m": ph[0]["static_stiffness_n_per_m"] if ph else nan,
        "free_rms_n": q["free_space"]["moving_force_rms_n"],
        "still_pulses": q["free_space"]["still_pulses"],
        "energy_virtual_j": rep["virtual_energy_generated_j"],
        "rendered_stiffness_n_per_m": rep["rendered_stiffness_n_per_m"],
        "hand_work_min_j": rep["hand_work_min_j"],
        "passive_at_hand": rep["passive_at_hand"],
    }


def gains(args):
    import os
    import subprocess
    os.makedirs(args.out, exist_ok=True)
    for name in args.scenes:
        base = json.loads(subprocess.run([args.dentsim, "run", name, "--show"], check=True,
                                         capture_output=True, text=True).stdout)
        cands = []
        for k in args.k:
            for kal in args.kalman:
                doc = json.loads(json.dumps(base))
                doc["tooth"]["k_tooth_n_per_m"] = k
                doc["method"]["encoder_kalman"] = bool(kal)
                tag = f"{name}-k{int(k)}-kal{int(kal)}"
                path = os.path.join(args.out, tag + ".json")
                with open(path, "w") as fh:
                    json.dump(doc, fh, indent=1)
                run_dir = os.path.join(args.out, tag)
                rc = 0
                if not (args.reuse and os.path.exists(os.path.join(run_dir, "report.json"))):
                    rc = subprocess.run([args.dentsim, "run", path, "--out", run_dir],
                                        capture_output=True, text=True).returncode
                m = {"scene": name, "k": k, "kalman": bool(kal)}
                try:
                    with open(os.path.join(run_dir, "report.json")) as fh:
                        rep = json.load(fh)
                    m.update(report_measures(rep))
                    m["fault"] = m["fault"] or rc != 0
                except (OSError, ValueError, IndexError, KeyError, TypeError) as e:
                    m["fault"] = True
                    m["error"] = str(e)
                cands.append(m)
                print(json.dumps(m), flush=True)
        best = pick(cands)
        print(json.dumps({"scene": name, "pick": {"k": best["k"], "kalman": best["kalman"]},
                          "quiet": not failed_criteria(best),
                          "fails": failed_criteria(best)}), flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    sc = sub.add_parser("scene")
    sc.add_argument("--k", type=float, default=3000.0)
    sc.add_argument("--b-tooth", type=float, default=5.0)
    sc.add_argument("--quantize", type=int, default=1)
    sc.add_argument("--press", type=float, default=0.5)
    sc.add_argument("--preset", default="explorer")
    sc.add_argument("--slide", action="store_true")
    sc.add_argument("--friction", type=float, default=0.0)
    sc.add_argument("--method-extra", default="")
    pa = sub.add_parser("patch")
    pa.add_argument("set", nargs="+")
    me = sub.add_parser("measure")
    me.add_argument("dir")
    me.add_argument("--from", dest="t_from", type=float)
    me.add_argument("--to", dest="t_to", type=float)
    me.add_argument("--json", action="store_true")
    me.add_argument("--detail", action="store_true",
                    help="also the device's tip z and orientation fluctuation (RMS about the 0.1 s "
                         "average) and the contact force's spectral peak [Hz]")
    ga = sub.add_parser("gains")
    ga.add_argument("dentsim")
    ga.add_argument("out")
    ga.add_argument("--scenes", nargs="+", default=["probe", "probe-groove", "drill"])
    ga.add_argument("--k", nargs="+", type=float, default=[3000.0, 4500.0, 6000.0, 12000.0])
    ga.add_argument("--kalman", nargs="+", type=int, default=[0, 1])
    ga.add_argument("--reuse", action="store_true", help="measure OUT/TAG/report.json if present")
    a = p.parse_args()
    if a.cmd == "scene":
        scene(a)
    elif a.cmd == "patch":
        patch(a)
    elif a.cmd == "gains":
        gains(a)
    else:
        measure(a)


if __name__ == "__main__":
    main()

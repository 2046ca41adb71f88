#!/usr/bin/env python3
"""Quiet Z-width tables from `dentsim zwidth --json` files (issue #29; docs/results/zwidth.md).

Usage:
  scripts/zwidth_quiet_table.py summary A.json [B.json ...]   # one row per file and method
  scripts/zwidth_quiet_table.py points A.json [--method pmi-pd] [--operator grip]
  dentsim device show > dev.json; scripts/zwidth_quiet_table.py tap-bound dev.json [F_SAT ...]

`summary`: per file (its device's tip quantum, filter on/off, observer gain), per method, the quiet
Z-width under each operator with its gains, and the quiet ratio pmi-pd / explicit of that file
(both methods on the same device). `points`: every grid point of one method and operator with its
runs' contact / device ripple [%], contact losses, static stiffness and Z-width (tap: one entry
per approach speed), and the point's verdict. `tap-bound`: the largest tap Z-width any method
and any sensor can score on the Phantom testbed (docs/zwidth_protocol.md: start pose q0 = 0, push
1 N, gap 0.5 mm, hand m_h 0.554 kg, B_h 6.45 N s/m, K_h 135 N/m, tap speeds 0.05 / 0.15 / 0.3 m/s):
the force fed back is at most F_sat = tau_max(q2) / l1 along z at q0 (a pure z motion there turns
q2 alone), so max f / max p <= F_sat / p_lb, p_lb the tap's penetration when the device resists
with F_sat plus its friction and damping from the first contact on (the hand on a tool of mass
m_d: 0, 0.12 kg, the model's mass along z at q0 (docs/derivations/quiet_stiffness.md section 10),
and 0.2 kg; the largest of the three bounds is the one to use). Optional F_SAT values [N] replace
the file's, to find the force that would reach a Z-width. A file with "torque_limit": {"model":
"thermal"} is bounded by its peak torque instead (the simulated device's clamp then). Standard
library only.
"""
import json
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def quiet_of(d, method, op):
    m = d["methods"].get(method)
    if m is None:
        return None, None
    o = m["operators"].get(op)
    if o is None:
        return None, None
    z = o.get("quiet_z_width_n_per_m") or 0.0
    g = o.get("quiet_gains") or {}
    return z, g


def gains_str(g):
    if not g:
        return "-"
    return "(%g, %g, %g)" % (g["k_vc_n_per_m"], g["b_vc_n_s_per_m"], g["k_tooth_n_per_m"])


def summary(paths):
    print("| file | tip quantum [mm] | filter | L [1/s] | method | quiet Z-width `grip` (point) | "
          "quiet Z-width `tap` (point) |")
    print("|---|---|---|---|---|---|---|")
    ratios = []
    for p in paths:
        d = load(p)
        tq = d.get("device_tip_quantum_m", 0.0) * 1e3
        filt = "on" if d.get("encoder_kalman") else "off"
        L = d.get("observer_gain_per_s")
        per = {}
        for method in ("explicit", "pmi", "pmi-pd"):
            if method not in d["methods"]:
                continue
            cells = []
            for op in ("grip", "tap"):
                z, g = quiet_of(d, method, op)
                per[(method, op)] = z
                cells.append("none" if not z else "%.0f %s" % (z, gains_str(g)))
            print("| %s | %.4f | %s | %g | %s | %s | %s |" % (p, tq, filt, L, method, *cells))
        r = []
        for op in ("grip", "tap"):
            e, q = per.get(("explicit", op)), per.get(("pmi-pd", op))
            r.append("%.2f" % (q / e) if e and q else "-")
        ratios.append((p, r))
    print()
    print("| file | quiet ratio pmi-pd / explicit `grip` | `tap` |")
    print("|---|---|---|")
    for p, r in ratios:
        print("| %s | %s | %s |" % (p, r[0], r[1]))


def points(path, method, op):
    d = load(path)
    o = d["methods"][method]["operators"][op]
    print("| (K_vc, b_vc, K_tooth) | contact / device ripple [%], losses per run | static stiffness "
          "[N/m] | Z-width [N/m] | stable, passive | quiet |")
    print("|---|---|---|---|---|---|")
    for pt in o["points"]:
        runs = pt["runs"]
        rip = "; ".join("%.1f / %.1f / %d" % (100 * r["ripple_contact_force"],
                                              100 * r["ripple_device_force"], r["contact_losses"])
                        for r in runs)
        st = "/".join("%.0f" % r["quiet_static_stiffness_n_per_m"] for r in runs)
        zw = "/".join("%.0f" % r["z_width_n_per_m"] for r in runs)
        print("| (%g, %g, %g) | %s | %s | %s | %s | %s |" % (
            pt["k_vc_n_per_m"], pt["b_vc_n_s_per_m"], pt["k_tooth_n_per_m"], rip, st, zw,
            "yes" if pt["stable"] and pt["passive"] else "no", "yes" if pt["quiet"] else "no"))


def tap_penetration_lb(f_sat, f_fric, b_tip, v, m_d=0.0, m_h=0.554, b_h=6.45, k_h=135.0, gap=0.5e-3,
                       push=1.0, dt=2e-6):
    """Max penetration [m] of the hand on a tool of mass m_d resisted by f_sat + f_fric + b_tip v."""
    m = m_h + m_d
    target = gap + push / k_h
    t = x = xd = pmax = 0.0
    while t < 2.0:
        moving = v * t < target
        xr, vr = (v * t, v) if moving else (target, 0.0)
        p = x - gap
        fd = (f_sat + f_fric + b_tip * max(xd, 0.0)) if p > 0.0 else 0.0
        xd += dt * (k_h * (xr - x) + b_h * (vr - xd) - fd) / m
        x += dt * xd
        t += dt
        pmax = max(pmax, x - gap)
        if not moving and xd < 0.0:
            break
    return pmax


def tap_bound(path, f_sats):
    d = load(path)
    l1 = d["arm"]["l1_m"]
    j = d["joints"]
    f_file = j["torque_limit_n_m"][1] / l1
    tl = d.get("torque_limit") or {}
    if tl.get("model") == "thermal":
        # The thermal torque limit: the clamp is the motors' peak (the winding's limit is seconds
        # away at the peak, a tap's impact lasts ~0.1 s), so the peak bounds the force along z.
        print("torque_limit thermal: F_sat at the peak = %.3f N m / %.3f m = %.3f N (continuous "
              "%.3f N m: %.3f N; the file's clamp %.3f N)" % (
                  tl["peak_n_m"][1], l1, tl["peak_n_m"][1] / l1, tl["continuous_n_m"][1],
                  tl["continuous_n_m"][1] / l1, f_file))
        f_file = tl["peak_n_m"][1] / l1
    f_fric = j["coulomb_n_m"][1] / l1
    b_tip = j["damping_n_m_s_per_rad"][1] / l1 ** 2
    print("F_sat = tau_max(q2) / l1 = %.3f N m / %.3f m = %.3f N along z at q0; friction %.1f mN, "
          "damping %.4f N s/m at the tip" % (f_file * l1, l1, f_file, 1e3 * f_fric, b_tip))
    print("| F_sat [N] | tap speed [m/s] | max penetration >= [mm] at m_d 0 / 0.12 / 0.2 kg | "
          "tap Z-width <= [N/m] (the largest) |")
    print("|---|---|---|---|")
    for f in ([f_file] + [float(x) for x in f_sats]):
        for v in (0.05, 0.15, 0.3):
            ps = [tap_penetration_lb(f, f_fric, b_tip, v, m_d) for m_d in (0.0, 0.12, 0.2)]
            print("| %.3f | %.2f | %s | %.0f |" % (f, v, " / ".join("%.3f" % (1e3 * p) for p in ps),
                                                   f / min(ps)))


def main(argv):
    if len(argv) >= 3 and argv[1] == "tap-bound":
        try:
            tap_bound(argv[2], argv[3:])
        except (OSError, ValueError, KeyError, IndexError) as e:
            print("zwidth_quiet_table.py: %s: %s" % (argv[2], e), file=sys.stderr)
            return 2
        return 0
    if len(argv) < 3 or argv[1] not in ("summary", "points"):
        print("usage: zwidth_quiet_table.py summary A.json [B.json ...] | "
              "points A.json [--method M] [--operator OP] | tap-bound DEVICE.json [F_SAT ...]",
              file=sys.stderr)
        return 2
    try:
        if argv[1] == "summary":
            summary(argv[2:])
        else:
            method, op, path = "pmi-pd", "grip", None
            it = iter(argv[2:])
            for a in it:
                if a == "--method":
                    method = next(it)
                elif a == "--operator":
                    op = next(it)
                else:
                    path = a
            points(path, method, op)
    except (OSError, ValueError, KeyError, StopIteration) as e:
        print("zwidth_quiet_table.py: %s: %s" % (" ".join(argv[2:]), e), file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

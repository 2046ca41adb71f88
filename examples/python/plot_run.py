#!/usr/bin/python3
"""Run a dentsim scene from Python and plot it with matplotlib (docs/python.md).

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/plot_run.py drill --out run.png

Runs SCENE (a built-in name: probe, probe-groove, drill; or a scene file) through dentsim.run and
writes one PNG with three panels against time: the contact force on the proxy and the force fed
back to the device [N]; the penetration of the proxy's and the device's tool tip into the tooth
[mm]; the human force the momentum observer estimates against the simulated hand's true force
(z and x) [N]. Prints the report's headline numbers. No display needed (Agg backend).
"""

import argparse
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

import dentsim  # noqa: E402


def plot(report, title, path):
    ts = report["timeseries"]
    t = ts["t_s"]
    fig, ax = plt.subplots(3, 1, figsize=(9, 9), sharex=True, constrained_layout=True)
    ax[0].plot(t, ts["contact_force_n"], label="contact force on proxy")
    ax[0].plot(t, ts["device_force_n"], "--", label="force on device")
    ax[0].set_ylabel("force [N]")
    ax[0].set_title(title)
    ax[1].plot(t, ts["penetration_m"] * 1e3, label="proxy tip")
    ax[1].plot(t, ts["device_penetration_m"] * 1e3, "--", label="device tip")
    ax[1].set_ylabel("penetration [mm]")
    # The estimates first, thin and light, so the true forces stay visible through their ripple.
    ax[2].plot(t, ts["observer_fz_n"], color="C1", lw=0.6, alpha=0.6, label="observer f_z")
    ax[2].plot(t, ts["observer_fx_n"], color="C3", lw=0.6, alpha=0.6, label="observer f_x")
    ax[2].plot(t, ts["hand_fz_n"], color="C0", lw=2, label="hand f_z (true)")
    ax[2].plot(t, ts["hand_fx_n"], color="C2", lw=2, label="hand f_x (true)")
    ax[2].set_ylabel("human force [N]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(loc="upper left", fontsize="small")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="built-in scene name or scene file")
    ap.add_argument("--out", default="run.png", help="PNG to write (default run.png)")
    ap.add_argument("--pipeline", default="fast", choices=["fast", "reference"])
    ap.add_argument("--duration", type=float, default=None,
                    help="simulated time [s] (default: the scene's)")
    args = ap.parse_args(argv)
    try:
        r = dentsim.run(args.scene, pipeline=args.pipeline, duration=args.duration)
    except dentsim.InputError as e:
        print(f"plot_run.py: error: {e}", file=sys.stderr)
        return 2
    title = (f"dentsim {r['scene']} ({r['method']}, {r['pipeline']} pipeline, "
             f"{r['simulated_s']:.2f} s at {r['tick_hz']:.0f} Hz)")
    plot(r, title, args.out)
    print(f"{r['scene']}: {r['ticks']} ticks ({r['contact_ticks']} in contact), "
          f"max contact force {r['max_contact_force_n']:.3f} N, "
          f"max penetration {r['max_penetration_m'] * 1e3:.3f} mm, "
          f"removed {r['removed_volume_mm3']['total']:.4f} mm^3, "
          f"observer RMS error {r['observer_rms_error_n'] or float('nan'):.3f} N -> {args.out}")
    return 1 if r["faults"] else 0


if __name__ == "__main__":
    sys.exit(main())

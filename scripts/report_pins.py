#!/usr/bin/env python3
"""Pins the reports of the built-in scenes and of `dentsim zwidth`, bit for bit (issue #31: a
renovation changes no result).

  report_pins.py write DENTSIM PINS [CASE ...]
        runs every pinned case (or only the CASEs named; the others keep their pins) twice and
        writes PINS: every leaf of report.json (of the zwidth JSON) that both runs agree on
        (timings, which a busy machine changes, drop out and are listed), and a SHA-256 per
        column of timeseries.csv. The full `zwidth --quick` grid (360 runs, ~5 min on two idle
        cores) runs once (its JSON holds no timing) and is pinned as a SHA-256 per method and
        operator of its leaves.
  report_pins.py check DENTSIM PINS
        runs every case once and fails on any pinned value or column that is not identical (new
        keys and columns are allowed). The `zwidth --quick` case runs only with DENTSIM_STRESS=full
        (the stress suites' long form); its short form, every method under every operator at one
        grid point, runs always.

A change that is meant to change results regenerates the pins with `write` in the same commit and
says why in its message."""
import hashlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile

# What a busy machine changes: never pinned, whatever two runs say.
MACHINE_DEPENDENT = ("timing_us", "wall_s", "setup_s")
# What thread scheduling decides (the field edit's worker against the servo thread): never pinned,
# even when two runs happen to agree (both are 0 on an idle machine).
SCHEDULING_DEPENDENT = ("field_edit_worker_waits", "field_edit_servo_takeovers",
                        "field_edit_worker_wakes")

CASES = [
    ("probe", ["probe"]),
    ("probe-groove", ["probe-groove"]),
    ("drill", ["drill"]),
    ("drill-reference", ["drill", "--pipeline", "reference"]),
]
# `dentsim zwidth` cases: (name, arguments, long form only).
ZWIDTH_CASES = [
    ("zwidth-slice", ["--methods", "explicit", "pmi", "pmi-pd", "--operators", "force", "grip",
                      "tap", "release", "--k-vc", "800", "--b-vc", "2", "--k-tooth", "3000",
                      "--threads", "2"], False),
    ("zwidth-quick", ["--quick", "--threads", "2"], True),
]


def flatten(node, prefix, out):
    if isinstance(node, dict):
        for k, v in node.items():
            flatten(v, f"{prefix}.{k}" if prefix else k, out)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            flatten(v, f"{prefix}[{i}]", out)
    elif isinstance(node, bool) or node is None or isinstance(node, str):
        out[prefix] = node
    elif isinstance(node, (int, float)):
        out[prefix] = repr(float(node)) if isinstance(node, float) else node
    return out


def columns(csv_path):
    lines = csv_path.read_text().splitlines()
    if not lines:
        return {}
    names = lines[0].split(",")
    cols = {n: hashlib.sha256() for n in names}
    for line in lines[1:]:
        for n, v in zip(names, line.split(",")):
            cols[n].update(v.encode() + b"\n")
    return {n: h.hexdigest() for n, h in cols.items()}


def run(dentsim, args):
    with tempfile.TemporaryDirectory() as d:
        out = pathlib.Path(d) / "out"
        r = subprocess.run([dentsim, "run", *args, "--out", str(out)], capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"report_pins: dentsim run {' '.join(args)} exited {r.returncode}:\n"
                             f"{r.stderr}")
        report = json.loads((out / "report.json").read_text())
        return flatten(report, "", {}), columns(out / "timeseries.csv")


def zwidth(dentsim, args):
    with tempfile.TemporaryDirectory() as d:
        out = pathlib.Path(d) / "zwidth.json"
        r = subprocess.run([dentsim, "zwidth", *args, "--json", str(out)], capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise SystemExit(f"report_pins: dentsim zwidth {' '.join(args)} exited {r.returncode}:\n"
                             f"{r.stderr}")
        return flatten(json.loads(out.read_text()), "", {}), {}


def groups(leaves):
    """SHA-256 of the leaves under each of their first four path components (for the zwidth JSON:
    a method's operator, methods.pmi-pd.operators.grip), over `key=value` lines in key order."""
    out = {}
    for k in sorted(leaves):
        g = ".".join(k.split(".")[:4])
        out.setdefault(g, hashlib.sha256()).update(f"{k}={leaves[k]!r}\n".encode())
    return {g: h.hexdigest() for g, h in out.items()}


def all_cases():
    """(name, args, kind, long form only) of every case."""
    return ([(n, a, "run", False) for n, a in CASES] +
            [(n, a, "zwidth", full) for n, a, full in ZWIDTH_CASES])


def run_case(dentsim, kind, args):
    return run(dentsim, args) if kind == "run" else zwidth(dentsim, args)


def write(dentsim, pins, only):
    names = [c[0] for c in all_cases()]
    unknown = [n for n in only if n not in names]
    if unknown:
        raise SystemExit(f"report_pins: unknown case {unknown[0]!r} (cases: {', '.join(names)})")
    path = pathlib.Path(pins)
    old = json.loads(path.read_text())["cases"] if only and path.exists() else {}
    doc = {"_what": "scripts/report_pins.py write: report.json leaves and timeseries.csv column "
                    "hashes of the built-in scenes, and the leaves of `dentsim zwidth`'s JSON "
                    "(tests/sim: ReportPins)", "cases": {}}
    for name, args, kind, full in all_cases():
        if only and name not in only:
            if name in old:
                doc["cases"][name] = old[name]
            continue
        twice = not full
        print(f"report_pins: {name} ({'twice' if twice else 'once'})", file=sys.stderr, flush=True)
        a, ca = run_case(dentsim, kind, args)
        b, cb = run_case(dentsim, kind, args) if twice else (a, ca)
        keep = {k: v for k, v in a.items()
                if b.get(k) == v and not k.split(".")[-1].startswith(MACHINE_DEPENDENT)
                and not k.startswith(MACHINE_DEPENDENT)
                and k.split(".")[-1] not in SCHEDULING_DEPENDENT}
        dropped = sorted(k for k in a if k not in keep)
        case = {"args": args, "kind": kind, "long_form_only": full, "report_unpinned": dropped,
                "timeseries_sha256": {k: v for k, v in ca.items() if cb.get(k) == v}}
        if full:  # tens of thousands of leaves: a SHA-256 per group of them
            case["report_groups_sha256"] = groups(keep)
        else:
            case["report"] = keep
        doc["cases"][name] = case
    path.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    print(f"report_pins: wrote {pins}", file=sys.stderr)


def check(dentsim, pins):
    doc = json.loads(pathlib.Path(pins).read_text())
    bad = 0
    checked = 0
    full = os.environ.get("DENTSIM_STRESS") == "full"
    for name, case in doc["cases"].items():
        if case.get("long_form_only") and not full:
            print(f"report_pins: {name}: long form, runs with DENTSIM_STRESS=full")
            continue
        report, cols = run_case(dentsim, case.get("kind", "run"), case["args"])
        bad_before = bad
        if "report_groups_sha256" in case:
            got = groups({k: v for k, v in report.items() if k not in case["report_unpinned"]})
            for g, h in case["report_groups_sha256"].items():
                checked += 1
                if got.get(g) != h:
                    bad += 1
                    print(f"report_pins: {name}: the leaves under {g} differ")
        for k, v in case.get("report", {}).items():
            checked += 1
            if report.get(k, "<missing>") != v:
                bad += 1
                if bad <= 40:
                    print(f"report_pins: {name}: report.json {k}: {report.get(k, '<missing>')} "
                          f"(pinned {v})")
        for k, v in case["timeseries_sha256"].items():
            checked += 1
            if cols.get(k) != v:
                bad += 1
                if bad <= 40:
                    print(f"report_pins: {name}: timeseries.csv column {k} differs")
        if bad - bad_before > 0:
            # The first 40 differences are printed in full; every case says how many it has.
            print(f"report_pins: {name}: {bad - bad_before} pinned values differ")
    print(f"report_pins: {checked} pinned values in {len(doc['cases'])} cases, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) < 4 or sys.argv[1] not in ("write", "check") or \
            (sys.argv[1] == "check" and len(sys.argv) != 4):
        raise SystemExit(__doc__)
    if sys.argv[1] == "write":
        write(sys.argv[2], sys.argv[3], sys.argv[4:])
        sys.exit(0)
    sys.exit(check(sys.argv[2], sys.argv[3]))

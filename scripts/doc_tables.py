#!/usr/bin/env python3
"""Regenerates the tables in docs/ that quote figures of the built-in scenes (issue #33).

Each table sits between two marker comments in its document:

    <!-- BEGIN doc_tables NAME: written by scripts/doc_tables.py, do not edit by hand -->
    ...
    <!-- END doc_tables NAME -->

and is made here from runs of `dentsim run` (numbers from report.json). When the scenes or their
gains change, regenerate with

    scripts/doc_tables.py --write                 # uses build/release/cli/dentsim

and commit the documents. `--check` (the ctest `docs_tables`, label `docs`) fails when a document
disagrees with what the script makes now, printing the difference. The runs are the built-in
scenes at their full duration on the default (fast) pipeline: deterministic, a few seconds each.
`--check` also fails on any other table in docs/ with figures and no `<!-- figures: WHERE -->`
line naming its source (docs/README.md "Tables of figures"); `--check --sources-only` checks
only that, without running dentsim.
"""

import argparse
import difflib
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_scene(dentsim, scene, out_dir, scene_text=None):
    """report.json of `dentsim run SCENE` (a built-in name, or scene_text written to a file)."""
    arg = scene
    if scene_text is not None:
        arg = os.path.join(out_dir, scene + ".json")
        with open(arg, "w") as f:
            f.write(scene_text)
    out = os.path.join(out_dir, scene)
    # Exit 1 with a report is a run the device ended in a named fault: its report is still a
    # result (the table shows the fault); anything else is an error.
    # --force: a method outside its stability bound at the scene's gains (explicit Euler at the
    # drill scene's) is measured anyway, as the table says; the supervisor still watches.
    p = subprocess.run([dentsim, "run", arg, "--force", "--out", out], stdout=subprocess.DEVNULL)
    if p.returncode not in (0, 1) or not os.path.exists(os.path.join(out, "report.json")):
        raise SystemExit("doc_tables: dentsim run %s failed (exit %d)" % (arg, p.returncode))
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


def builtin_scenes(dentsim):
    """[(name, description)] from `dentsim run --list` (one line per scene: NAME DESCRIPTION)."""
    out = subprocess.run([dentsim, "run", "--list"], check=True, capture_output=True,
                         text=True).stdout
    return [tuple(line.split(None, 1)) for line in out.splitlines() if line.strip()]


def show(dentsim, scene):
    return subprocess.run([dentsim, "run", scene, "--show"], check=True, capture_output=True,
                          text=True).stdout


def hand_port(r):
    w = r["hand_work_min_j"]
    if w is None:
        return "n/a"
    faults = "; fault " + r["faults"][0] if r.get("faults") else ""
    return "%.1e J (%s%s)" % (w, "passive" if r["passive_at_hand"] else "ACTIVE", faults)


def removed(r):
    v = r["removed_volume_mm3"]
    if v["total"] == 0:
        return "0"
    parts = ["%s %.2f" % (m, v[m]) for m in ("enamel", "dentin", "caries", "pulp") if v.get(m)]
    pulp = r.get("pulp_exposed_at_s")
    parts.append("`pulp_exposed_at_s` " + ("null" if pulp is None else "%.3f" % pulp))
    return ", ".join(parts)


def scenes_table(dentsim, tmp):
    rows = [
        "Made by `scripts/doc_tables.py --write`: `dentsim run NAME --out DIR` per built-in scene "
        "(default pipeline, full duration), numbers from `DIR/report.json`.",
        "",
        "| scene | rendered stiffness [N/m] | contact force max / RMS [N] | proxy penetration max [mm] "
        "| hand port W_h min | removed [mm³] |",
        "|---|---|---|---|---|---|",
    ]
    for name, description in builtin_scenes(dentsim):
        r = run_scene(dentsim, name, tmp)
        rows.append("| `%s` (%s) | %.0f | %.2f / %.2f | %.3f | %s | %s |" % (
            name, description.rstrip("."), r["rendered_stiffness_n_per_m"],
            r["max_contact_force_n"], r["rms_contact_force_n"], r["max_penetration_m"] * 1e3,
            hand_port(r), removed(r)))
    return rows


def methods_table(dentsim, tmp):
    """The drill scene with each method at the scene's gains (the grip detector and the hand's
    mass in the model belong to pmi-pd: off for the other two)."""
    base = json.loads(show(dentsim, "drill"))
    rows = [
        "Made by `scripts/doc_tables.py --write`: the drill scene (`dentsim run drill --show`) "
        "with `method.name` set to each method (for `explicit` and `pmi` also "
        "`grip_detector` false and `grasp_mass_scale` 0, which need `pmi-pd`), then "
        "`dentsim run FILE --force --out DIR` (`--force`: explicit Euler at these gains is outside "
        "its stability bound, which `dentsim run` checks at load, docs/hardware.md \"5a\"); "
        "numbers from `DIR/report.json`:",
        "",
        "```",
        "dentsim run drill --show | python3 -c \"import json,sys; s=json.load(sys.stdin); "
        "s['method'].update(name='explicit', grip_detector=False, grasp_mass_scale=0); "
        "json.dump(s,sys.stdout)\" > drill_explicit.json",
        "dentsim run drill_explicit.json --force --out out/explicit",
        "```",
        "",
        "| method | max contact force [N] | rendered stiffness [N/m] | hand port W_h min | "
        "proxy penetration max [mm] |",
        "|---|---|---|---|---|",
    ]
    for method in ("explicit", "pmi", "pmi-pd"):
        s = json.loads(json.dumps(base))
        s["method"]["name"] = method
        if method != "pmi-pd":
            s["method"]["grip_detector"] = False
            s["method"]["grasp_mass_scale"] = 0.0
        r = run_scene(dentsim, "drill_" + method, tmp, json.dumps(s))
        rows.append("| %s | %.2f | %.0f | %s | %.3f |" % (
            method, r["max_contact_force_n"], r["rendered_stiffness_n_per_m"], hand_port(r),
            r["max_penetration_m"] * 1e3))
    return rows


# (document, table name, generator)
TABLES = [
    ("docs/scenes.md", "scenes", scenes_table),
    ("docs/scenes.md", "methods", methods_table),
]


# Every other table in docs/ says where its figures come from: a comment line
#
#     <!-- figures: WHERE -->
#
# between the table and the heading or table before it, WHERE being the command that regenerates
# it (run by hand: benchmarks, sweeps and other long runs are not re-run in CI, docs/README.md
# "Tables of figures"), the test that measures or asserts them, or `none` for a table of
# definitions, parameters or sources (nothing measured). `--check` fails on a table with a digit
# in its body and neither that comment nor doc_tables markers (a new table must say it).
FIGURES = "<!-- figures:"


def unsourced_tables(root):
    """[(path, line, header)] of the tables in docs/ whose figures have no stated source."""
    found = []
    for folder, _, files in sorted(os.walk(os.path.join(root, "docs"))):
        for name in sorted(files):
            if not name.endswith(".md"):
                continue
            path = os.path.join(folder, name)
            with open(path) as f:
                lines = f.read().splitlines()
            i = 0
            while i < len(lines):
                if not lines[i].startswith("|"):
                    i += 1
                    continue
                j = i
                while j < len(lines) and lines[j].startswith("|"):
                    j += 1
                body = "".join(lines[i + 2:j])
                sourced = False
                for k in range(i - 1, -1, -1):  # back to the heading or table before it
                    above = lines[k]
                    if above.startswith(FIGURES) or above.startswith("<!-- BEGIN doc_tables"):
                        sourced = True
                        break
                    if above.startswith("#") or above.startswith("|"):
                        break
                if any(c.isdigit() for c in body) and not sourced:
                    found.append((os.path.relpath(path, root), i + 1, lines[i][:80]))
                i = j
    return found


def begin(name):
    return "<!-- BEGIN doc_tables %s: written by scripts/doc_tables.py, do not edit by hand -->" % name


def end(name):
    return "<!-- END doc_tables %s -->" % name


def replace_block(text, name, rows, path):
    b, e = begin(name), end(name)
    if b not in text or e not in text:
        raise SystemExit("doc_tables: %s has no '%s' ... '%s' markers" % (path, b, e))
    head, rest = text.split(b, 1)
    _, tail = rest.split(e, 1)
    return head + b + "\n" + "\n".join(rows) + "\n" + e + tail


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="rewrite the tables in docs/")
    mode.add_argument("--check", action="store_true",
                      help="exit 1 when a document differs from what the script makes")
    ap.add_argument("--dentsim", default=os.path.join(ROOT, "build/release/cli/dentsim"),
                    help="the dentsim binary (default: build/release/cli/dentsim)")
    ap.add_argument("--only", help="only this table name")
    ap.add_argument("--sources-only", action="store_true",
                    help="only check that every table of figures states its source (no runs)")
    a = ap.parse_args()
    unsourced = unsourced_tables(ROOT) if a.check else []
    for path, line, header in unsourced:
        print("doc_tables: %s:%d: a table of figures without a '%s WHERE -->' line above it "
              "(the command or test that makes it, or 'none'): %s" % (path, line, FIGURES, header),
              file=sys.stderr)
    if a.sources_only:
        return 1 if unsourced else 0
    docs = {}
    with tempfile.TemporaryDirectory(prefix="dentsim_doc_tables_") as tmp:
        for path, name, make in TABLES:
            if a.only and name != a.only:
                continue
            full = os.path.join(ROOT, path)
            if path not in docs:
                with open(full) as f:
                    docs[path] = f.read()
            docs[path] = replace_block(docs[path], name, make(a.dentsim, tmp), path)
    differ = False
    for path, text in docs.items():
        full = os.path.join(ROOT, path)
        with open(full) as f:
            old = f.read()
        if old == text:
            continue
        if a.write:
            with open(full, "w") as f:
                f.write(text)
            print("doc_tables: rewrote the tables in %s" % path)
        else:
            differ = True
            sys.stdout.writelines(difflib.unified_diff(
                old.splitlines(True), text.splitlines(True), path, path + " (now)"))
    if differ or unsourced:
        if not differ:
            return 1
        print("doc_tables: the tables above are stale; regenerate with scripts/doc_tables.py "
              "--write (after building dentsim) and commit", file=sys.stderr)
        return 1
    if a.check:
        print("doc_tables: every table agrees with its runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())

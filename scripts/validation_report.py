#!/usr/bin/env python3
"""Writes docs/validation.md (to stdout) from the rows of millcharge_validate
and, when there is one, a LIGGGHTS comparison folder. Called by
scripts/validate.sh, which says what the options hold."""
import argparse
import glob
import json
import os
import re
import statistics
import sys


def fail(msg):
    sys.exit(f"validation_report.py: {msg}")


def read_rows(path):
    head, groups = None, []
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                j = json.loads(line)
            except json.JSONDecodeError as e:
                fail(f"{path}:{n}: not a JSON line ({e})")
            if "device" in j:
                head = j
            elif "about" in j:
                groups.append({"name": j["group"], "about": j["about"], "rows": []})
            elif "check" in j:
                if not groups or groups[-1]["name"] != j["group"]:
                    fail(f"{path}:{n}: a row of '{j['group']}' before its group")
                groups[-1]["rows"].append(j)
    if head is None:
        fail(f"{path}: no device line: millcharge_validate did not start")
    return head, groups


def liggghts_group(folder):
    """Throughput and power of both codes from a liggghts_compare.sh folder."""
    rows = []
    info = open(os.path.join(folder, "info.txt"), encoding="utf-8").read() if os.path.exists(
        os.path.join(folder, "info.txt")) else ""
    # Throughput: LIGGGHTS on its largest rank count against millcharge
    # (float), the medians of the timed repeats.
    lg, timed_steps = {}, 0
    for name in glob.glob(os.path.join(folder, "liggghts", "timed.*.*.out")):
        text = open(name, encoding="utf-8").read()
        m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
        if m:
            procs = int(m.group(2))
            timed_steps = int(m.group(3))
            lg.setdefault(procs, []).append(int(m.group(4)) * int(m.group(3)) / float(m.group(1)))
    mc = []
    for name in glob.glob(os.path.join(folder, "millcharge-bench-float.*.json")):
        mc.append(json.load(open(name, encoding="utf-8"))["particle_updates_per_s"])
    if not lg or not mc:
        fail(f"{folder}: no timed LIGGGHTS runs or no millcharge bench (is it a liggghts_compare.sh --out folder?)")
    procs = max(lg)
    lg_ups, mc_ups = statistics.median(lg[procs]), statistics.median(mc)
    rows.append({"check": f"throughput, particle-updates/s (LIGGGHTS double on {procs} MPI rank"
                          f"{'s' if procs > 1 else ''}, millcharge float on PoCL)",
                 "reference": f"{lg_ups:.3g}", "value": f"{mc_ups:.3g}",
                 "error": f"{mc_ups / lg_ups:.2f}×", "criterion": "at least as fast", "pass": mc_ups >= lg_ups})
    # Power: the torque on the turning walls over the same turning phase.
    warm = os.path.join(folder, "liggghts", "warmup.out")
    summ = os.path.join(folder, "millcharge-run", "summary.json")
    power, turned = None, None
    if os.path.exists(warm):
        text = open(warm, encoding="utf-8").read()
        m = re.findall(r"^TURNED .*\bpower_W (\S+)", text, re.M)
        if m:
            power = float(m[-1])
        t_settled = re.findall(r"^SETTLED step \S+ time (\S+)", text, re.M)
        t_turned = re.findall(r"^TURNED step \S+ time (\S+)", text, re.M)
        if t_settled and t_turned:
            turned = float(t_turned[-1]) - float(t_settled[-1])
    if power is not None and os.path.exists(summ):
        mine = json.load(open(summ, encoding="utf-8"))["power_W"]["torque"]
        rel = (mine - power) / power
        rows.append({"check": "power draw over the same turning phase (wall torque × ω)",
                     "reference": f"{power:.4g} W", "value": f"{mine:.4g} W", "error": f"{100 * rel:+.2f} %",
                     "criterion": "within 10 %", "pass": abs(rel) <= 0.10})
    else:
        rows.append({"check": "power draw over the same turning phase", "reference": "—", "value": "—",
                     "error": "—", "criterion": "—", "pass": None,
                     "note": "this folder's LIGGGHTS warm-up printed no power (made before liggghts_compare.sh "
                             "measured it): run it again"})
    about = ("The benchmark mill (assets/cases/bench_100k.toml cut to 0.5 m: D 1.0 m, 16 lifters, 16,412 balls "
             "of 19–21 mm, J 0.30, 75 % of critical, Hertz, dt 5 µs) in LIGGGHTS 3.8 and in millcharge on the "
             "same machine, from `scripts/liggghts_compare.sh` (scripts/liggghts/README.md says how the two "
             "setups are matched and what still differs). Both settle, then turn " +
             (f"{turned:.2f} s" if turned is not None else "for the script's --turn") +
             " (the mill's revolution takes 1.87 s: the charge is still being lifted): the power is the mean "
             f"over that phase; the throughput times {timed_steps:,} steps after it, the median of the repeats. "
             "Both codes share the machine's cores, so the throughput is only meaningful on a quiet machine.")
    if info:
        about += "\n\n```\n" + info.strip() + "\n```"
    return {"name": "The same mill in LIGGGHTS", "about": about, "rows": rows}


def cell(s):
    return str(s).replace("|", "\\|")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", required=True)
    ap.add_argument("--command", required=True)
    ap.add_argument("--machine", required=True)
    ap.add_argument("--date", required=True)
    ap.add_argument("--commit", required=True)
    ap.add_argument("--liggghts")
    ap.add_argument("--liggghts-note")
    a = ap.parse_args()

    head, groups = read_rows(a.rows)
    if a.liggghts:
        groups.append(liggghts_group(a.liggghts))
    elif a.liggghts_note and a.liggghts_note != "skip":
        groups.append({"name": "The same mill in LIGGGHTS",
                       "about": "The benchmark mill cut to 0.5 m (16,412 balls) in LIGGGHTS 3.8 and in millcharge "
                                "on the same machine: power and throughput (`scripts/liggghts_compare.sh`).",
                       "rows": [{"check": "power draw and throughput", "reference": "—", "value": "—",
                                 "error": "—", "criterion": "—", "pass": None, "note": a.liggghts_note}]})

    rows = [r for g in groups for r in g["rows"]]
    judged = [r for r in rows if r["pass"] is not None]
    passed = sum(1 for r in judged if r["pass"])
    failed = [(g["name"], r) for g in groups for r in g["rows"] if r["pass"] is False]

    out = []
    w = out.append
    w("# Validation")
    w("")
    w("millcharge against published and analytic values: the checks the test suite asserts on "
      "(`tests/checks.cpp`), run again and reported with their numbers. The references are those of "
      "Chung & Ooi (2011, Granular Matter 13, 643–656) for the impacts, closed forms of single-ball motion, and Morrell's C-model (1996, Trans. IMM C105) for the mill. "
      "This page is written by `bash scripts/validate.sh`; do not edit it by hand, run the script again. "
      "What the checks mean for the physics: [physics.md](physics.md).")
    w("")
    w("| | |")
    w("|---|---|")
    w(f"| command | `{cell(a.command)}` |")
    w(f"| machine | {cell(a.machine)} |")
    w(f"| OpenCL device | {cell(head['device'])}; {cell(head.get('opencl', ''))} |")
    w(f"| date | {a.date} |")
    w(f"| millcharge | commit {cell(a.commit)} |")
    w(f"| result | {passed} of {len(judged)} rows pass" +
      (f"; {len(rows) - len(judged)} not run" if len(rows) > len(judged) else "") + " |")
    w("")
    if failed:
        w("Rows that fail:")
        w("")
        for gname, r in failed:
            w(f"- {gname}: {r['check']} ({r['error']}; criterion {r['criterion']})")
        w("")
    w("Contents: " + ", ".join(f"[{g['name']}](#{anchor(g['name'])})" for g in groups) + ".")
    w("")
    for g in groups:
        w(f"## {g['name']}")
        w("")
        w(g["about"])
        w("")
        w("| check | reference | millcharge | error | criterion | result |")
        w("|---|---|---|---|---|---|")
        for r in g["rows"]:
            result = "pass" if r["pass"] else ("**FAIL**" if r["pass"] is False else "not run")
            w(f"| {cell(r['check'])} | {cell(r['reference'])} | {cell(r['value'])} | {cell(r['error'])} | "
              f"{cell(r['criterion'])} | {result} |")
        notes = [r["note"] for r in g["rows"] if r.get("note")]
        if notes:
            w("")
            for n in notes:
                w(n[0].upper() + n[1:] + ".")
        w("")
    sys.stdout.write("\n".join(out))


def anchor(title):
    t = title.lower()
    t = re.sub(r"[^\w\- ]", "", t)
    return t.replace(" ", "-")


if __name__ == "__main__":
    main()

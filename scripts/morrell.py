#!/usr/bin/env python3
"""Prints a run's DEM result beside Morrell's C-model for the same mill.

    python3 scripts/morrell.py RUN_DIR [RUN_DIR...]

Reads each RUN_DIR/summary.json (written by `millcharge run`): the DEM's
torque power, toe, shoulder and centre-of-mass angle, and the C-model's power
(k = 1.26 times its theoretical net power, Morrell's calibration to measured
mills) and angles that millcharge computed for the same mill, speed, filling
and charge density (src/core/morrell.cpp). Angles are degrees counter-clockwise
from 3 o'clock (Morrell's convention).
"""
import json
import sys
from pathlib import Path


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    rows = []
    for arg in argv[1:]:
        path = Path(arg) / "summary.json"
        try:
            s = json.loads(path.read_text())
        except (OSError, ValueError) as e:
            print(f"morrell.py: {path}: {e}", file=sys.stderr)
            return 2
        m = s["morrell"]
        dem_p = s["power_W"]["torque"]
        rows.append((s.get("case", arg), 100 * s["speed_fraction"], s["filling"], dem_p, m["power_W"],
                     s["toe_deg"], m["toe_deg"], s["shoulder_deg"], m["shoulder_deg"], s["power_W"]["dissipation"],
                     s["average"]["revolutions"]))
    head = ("case", "% crit", "J", "P DEM W", "P Morrell W", "ratio", "toe DEM", "toe M", "shoulder DEM",
            "shoulder M", "P diss W", "revs")
    print("  ".join(f"{h:>12}" for h in head))
    for r in rows:
        case, phi, j, p, pm, toe, toem, sh, shm, diss, revs = r
        cells = (case, fmt(phi, ".1f"), fmt(j, ".3f"), fmt(p, ".4g"), fmt(pm, ".4g"), fmt(p / pm if pm else None, ".3f"),
                 fmt(toe, ".1f"), fmt(toem, ".1f"), fmt(sh, ".1f"), fmt(shm, ".1f"), fmt(diss, ".4g"), fmt(revs, ".2f"))
        print("  ".join(f"{c:>12}" for c in cells))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

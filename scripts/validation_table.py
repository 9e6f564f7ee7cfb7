#!/usr/bin/env python3
"""Markdown table of the Chapter 2-4 targets from `hdi validate --json` (docs/validation.md).

    ./target/release/hdi validate --json > v.json; python3 scripts/validation_table.py v.json

One line per row whose id starts with `dyn-`, in id order: class, basis (published / derived /
by construction), the value with the row's own inputs, on the synthetic DMW record of raw/, after
calibration (with the calibration set: fitted / selection / final), status, and the values under
other variants (friction laws, summit distributions, readings of the 3-DOF air bearing).
"""
import json
import re
import sys


def num(x):
    if x is None:
        return "–"
    a = abs(x)
    if a != 0 and (a < 1e-3 or a >= 1e5):
        return f"{x:.3g}"
    return f"{x:.4g}"


def tol(t):
    k = t["kind"]
    if k == "relative":
        return f"±{t['value'] * 100:g} %"
    if k == "absolute":
        return f"±{t['value']:g}"
    lo, hi = t.get("lo"), t.get("hi")
    if hi is None:
        return f"≥ {lo:g}"
    return f"[{lo:g}, {hi:g}]"


def key(r):
    m = re.match(r"dyn-(\d+)(.*)", r["id"])
    return (int(m.group(1)), m.group(2)) if m else (99, r["id"])


BASIS = {"published": "published", "derived": "derived", "by_construction": "by constr.", "unstated": "?"}


def main():
    d = json.load(open(sys.argv[1]))
    rows = [r for a in d["areas"].values() for r in a]
    dyn = sorted((r for r in rows if r["id"].startswith("dyn-")), key=key)
    print(
        "| id | class | basis | quantity | published | tolerance | hdi | synthetic record "
        "| calibrated | status | other variants |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in dyn:
        o = r["ordering"]
        if o:
            items = ", ".join(f"{i['label']} {num(i['value'])}" for i in o["items"])
            target, t, value = "ordering", o["relation"]["kind"], items
        else:
            target, t, value = num(r["target"]), tol(r["tolerance"]), num(r["value"])

        def alt(c):
            return "–" if not c else num(c["value"]) + (" ✓" if c["pass"] else "")

        rec, cal = alt(r.get("uncalibrated_record")), alt(r["calibrated"])
        if r["calibrated"] and r.get("calibration_set"):
            cal += f" ({r['calibration_set']})"
        status = {"pass": "yes", "fail": "no", "not_run": "not run"}[r["status"]]
        variants = "; ".join(
            f"{v['variant']}: "
            + (("holds" if v["pass"] else "no") if v["ordering"] else num(v["value"]) + (" ✓" if v["pass"] else ""))
            for v in r.get("variants", [])
        ) or "–"
        unit = "" if r["unit"] in ("1", "") else f" ({r['unit']})"
        print(
            f"| {r['id']} | {r['class']} | {BASIS[r['basis']['kind']]} | {r['quantity']}{unit} | {target} | {t} "
            f"| {value} | {rec} | {cal} | {status} | {variants} |"
        )


if __name__ == "__main__":
    main()

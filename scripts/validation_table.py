#!/usr/bin/env python3
"""Markdown table of the Chapter 2-4 targets from `hdi validate --json` (docs/validation.md).

    ./target/release/hdi validate --json > v.json; python3 scripts/validation_table.py v.json

One line per row whose id starts with `dyn-` (plus the consistency checks), in id order.
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


def main():
    d = json.load(open(sys.argv[1]))
    rows = [r for a in d["areas"].values() for r in a]
    dyn = sorted((r for r in rows if r["id"].startswith("dyn-")), key=key)
    print(
        "| id | class | quantity | published | tolerance | hdi | record | calibrated | pass | origin |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
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
        origin = r["origin"]["kind"]
        if origin != "computed":
            origin += " " + r["origin"]["instance"]
        unit = "" if r["unit"] in ("1", "") else f" ({r['unit']})"
        print(
            f"| {r['id']} | {r['class']} | {r['quantity']}{unit} | {target} | {t} | {value} | {rec} | {cal} "
            f"| {'yes' if r['pass'] else 'no'} | {origin} |"
        )


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The published orderings (class-Q rows of `hdi validate`) under every model-form switch of
docs/model-form.md: one copy of the pipeline per variant with the switch set on the instances it
concerns, the 3-DOF and App. B instances run (`hdi run --only …`, the calibration is not
touched), then `hdi validate --json --only dynamics three_dof` read back. Table 4.4's three
orderings are also evaluated on the stage's own cases (the synthetic DMW record of raw/), since
`hdi validate` computes its Table 4.4 rows on its synthetic DMW with the default interface.

    python3 scripts/orderings_under_switches.py HDI_BINARY PROJECT_DIR WORK_DIR [VARIANT …]

PROJECT_DIR holds pipeline.toml and raw/; WORK_DIR gets one project copy per variant and
`orderings.json` (every Q row per variant) and prints a Markdown table of the orderings that do
not hold under the defaults. The 2-DOF-only orderings (dyn-10, dyn-27) are computed with the
default interface by `hdi validate`; their values under the interface switches come from
`cargo run --release --example model_form -- model=initial_2dof …` (docs/model-form.md).
"""
import json
import os
import shutil
import subprocess
import sys
import tomllib

# name → [(section, key, TOML value)]. The interface switches go to the 3-DOF interface
# (`[contact.slider3]`); the air-bearing readings to every `[three_dof]` instance.
INTERFACE = "contact.slider3"
VARIANTS = {
    "defaults": [],
    "friction_law = seed_power_elastic": [(INTERFACE, "friction_law", '"seed_power_elastic"')],
    "friction_law = ke_static": [(INTERFACE, "friction_law", '"ke_static"')],
    "summit_distribution = mccool": [(INTERFACE, "summit_distribution", '"mccool"')],
    "summit_distribution = fig_2_11": [(INTERFACE, "summit_distribution", '"fig_2_11"')],
    "contact_force = integrated_stiffness": [("THREE_DOF", "contact_force", '"integrated_stiffness"')],
    "ab_nominal_force = as_printed": [("THREE_DOF", "ab_nominal_force", '"as_printed"')],
    "ab_stiffness_argument = pole_tip": [("THREE_DOF", "ab_stiffness_argument", '"pole_tip"')],
    "ab_roll_spring = absolute": [("THREE_DOF", "ab_roll_spring", '"absolute"')],
    "ab_spring_law = linear, ab_stiffness_argument = static_pole_tip": [
        ("THREE_DOF", "ab_spring_law", '"linear"'),
        ("THREE_DOF", "ab_stiffness_argument", '"static_pole_tip"'),
    ],
    "ab_spring_law = linear": [("THREE_DOF", "ab_spring_law", '"linear"')],
    "air_bearing = faithful": [("THREE_DOF", "air_bearing", '"faithful"')],
}


def edited(text, edits, three_dof):
    """`text` with each `key = value` inserted under its `[section]` header."""
    lines = text.split("\n")
    for section, key, value in edits:
        sections = three_dof if section == "THREE_DOF" else [section]
        for s in sections:
            header = f"[{s}]"
            i = next(k for k, l in enumerate(lines) if l.split("#")[0].strip() == header)
            lines.insert(i + 1, f"{key} = {value}")
    return "\n".join(lines)


def table_4_4(project):
    """Table 4.4's orderings on the stage's MTL cases (the synthetic DMW record)."""
    try:
        cases = json.load(open(os.path.join(project, "processed/lubricant_cases/result.json")))["cases"]
    except (OSError, KeyError):
        return None
    by = {c["case"]: c for c in cases}
    order = ["mtl_reference", "mtl_humidity_temperature", "mtl_more_bonding", "mtl_larger_gyration_radius"]
    if not all(o in by for o in order):
        return None
    jtc = [by[o].get("jump_to_contact_bv_percent") for o in order]
    steady = [by[o].get("steady_contact_bv_percent") for o in order]
    fly = [by[o].get("flying_fhm_percent") for o in order]
    ok = lambda xs: all(x is not None for x in xs)
    return {
        "jtc": jtc,
        "steady": steady,
        "flying": fly,
        "jtc_order": ok(jtc) and min(jtc[1], jtc[3]) >= 3 * max(jtc[0], jtc[2]),
        "steady_order": ok(steady) and steady[2] < steady[0] < steady[1] < steady[3],
        "flying_band": ok(fly) and all(4 <= f <= 10 for f in fly),
    }


def main():
    hdi, project, work = (os.path.abspath(a) for a in sys.argv[1:4])
    names = sys.argv[4:] or list(VARIANTS)
    text = open(os.path.join(project, "pipeline.toml")).read()
    cfg = tomllib.loads(text)
    three_dof = [f"three_dof.{n}" for n in cfg.get("three_dof", {})]
    only = list(cfg.get("three_dof", {})) + [
        n for n, a in cfg.get("analysis", {}).items() if a.get("source") in cfg.get("three_dof", {})
    ]
    out = {}
    os.makedirs(work, exist_ok=True)
    for name in names:
        d = os.path.join(work, name.replace(" ", "").replace("=", "-").replace(",", "+"))
        os.makedirs(d, exist_ok=True)
        open(os.path.join(d, "pipeline.toml"), "w").write(edited(text, VARIANTS[name], three_dof))
        raw = os.path.join(d, "raw")
        if not os.path.exists(raw):
            shutil.copytree(os.path.join(project, "raw"), raw)
        r = subprocess.run([hdi, "run", "--only", *only], cwd=d, capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{name}: hdi run failed: {r.stderr.strip()[-400:]}", file=sys.stderr)
        v = subprocess.run(
            [hdi, "validate", "--json", "--only", "dynamics", "three_dof"],
            cwd=d, capture_output=True, text=True,
        )
        rows = {}
        if v.stdout.strip():
            for area in json.loads(v.stdout)["areas"].values():
                for row in area:
                    if row["class"] == "Q":
                        rows[row["id"]] = {
                            "status": row["status"],
                            "items": [(i["label"], i["value"]) for i in (row["ordering"] or {}).get("items", [])],
                        }
        out[name] = {"rows": rows, "table_4_4_record": table_4_4(d), "run_ok": r.returncode == 0}
        print(f"{name}: done", file=sys.stderr)
    json.dump(out, open(os.path.join(work, "orderings.json"), "w"), indent=1)

    base = out.get("defaults") or next(iter(out.values()))
    failing = [i for i, r in base["rows"].items() if r["status"] != "pass"]

    def cell(name, rid):
        r = out[name]["rows"].get(rid)
        if not r:
            return "–"
        word = {"pass": "**holds**", "fail": "no", "not_run": "not run"}[r["status"]]
        vals = ", ".join(
            f"{l} {v:.3g}" for l, v in r["items"] if isinstance(v, (int, float)) and l not in ("published floor",)
        )
        return f"{word} ({vals})" if vals else word

    print("| ordering | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for rid in failing:
        print(f"| {rid} | " + " | ".join(cell(n, rid) for n in names) + " |")
    print("| Table 4.4 on the record: JTC order / steady order / flying 4–10 % | " + " | ".join(
        "–" if not out[n]["table_4_4_record"] else "{} / {} / {}".format(
            *("**holds**" if out[n]["table_4_4_record"][k] else "no" for k in ("jtc_order", "steady_order", "flying_band"))
        )
        for n in names
    ) + " |")


if __name__ == "__main__":
    main()

#!/bin/bash
# The default pipeline's 3-DOF cases (constant_12nm, shock, lubricant_cases: 8 cases) locally
# and as Slurm array tasks of CPT cases each (default 1), upstream (disk_md, slider3) warm in
# both; then every output file compared with cmp and the per-case compute times listed.
# Usage (repository root, Slurm up: scripts/slurm-local-up.sh): CPT=1 bash scripts/slurm-three-dof-timing.sh
set -e
HDI=$(realpath "${HDI:-${CARGO_TARGET_DIR:-target}/release/hdi}")
ROOT=${ROOT:-$PWD}
CPT=${CPT:-1}
W=$(mktemp -d "${TMPDIR:-/var/tmp}/hdi-3dof-timing.XXXX")
for d in local remote; do
  mkdir -p $W/$d; cp -r $ROOT/raw $W/$d/; cp $ROOT/pipeline.toml $W/$d/
  (cd $W/$d && $HDI run --only disk_md slider3 >/dev/null 2>&1)
done
ONLY="constant_12nm shock lubricant_cases"
cd $W/local
/usr/bin/time -f "local           wall %e s  user %U s  sys %S s" $HDI run --only $ONLY 2>&1 | tail -1
cd $W/remote
/usr/bin/time -f "slurm cpt=$CPT  wall %e s  user %U s  sys %S s (submitter; tasks' CPU not counted)" \
  env HDI_SLURM_POLL_MS=200 $HDI run --executor slurm --cases-per-task $CPT --only $ONLY 2>&1 | tail -1
n=0; bad=0
for i in $ONLY; do
  for f in $(cd $W/local/processed/$i && find . -type f ! -name manifest.json); do
    n=$((n+1)); cmp -s $W/local/processed/$i/$f $W/remote/processed/$i/$f || { bad=$((bad+1)); echo "DIFFERS $i/$f"; }
  done
done
echo "output files compared: $n, differing: $bad"
python3 - $W <<'PY'
import json, sys, pathlib
w = pathlib.Path(sys.argv[1])
def cases(side):
    out = {}
    for m in (w / side / "processed/.hdi/store/case").glob("*/manifest.json"):
        j = json.loads(m.read_text())
        p = j["fingerprint"]["params"]
        if isinstance(p, dict) and "case" in p and isinstance(p.get("instance"), dict):
            out[(p["instance"]["scenario"], p["case"])] = j["wall_time_s"]
    return out
l, r = cases("local"), cases("remote")
print(f"case compute time (get_or_compute): local {sum(l.values()):.1f} s over {len(l)} cases, in tasks {sum(r.values()):.1f} s over {len(r)}")
PY
rm -rf $W

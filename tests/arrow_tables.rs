//! Arrow IPC tables (docs/tables.md): every table hdi writes as Parquet has an Arrow IPC file
//! beside it that pyarrow opens — memory-mapped, zero-copy — with the same columns, types and
//! values, and unit metadata that matches each column's suffix.

use crate::common::*;

/// pyarrow against every `.arrow` under `processed/` (summary tables and per-stage tables).
/// The suffix → unit table below is the one docs/tables.md documents, written out
/// independently of `core::store::UNIT_SUFFIXES`.
const CHECK: &str = r#"
import os, sys, math, json, pyarrow as pa, pyarrow.ipc as ipc, pyarrow.parquet as pq

UNITS = {"m": "m", "mm": "mm", "um": "um", "nm": "nm", "um2": "um^2", "per_um2": "1/um^2",
         "s": "s", "ms": "ms", "us": "us", "Hz": "Hz", "kHz": "kHz", "MHz": "MHz",
         "N": "N", "mN": "mN", "uN": "uN", "Pa": "Pa", "MPa": "MPa", "GPa": "GPa",
         "W": "W", "mW": "mW", "rad": "rad", "urad": "urad", "N_per_m": "N/m",
         "mm_s": "mm/s", "um_s": "um/s", "nm_per_mW": "nm/mW", "percent": "%", "pct": "%"}

def expected_unit(name):
    tokens = name.split("_")
    # Longest suffix of whole tokens that names a unit, with at least one token before it.
    for k in range(len(tokens) - 1, 0, -1):
        suffix = "_".join(tokens[-k:])
        if suffix in UNITS and len(tokens) > k:
            return UNITS[suffix]
    return None

def same(x, y):
    if isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y):
        return True
    return x == y and type(x) is type(y)

root = sys.argv[1]
seen, files = set(), []
for d, _, names in os.walk(root, followlinks=True):
    for n in names:
        p = os.path.join(d, n)
        if n.endswith(".arrow") and os.path.realpath(p) not in seen:
            seen.add(os.path.realpath(p))
            files.append(p)
assert files, "no .arrow file under " + root
n_tables = sum(1 for p in files if os.sep + "tables" + os.sep in p)
units_checked = 0
for path in sorted(files):
    rel = os.path.relpath(path, root)
    parquet = pq.read_table(path[:-len(".arrow")] + ".parquet")
    # Memory-mapped and zero-copy: every (non-empty) buffer of every column lies inside the
    # map, i.e. pyarrow decompressed and copied nothing.
    with pa.memory_map(path) as src:
        whole = src.read_buffer()
        lo, hi = whole.address, whole.address + whole.size
        reader = ipc.open_file(src)
        arrow = reader.read_all()
        for name, col in zip(arrow.column_names, arrow.columns):
            for chunk in col.chunks:
                for buf in chunk.buffers():
                    if buf is not None and buf.size > 0:
                        assert lo <= buf.address and buf.address + buf.size <= hi, (rel, name, "copied: not zero-copy")
        assert reader.num_record_batches <= 1, rel
        assert arrow.num_rows == parquet.num_rows, (rel, arrow.num_rows, parquet.num_rows)
        assert arrow.column_names == parquet.column_names, (rel, arrow.column_names, parquet.column_names)
        for name in arrow.column_names:
            fa, fp = arrow.schema.field(name), parquet.schema.field(name)
            ta, tp = fa.type, fp.type
            # Text: large_string in the Arrow file (docs/tables.md), string_view in polars'
            # Parquet schema as pyarrow reads it; both are UTF-8 strings.
            assert ta == tp or (ta == pa.large_string() and tp in (pa.string(), pa.string_view(), pa.large_string())), (rel, name, ta, tp)
            va, vp = arrow.column(name).to_pylist(), parquet.column(name).to_pylist()
            bad = [i for i, (x, y) in enumerate(zip(va, vp)) if not same(x, y)]
            assert not bad, (rel, name, bad[:3], [va[i] for i in bad[:3]], [vp[i] for i in bad[:3]])
            meta = {k.decode(): v.decode() for k, v in (fa.metadata or {}).items()}
            want = expected_unit(name)
            if want is None:
                assert "unit" not in meta, (rel, name, meta)
            else:
                assert meta.get("unit") == want, (rel, name, meta, want)
                units_checked += 1
        assert set(arrow.schema.metadata or {}) == set(), (rel, arrow.schema.metadata)
        # The Parquet file's one `units` key: the same units, in column order.
        want_units = {n: expected_unit(n) for n in arrow.column_names if expected_unit(n)}
        pmeta = pq.read_metadata(path[:-len(".arrow")] + ".parquet").metadata or {}
        got_units = json.loads(pmeta[b"units"]) if b"units" in pmeta else {}
        assert got_units == want_units, (rel, got_units, want_units)
        assert list(got_units) == list(want_units), rel
    print(rel, arrow.num_rows, "rows", arrow.num_columns, "columns")
print("FILES", len(files), "TABLES", n_tables, "UNITS", units_checked)
"#;

#[test]
fn every_arrow_table_matches_its_parquet_and_carries_units() {
    let p = Project::shipped();
    // Surfaces and interfaces, the DMW chain, the bulge scans, contact and a four-case slider
    // sweep: summary tables of six kinds and two per-stage tables (scans, sweep).
    let o = p.run(&[
        "run",
        "--only",
        "hdi",
        "table_2_2",
        "disk_md",
        "tfc",
        "measured",
        "improved_sweep",
    ]);
    assert_ok(&o);
    let tables = p.processed().join("tables");
    let mut stems: Vec<String> = std::fs::read_dir(&tables)
        .expect("processed/tables")
        .filter_map(|e| {
            let name = e.ok()?.file_name().to_string_lossy().into_owned();
            name.strip_suffix(".parquet").map(str::to_owned)
        })
        .collect();
    stems.sort();
    assert!(stems.len() >= 5, "summary tables: {stems:?}");
    for s in &stems {
        for ext in ["arrow", "csv"] {
            assert!(
                tables.join(format!("{s}.{ext}")).is_file(),
                "{s}.parquet has no {s}.{ext} beside it"
            );
        }
    }
    let out = std::process::Command::new(python())
        .args(["-c", CHECK])
        .arg(p.processed())
        .output()
        .expect("python");
    let text = stdout(&out);
    assert!(
        out.status.success(),
        "pyarrow check failed:\n{text}{}",
        stderr(&out)
    );
    eprintln!("{text}");
    let last = text.lines().last().unwrap_or_default();
    let n = |key: &str| -> usize {
        last.split_whitespace()
            .skip_while(|w| *w != key)
            .nth(1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    };
    // Every summary table plus the per-stage scans and sweep tables were checked, and unit
    // metadata was seen (clearance_nm, peak_contact_force_mN, …).
    assert_eq!(n("TABLES"), stems.len(), "{text}");
    assert!(n("FILES") >= stems.len() + 2, "{text}");
    assert!(n("UNITS") >= 10, "{text}");
    for per_stage in ["scans.arrow", "sweep.arrow"] {
        assert!(text.contains(per_stage), "{per_stage} not checked:\n{text}");
    }
}

/// Reruns write the same Arrow bytes (docs/architecture.md, determinism): `--force` recomputes
/// the summary tables and the stage's own table.
#[test]
fn arrow_tables_are_byte_identical_on_a_forced_rerun() {
    let p = Project::shipped();
    assert_ok(&p.run(&["run", "--only", "tfc"]));
    let arrow_files = |p: &Project| -> Vec<(String, String)> {
        snapshot(&p.processed())
            .into_iter()
            .filter(|(rel, _)| rel.ends_with(".arrow"))
            .collect()
    };
    let first = arrow_files(&p);
    assert!(
        first.iter().any(|(rel, _)| rel.ends_with("scans.arrow")),
        "{first:?}"
    );
    assert_ok(&p.run(&["run", "--only", "tfc", "--force"]));
    assert_eq!(first, arrow_files(&p));
}

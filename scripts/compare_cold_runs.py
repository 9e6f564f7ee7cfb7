#!/usr/bin/env python3
"""Do two cold runs of one pipeline (old and new hdi binary) give the same results, up to the
cache keys they list? For a change that alters cache keys but no number (issue 21: key params
as plain data; docs/architecture.md).

    (cd OLD && old/hdi run && old/hdi validate --json > validate.json)
    (cd NEW && new/hdi run && new/hdi validate --json > validate.json)
    .venv/bin/python scripts/compare_cold_runs.py OLD NEW        # exit 0: identical

OLD and NEW are project dirs (pipeline.toml, raw/, processed/). Result files: everything under
processed/<instance>/ (the store entry the link points to) and processed/tables/, without
manifest.json; every case entry of the case store (.hdi/store/case/<key>/, without
manifest.json), matched by content; and validate.json when both dirs have one. Not compared:
.hdi/ bookkeeping, report/, manifests (times). A file that differs is compared again after
rewriting, on both sides, each cache key to a token of the same length: an instance key → a
hash of the instance's name, a case key → the digest of its case entry's contents, the
calibration's fit-inputs fingerprint → "f" × 16. Parquet files (compressed) are compared as
tables (pyarrow); a JSON `case_keys` list (a set in key order) as a sorted list.
"""
import hashlib, json, os, re, sys
from collections import Counter

old, new = sys.argv[1], sys.argv[2]

def sha(p):
    return hashlib.sha256(open(p, 'rb').read()).hexdigest()

def result_files(proc):
    out = {}
    for name in sorted(os.listdir(proc)):
        if name in ('.hdi', 'report'):
            continue
        root = os.path.join(proc, name)
        if os.path.isfile(root):
            out[name] = os.path.realpath(root)
            continue
        for dp, dns, fns in os.walk(root, followlinks=True):
            for fn in fns:
                if fn == 'manifest.json':
                    continue
                p = os.path.join(dp, fn)
                out[os.path.relpath(p, proc)] = os.path.realpath(p)
    return out

def case_entries(proc):
    base = os.path.join(proc, '.hdi/store/case')
    out = {}
    for key in sorted(os.listdir(base)):
        d = os.path.join(base, key)
        files = []
        for dp, dns, fns in os.walk(d):
            for fn in fns:
                if fn == 'manifest.json':
                    continue
                p = os.path.join(dp, fn)
                files.append((os.path.relpath(p, d), sha(p)))
        out[key] = hashlib.sha256(json.dumps(sorted(files)).encode()).hexdigest()
    return out

def refs(proc):
    d = os.path.join(proc, '.hdi/refs')
    return {f[:-5]: json.load(open(os.path.join(d, f)))['key'] for f in os.listdir(d) if f.endswith('.json')}

po, pn = os.path.join(old, 'processed'), os.path.join(new, 'processed')
fo, fn_ = result_files(po), result_files(pn)
co, cn = case_entries(po), case_entries(pn)

# Canonical tokens (same length as what they replace): an instance key -> sha256 of its
# name, a case key -> the digest of its case entry's contents, the calibration's fit-inputs
# fingerprint -> 16 x "f". Both sides are rewritten, so two files are equal after rewriting
# only if every key they list names the same instance or a case with identical contents.
def tokens(proc, refs_, cases_, files):
    t = {}
    for name, key in refs_.items():
        t[key] = hashlib.sha256(("instance:" + name).encode()).hexdigest()
    for key, dg in cases_.items():
        t[key] = dg
    for name, p in files.items():
        if name.endswith('result.json'):
            r = json.load(open(p))
            if isinstance(r, dict) and isinstance(r.get('convergence'), dict) and r['convergence'].get('fit_inputs'):
                t[r['convergence']['fit_inputs']] = 'f' * 16
    return t
ro, rn = refs(po), refs(pn)
to, tn = tokens(po, ro, co, fo), tokens(pn, rn, cn, fn_)
ambiguous = sum(1 for c in Counter(co.values()).values() if c > 1)
KEY = re.compile(rb'[0-9a-f]{64}|[0-9a-f]{16}')
def canon(b, t):
    return KEY.sub(lambda m: t.get(m.group().decode(), m.group().decode()).encode(), b)
def parquet_canon(path, t):
    import pyarrow.parquet as pq
    tab = pq.read_table(path)
    rows = tab.to_pylist()
    def c(v):
        if isinstance(v, str):
            return canon(v.encode(), t).decode()
        if isinstance(v, list):
            return [c(x) for x in v]
        if isinstance(v, dict):
            return {k: c(x) for k, x in v.items()}
        return v
    meta = tab.schema.metadata or {}
    return (str(tab.schema.remove_metadata()), {k: canon(v, t) for k, v in meta.items()}, [c(r) for r in rows])
# contact-3 (issue 21): the contact key's `inputs` name the summit offset and friction law as
# the results always did (`none`, `junction_shear`) instead of their Rust Debug form. The root
# `parameters` attribute of an HDF5 file holds the key params, so it changes with them.
CONTACT_ENUMS = {"None": "none", "McCool": "mccool", "JunctionShear": "junction_shear",
                 "SeedPowerElastic": "seed_power_elastic"}
def h5_canon(path, t, old_side):
    import h5py, numpy as np
    out = []
    def plain(a):
        # Variable-length strings are objects (pointers in memory): compare their values.
        if a.dtype == object:
            return repr([x.decode() if isinstance(x, bytes) else x for x in a.ravel().tolist()])
        return a.tobytes()
    def attrs(obj):
        a = {}
        for k, v in obj.attrs.items():
            if isinstance(v, bytes):
                v = v.decode()
            if isinstance(v, str):
                v = canon(v.encode(), t).decode()
                if k == 'parameters' and old_side:
                    p = json.loads(v)
                    inputs = p.get('inputs') if isinstance(p, dict) else None
                    if isinstance(inputs, dict):
                        for e in ('summit_offset', 'friction_law'):
                            if inputs.get(e) in CONTACT_ENUMS:
                                inputs[e] = CONTACT_ENUMS[inputs[e]]
                    v = json.dumps(p)
                elif k == 'parameters':
                    v = json.dumps(json.loads(v))
            elif isinstance(v, np.ndarray):
                v = (str(v.dtype), v.shape, plain(v))
            else:
                v = repr(v)
            a[k] = v
        return a
    with h5py.File(path, 'r') as f:
        out.append(('/', attrs(f)))
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                d = obj[()]
                d = (str(obj.dtype), obj.shape, plain(d) if isinstance(d, np.ndarray) else repr(d))
                out.append((name, 'dataset', d, attrs(obj)))
            else:
                out.append((name, 'group', attrs(obj)))
        f.visititems(visit)
    return out
mapping = to
print(f"result files: old {len(fo)}, new {len(fn_)}")
print(f"case entries: old {len(co)}, new {len(cn)}; same multiset of contents: {Counter(co.values()) == Counter(cn.values())}")
print(f"keys rewritten: old {len(to)}, new {len(tn)}; case contents shared by several keys: {ambiguous}")
ok = set(fo) == set(fn_) and Counter(co.values()) == Counter(cn.values())
if set(fo) != set(fn_):
    print("only old:", sorted(set(fo) - set(fn_))[:20])
    print("only new:", sorted(set(fn_) - set(fo))[:20])
identical = substituted = 0
for name in sorted(set(fo) & set(fn_)):
    a, b = open(fo[name], 'rb').read(), open(fn_[name], 'rb').read()
    if a == b:
        identical += 1
        continue
    if name.endswith('.parquet'):
        same = parquet_canon(fo[name], to) == parquet_canon(fn_[name], tn)
    else:
        same = canon(a, to) == canon(b, tn)
    if not same and name.endswith('.h5'):
        same = h5_canon(fo[name], to, True) == h5_canon(fn_[name], tn, False)
        if same:
            print(f"  (HDF5 compared object by object, contact enum names lower-cased: {name})")
    if not same and name.endswith('.json'):
        # `case_keys` is a set listed in key order: compared as a sorted list of tokens.
        def c(v, t, k=None):
            if isinstance(v, str):
                return canon(v.encode(), t).decode()
            if isinstance(v, list):
                out = [c(x, t) for x in v]
                return sorted(out) if k == 'case_keys' else out
            if isinstance(v, dict):
                return {kk: c(x, t, kk) for kk, x in v.items()}
            return v
        same = c(json.loads(a), to) == c(json.loads(b), tn)
        if same:
            print(f"  (`case_keys` compared as sets: {name})")
    if same:
        substituted += 1
        print(f"  equal up to cache keys: {name}")
    else:
        ok = False
        print(f"  DIFFERENT: {name}")
print(f"byte-identical: {identical}; identical up to cache keys: {substituted}")
# `hdi validate --json`: stage-entry keys (`origin.key`) → the instance's token.
va, vb = os.path.join(old, 'validate.json'), os.path.join(new, 'validate.json')
if os.path.exists(va) and os.path.exists(vb):
    ka = {k: hashlib.sha256(("instance:" + n).encode()).hexdigest() for n, k in ro.items()}
    kb = {k: hashlib.sha256(("instance:" + n).encode()).hexdigest() for n, k in rn.items()}
    def vc(v, t):
        if isinstance(v, str):
            return t.get(v, v)
        if isinstance(v, list):
            return [vc(x, t) for x in v]
        if isinstance(v, dict):
            return {k: vc(x, t) for k, x in v.items()}
        return v
    A, B = open(va, 'rb').read(), open(vb, 'rb').read()
    if A == B:
        print("validate.json: byte-identical")
    elif vc(json.loads(A), ka) == vc(json.loads(B), kb):
        print("validate.json: identical up to the store keys in `origin.key`")
    else:
        ok = False
        print("validate.json: DIFFERENT")
print("RESULT:", "IDENTICAL" if ok else "DIFFERENT")
sys.exit(0 if ok else 1)

import sys, glob, os, json, numpy as np
import orbatt
out = sys.argv[1]
only = set(sys.argv[2:])  # scenario names to (re)write; all when none given
for p in sorted(glob.glob("scenarios/*.toml")):
    name = os.path.basename(p)[:-5]
    if only and name not in only:
        continue
    ds = orbatt.load_scenario(p).run()
    n = ds.sizes["time"]
    idx = np.unique(np.linspace(0, n - 1, min(n, 120)).round().astype(int))
    arrs = {"_time_index": idx}
    meta = {}
    for k in ds.variables:
        v = ds[k]
        meta[k] = {"dims": list(v.dims), "attrs": {a: str(b) for a, b in v.attrs.items()}}
        if v.dtype.kind in "fiub":
            vals = v.values
            if "time" in v.dims:
                vals = np.take(vals, idx, axis=v.dims.index("time"))
            arrs[k] = vals
    meta["_global_attrs"] = sorted(ds.attrs)
    np.savez_compressed(f"{out}/{name}.npz", **arrs)
    json.dump(meta, open(f"{out}/{name}.json", "w"), indent=1, sort_keys=True)

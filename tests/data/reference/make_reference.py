"""Write the reference outputs of the shipped scenarios (tests/test_reference_outputs.py).

    python tests/data/reference/make_reference.py OUT [--form time|default] [NAME ...]

``--form time`` (the top folder, orbatt 0.1.0's numbers): every scenario run with
``independent_variable = "time"``; ``--form default`` (``anomaly/``): the Keplerian scenarios
as they run by default, DOP853 in the eccentric anomaly. Only the NAMEs given are (re)written.
"""
import sys, glob, os, json, numpy as np
import orbatt
args = sys.argv[1:]
out = args.pop(0)
form = "time"
if args and args[0] == "--form":
    form = args[1]
    args = args[2:]
only = set(args)  # scenario names to (re)write; all when none given
for p in sorted(glob.glob("scenarios/*.toml")):
    name = os.path.basename(p)[:-5]
    if only and name not in only:
        continue
    ds = orbatt.load_scenario(p).run(**({"independent_variable": "time"} if form == "time" else {}))
    if form != "time" and "eccentric-anomaly" not in ds.attrs["method_settings"]:
        continue  # the default runs in time: the time reference covers it
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

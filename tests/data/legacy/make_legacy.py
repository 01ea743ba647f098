"""Write the legacy result files of this folder (run once with orbatt 0.3.0.dev0, commit
6535ac4, before issue 26 item 3 changed the output units and the time axis).

They are the files an earlier orbatt wrote: attitude quantities in kg km^2 (s^-1, s^-2), the
time coordinate as float ``seconds since <epoch>`` (year 0001 without an epoch), no
``elapsed`` coordinate. ``tests/dataset/test_si_time_axis.py`` opens them in the current form.

    python tests/data/legacy/make_legacy.py tests/data/legacy
"""
import re
import sys
from pathlib import Path

import orbatt
from orbatt.scenario import Scenario, parse
from orbatt.sweep import Sweep, run_sweep

SCEN = Path(__file__).resolve().parents[3] / "scenarios"


def shortened(name, t_end, step):
    text = (SCEN / f"{name}.toml").read_text()
    text = re.sub(r"^t_end = .*$", f"t_end = {t_end}", text, flags=re.M)
    text = re.sub(r"^output_step = .*$", f"output_step = {step}", text, flags=re.M)
    return text


def main(out):
    out = Path(out)
    for name, t_end, step in [("lvlh-hold-wheels", '"200 s"', '"20 s"'),
                              ("iss-tle-gravity-gradient", '"300 s"', '"30 s"'),
                              ("mercury-3-2-normalized", "0.5", "0.05")]:
        text = shortened(name, t_end, step)
        ds = Scenario(parse(text, f"{name}.toml")).run()
        orbatt.dataset.write_netcdf(ds, out / f"{name}.nc")
    text = shortened("gg-leo-dispersion", '"200 s"', '"20 s"')
    text = re.sub(r"^samples = .*$", "samples = 3", text, flags=re.M)
    text = re.sub(r"^chunk_size = .*$", "chunk_size = 3", text, flags=re.M)
    text = re.sub(r'^outputs = \[', 'outputs = ["trajectory", ', text, flags=re.M)
    run_sweep(Sweep(Scenario(parse(text, "gg-leo-dispersion.toml"))), out / "gg-leo-dispersion-sweep.nc",
              scheduler="synchronous")


if __name__ == "__main__":
    main(sys.argv[1])

"""IOOS compliance-checker (CF 1.11) on the output of every shipped scenario: no high-priority
finding, except the time unit of a dimensionless run (optional: skipped without the checker).

A dimensionless run's time is in the problem's own unit (``"1"``, i.e. ``1/n``); CF's time
coordinate needs ``"<time unit> since <date>"``, which cannot express it, so the checker's
§3.1/§4.4 findings on that one variable are expected there and nothing else is."""
import json

import pytest
import xarray as xr

pytest.importorskip("compliance_checker")

from compliance_checker.runner import CheckSuite, ComplianceChecker  # noqa: E402

#: the findings a dimensionless time coordinate gets (see the module docstring)
DIMENSIONLESS_TIME = {"§3.1 Units", "§4.4 Time Coordinate"}


def high_priority_findings(path, tmp_path):
    CheckSuite.load_all_available_checkers()
    report = tmp_path / f"{path.stem}.json"
    ComplianceChecker.run_checker(str(path), ["cf:1.11"], 0, "normal", output_filename=str(report),
                                  output_format="json")
    result = json.loads(report.read_text())["cf:1.11"]
    return {r["name"]: r["msgs"] for r in result["high_priorities"] if r["msgs"]}


def test_shipped_outputs_have_no_high_priority_cf_failure(shipped_outputs, tmp_path):
    for name, path in shipped_outputs.items():
        found = high_priority_findings(path, tmp_path)
        with xr.open_dataset(path, decode_times=False) as ds:
            dimensionless = ds["time"].attrs["units"] == "1"
            assert ds["time"].attrs["standard_name"] == "time" and ds["time"].attrs["axis"] == "T"
        if dimensionless:
            assert set(found) <= DIMENSIONLESS_TIME, (name, found)
            assert all("time" in m for msgs in found.values() for m in msgs), (name, found)
        else:
            assert not found, (name, found)

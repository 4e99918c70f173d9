#!/usr/bin/env python3
"""The calibration report a technician files (issue 18 item 3): vitreo-calibrate against the simulated
rig writes, beside the calibration file, NAME.report.json and NAME.report.html. Checked independently
of the code that wrote them:
- its numbers against the calibration file itself, read with Python's own TOML reader (tip offsets,
  RMS and spread, FRE and TRE, pedal ranges, clocks);
- its plot data against what they claim: the RMS of the per-pose residuals is the pivot's RMS, the
  widest angle between the shaft directions the tilts describe is the pivot's spread, the RMS of the
  fiducial residuals is the FRE;
- the page in headless Chromium (network off): no console error, every chart drawn with data;
- a calibration that fails (the tracker's cable pulled half-way) still writes its report, marked
  FAIL, naming no calibration file.

usage: report_page_test.py VITREO_CALIBRATE SOURCE_DIR
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib

calibrate, source = sys.argv[1], sys.argv[2]
work = tempfile.mkdtemp()
failures = []


def check(what, ok, detail=""):
    if not ok:
        failures.append(f"{what}: {detail}")


def run(rig, out):
    return subprocess.run([calibrate, "--rig", rig, "--out", out, "--non-interactive"], capture_output=True, text=True)


out = os.path.join(work, "rig.calibration.toml")
r = run(os.path.join(source, "rig/config/sim-calibration.toml"), out)
if r.returncode != 0:
    print(r.stdout, r.stderr)
    sys.exit(f"vitreo-calibrate failed ({r.returncode})")
base = os.path.join(work, "rig.calibration")
check("the tool says where the report is", f"report {base}.report.html" in r.stdout, r.stdout[-400:])
cal = tomllib.load(open(out, "rb"))
rep = json.load(open(base + ".report.json"))

check("result", rep["result"] == "PASS", rep["result"])
check("calibration file", rep["calibration_file"] == out, rep["calibration_file"])
check("tool", rep["tool"] == cal["calibration"]["tool"], rep["tool"])
check("rig", rep["rig"] == cal["calibration"]["rig"], rep["rig"])
check("devices", [(d["name"], d["serial"]) for d in rep["devices"]] == [(d["name"], d["serial"]) for d in cal["device"]], rep["devices"])

# Pivots: the file's numbers, and the plot data's own consistency.
by_instrument = {i["instrument"]: i for i in cal["instrument"]}
check("a pivot per calibrated instrument", sorted(p["instrument"] for p in rep["pivots"]) == sorted(by_instrument), rep["pivots"])
for p in rep["pivots"]:
    f = by_instrument[p["instrument"]]
    res = p["residuals_mm"]
    check(f"pivot {p['instrument']}: one residual per pose", len(res) == f["poses"] == len(p["tilt_x_deg"]) == len(p["tilt_y_deg"]),
          (len(res), f["poses"]))
    check(f"pivot {p['instrument']}: tip offset", all(abs(a - b) < 1e-6 for a, b in zip(p["tip_offset_mm"], f["tip_offset_mm"])),
          (p["tip_offset_mm"], f["tip_offset_mm"]))
    rms = math.sqrt(sum(x * x for x in res) / len(res))
    check(f"pivot {p['instrument']}: RMS of the plotted residuals is the file's", abs(rms - f["rms_mm"]) < 1e-6, (rms, f["rms_mm"]))
    check(f"pivot {p['instrument']}: under its limit", f["rms_mm"] <= p["max_rms"]["value"], (f["rms_mm"], p["max_rms"]))
    # Each tilt pair is a shaft direction (tan x, tan y, 1) in a frame about the mean axis; the
    # widest angle between two of them is the spread the pivot step measured.
    dirs = []
    for x, y in zip(p["tilt_x_deg"], p["tilt_y_deg"]):
        v = (math.tan(math.radians(x)), math.tan(math.radians(y)), 1.0)
        n = math.sqrt(sum(c * c for c in v))
        dirs.append(tuple(c / n for c in v))
    widest = max(math.degrees(math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(u, w)))))) for u in dirs for w in dirs)
    check(f"pivot {p['instrument']}: the tilts span the file's spread", abs(widest - f["spread_deg"]) < 1e-3, (widest, f["spread_deg"]))
    check(f"pivot {p['instrument']}: spread at least the minimum", f["spread_deg"] >= p["min_spread"]["value"])

# Registration: FRE is the RMS of the fiducial residuals plotted.
reg = rep["registration"]
fr = reg["residuals_mm"]
check("a residual per fiducial", len(fr) == cal["registration"]["fiducials"] == reg["fiducials"], (len(fr), cal["registration"]["fiducials"]))
fre = math.sqrt(sum(x * x for x in fr) / len(fr))
check("FRE is the RMS of the residuals", abs(fre - cal["registration"]["fre_mm"]) < 1e-6, (fre, cal["registration"]["fre_mm"]))
check("TRE", abs(reg["tre"]["value"] - cal["registration"]["tre_mm"]) < 1e-6 and reg["tre_measured"] == cal["registration"]["tre_measured"])
check("ports", len(rep["ports"]) == len(cal["port"]) > 0 and all(
      rp["port"] == cp["port"] and all(abs(a - b) < 1e-6 for a, b in zip(rp["position_mm"], cp["position_mm"]))
      for rp, cp in zip(rep["ports"], cal["port"])), rep["ports"])
check("pedals", all(abs(rp[k] - cp[k]) < 1e-6 for rp, cp in zip(rep["pedals"], cal["pedal"]) for k in ("lo", "hi", "dead_zone"))
      and len(rep["pedals"]) == len(cal["pedal"]), rep["pedals"])
check("clocks", all(abs(rc["offset"]["value"] - cc["offset_ms"]) < 1e-6 and rc["device"] == cc["device"] for rc, cc in zip(rep["clocks"], cal["clock"]))
      and len(rep["clocks"]) == len(cal["clock"]), rep["clocks"])
check("every step passed", all(s["ok"] for s in rep["steps"]) and len(rep["steps"]) > 10, len(rep["steps"]))
check("the printed summary", rep["summary_text"].startswith("calibration summary") and "result: PASS" in rep["summary_text"])

# The page in headless Chromium, from the file alone.
flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", f"--user-data-dir={work}/profile", "--proxy-server=127.0.0.1:9",
         "--proxy-bypass-list=<-loopback>", "--enable-logging=stderr", "--v=0", "--virtual-time-budget=1000"]
page = subprocess.run(["chromium", *flags, "--dump-dom", f"file://{base}.report.html"], capture_output=True, text=True, timeout=60)
console = [l for l in page.stderr.splitlines() if ("CONSOLE" in l or "Uncaught" in l) and "level=0" not in l]
check("no console messages", not console, console[:3])
dom = page.stdout
check("the page finished drawing", 'data-rendered="yes"' in dom and "data-error=" not in dom)
for chart in ("chart-pivot-residuals", "chart-pivot-spread", "chart-fiducials", "chart-pedals", "chart-clocks"):
    m = re.search(rf'<canvas id="{chart}"[^>]*data-points="(\d+)"', dom)
    check(f"{chart} drawn with data", m is not None and int(m.group(1)) > 0, m and m.group(0))
check("PASS shown", 'class="result pass">PASS<' in dom, "")

# A calibration that fails still leaves its report (FAIL, no file named), and no calibration file.
rig_dir = os.path.join(work, "broken")
shutil.copytree(os.path.join(source, "rig/config/sim"), os.path.join(rig_dir, "sim"))
with open(os.path.join(rig_dir, "sim/calibration-tracker.sim"), "a") as f:
    f.write("fault 16000 60000 disconnect\n")  # while the fiducials are touched
shutil.copy(os.path.join(source, "rig/config/sim-calibration.toml"), rig_dir)
shutil.copy(os.path.join(source, "rig/config/sim-calibration.technician.toml"), rig_dir)
bad_out = os.path.join(work, "failed.toml")
b = run(os.path.join(rig_dir, "sim-calibration.toml"), bad_out)
check("the failed calibration exits 1", b.returncode == 1, b.returncode)
check("no calibration file from a failed run", not os.path.exists(bad_out))
bad = json.load(open(os.path.join(work, "failed.report.json")))
check("the failed run's report says FAIL", bad["result"] == "FAIL" and bad["calibration_file"] is None and bad["errors"], bad["result"])
check("and names the lost link", any("link lost" in e for e in bad["errors"]), bad["errors"][:3])

for f in failures:
    print("FAIL", f)
print(f"calibration report: {len(rep['pivots'])} pivots, {len(fr)} fiducials, {len(rep['pedals'])} pedal axes, "
      f"{len(rep['clocks'])} clocks; {len(failures)} failures")
shutil.rmtree(work, ignore_errors=True)
sys.exit(1 if failures else 0)

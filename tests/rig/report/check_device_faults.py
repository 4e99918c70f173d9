#!/usr/bin/env python3
"""The debrief's devices section against the session's telemetry, read independently of the report's
code (lcm_log.py parses the log from its specification; lcm-gen's Python classes decode the
device_status_t messages), and against the faults the fixture script injected
(device_faults.script.toml): the tracker stuck 2.0–2.6 s, its clock jumping at 3.0 s, its link gone
4.0–4.8 s, the pedals sending out-of-range samples 5.0–5.2 s.

usage: check_device_faults.py PYTHON_TYPES_DIR SESSION_DIR
"""
import json
import sys

from lcm_log import read_log

sys.path.insert(0, sys.argv[1])
from vitreo_lcm import device_status_t  # noqa: E402

session = sys.argv[2]
failures = []


def check(what, ok, detail=""):
    if not ok:
        failures.append(f"{what}: {detail}")


statuses = [device_status_t.decode(b) for chan, b in read_log(f"{session}/telemetry.lcmlog") if chan == "VITREO_DEVICE_STATUS"]
last = {}
for s in statuses:
    last[s.device_id] = s
report = json.load(open(f"{session}/report.json"))
devices = {d["device_id"]: d for d in report["devices"]}
check("one entry per device that published a status", sorted(devices) == sorted(last), f"{sorted(devices)} vs {sorted(last)}")

STATES = {0: "unconfigured", 1: "inactive", 2: "active", 3: "error", 4: "lost"}
for dev_id, s in last.items():
    d = devices.get(dev_id)
    if d is None:
        continue
    who = s.name
    check(f"{who}: name", d["name"] == s.name, d["name"])
    check(f"{who}: transport", d["transport"] == s.transport, d["transport"])
    check(f"{who}: calibration in force", d["calibration"] == s.calibration, d["calibration"])
    check(f"{who}: state at the end", d["state"] == STATES[s.state], f'{d["state"]} vs {s.state}')
    check(f"{who}: status messages", d["status_messages"] == sum(1 for x in statuses if x.device_id == dev_id), d["status_messages"])
    for field in ("frames_rx", "sequence_gaps", "heartbeat_misses", "reconnects", "stuck_episodes", "stuck_samples", "timestamp_jumps",
                  "reader_stalls"):
        check(f"{who}: {field}", d[field] == getattr(s, field), f"{d[field]} vs {getattr(s, field)}")
    for key, field in (("crc", "crc_errors"), ("framing", "framing_errors"), ("version", "version_rejected"),
                       ("unknown_type", "unknown_type_rejected"), ("length", "length_rejected"), ("range", "range_rejected"),
                       ("identity", "identity_rejected"), ("protocol", "protocol_rejected")):
        check(f"{who}: refused {key}", d["refused"][key] == getattr(s, field), f'{d["refused"][key]} vs {getattr(s, field)}')
    check(f"{who}: longest reader stall", abs(d["reader_stall_max"]["value"] - s.reader_stall_max_ms) < 1e-3, d["reader_stall_max"])

tracker = next((d for d in report["devices"] if d["name"] == "tracker-0"), None)
pedals = next((d for d in report["devices"] if d["name"] == "pedals"), None)
check("the tracker and the pedals are reported", tracker is not None and pedals is not None, [d["name"] for d in report["devices"]])
if tracker:
    def spells(what):
        return [s for s in tracker["spells"] if s["what"] == what]
    stuck, lost = spells("stuck"), spells("lost")
    # Stuck means 50 ms of bit-identical samples; a status goes out at once when the verdict changes,
    # carrying the session time it was taken at (in lockstep the step's), so the spell is timed to
    # the step however the telemetry thread was scheduled: 2.05 s (50 ms after the sensor hung) to
    # 2.6 s (its first moving sample), each to a tracker sample (1 ms) and a step.
    check("the tracker's stuck spell", len(stuck) == 1 and 2.049 <= stuck[0]["from"]["value"] <= 2.053 and stuck[0]["to"] is not None
          and 2.599 <= stuck[0]["to"]["value"] <= 2.603, stuck)
    tracker_statuses = [s for s in statuses if s.name == "tracker-0"]
    first_stuck = next((s for s in tracker_statuses if s.stuck), None)
    moving_again = next((s for s in tracker_statuses if first_stuck and s.t_s > first_stuck.t_s and not s.stuck), None)
    check("the stuck spell is timed by the statuses' own session time",
          stuck and first_stuck and moving_again and stuck[0]["from"]["value"] == first_stuck.t_s
          and stuck[0]["to"]["value"] == moving_again.t_s, (stuck, first_stuck and first_stuck.t_s, moving_again and moving_again.t_s))
    check("one stuck episode counted", tracker["stuck_episodes"] == 1, tracker["stuck_episodes"])
    check("samples frozen while stuck", tracker["stuck_samples"] > 50, tracker["stuck_samples"])
    # Lost once the link hangs up (or is silent past the rig's timeout), found again after the
    # reconnect, each end published at once with the session time of the step it happened at.
    check("the tracker's lost spell", len(lost) == 1 and 3.999 <= lost[0]["from"]["value"] <= 4.3 and lost[0]["to"] is not None
          and 4.799 <= lost[0]["to"]["value"] <= 5.2, lost)
    check("the reconnect", tracker["reconnects"] >= 1, tracker["reconnects"])
    check("the clock jump", tracker["timestamp_jumps"] >= 1, tracker["timestamp_jumps"])
    for words in ("stuck 1 time", "lost 1 time", "samples frozen while stuck", "timestamp jump", "reconnect"):
        check(f"the tracker's line says '{words}'", words in tracker["faults"], tracker["faults"])
    check("a notice names the tracker's faults", any(n.startswith("tracker-0 during the session: ") for n in report["notices"]),
          report["notices"])
if pedals:
    check("the pedals' out-of-range samples refused", pedals["refused"]["range"] > 0, pedals["refused"])
    check("the pedals' line says so", "out of range or NaN" in pedals["faults"], pedals["faults"])

html = open(f"{session}/report.html", encoding="utf-8").read()
check("the page has the devices tables", 'id="devices"' in html and 'id="device-spells"' in html, "")

for f in failures:
    print("FAIL", f)
if tracker:
    print("tracker-0:", tracker["faults"])
    print("  spells:", [(s["what"], s["from"]["value"], s["to"] and s["to"]["value"]) for s in tracker["spells"]])
if pedals:
    print("pedals:", pedals["faults"])
sys.exit(1 if failures else 0)

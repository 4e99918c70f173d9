#!/usr/bin/env python3
"""The report's numbers against the session's telemetry log, read independently of the code under test:
the LCM log framing parsed here from its specification (sync word, event number, timestamp, channel and
data lengths, big-endian), the messages decoded by the Python classes lcm-gen generates from the same
.lcm types (a different decoder from the C++ one the report uses), and the main job's console summary
(printed from the in-memory metrics, not from telemetry).

usage: check_numbers.py PYTHON_TYPES_DIR SESSION_DIR
"""
import json
import math
import re
import sys

from lcm_log import read_log

sys.path.insert(0, sys.argv[1])
from vitreo_lcm import (controls_t, criteria_t, event_t, instrument_state_t, score_t,  # noqa: E402
                        session_totals_t)

session = sys.argv[2]
failures = []


def check(what, ok, detail=""):
    if not ok:
        failures.append(f"{what}: {detail}")


events = read_log(f"{session}/telemetry.lcmlog")
by_chan = {}
for chan, body in events:
    by_chan.setdefault(chan, []).append(body)
scores = [score_t.decode(b) for b in by_chan.get("VITREO_SCORE", [])]
criteria = [criteria_t.decode(b) for b in by_chan.get("VITREO_CRITERIA", [])]
totals = [session_totals_t.decode(b) for b in by_chan.get("VITREO_TOTALS", [])]
states = [instrument_state_t.decode(b) for b in by_chan.get("VITREO_INSTRUMENT_STATE", [])]
evts = [event_t.decode(b) for b in by_chan.get("VITREO_EVENT", [])]
ctrls = [controls_t.decode(b) for b in by_chan.get("VITREO_CONTROLS", [])]
check("the log has score cards, criteria and totals", scores and criteria and totals, "missing")


def last_final(msgs):
    finals = [m for m in msgs if m.final_score]
    return finals[-1] if finals else msgs[-1]


score, crit, tot = last_final(scores), last_final(criteria), last_final(totals)
with open(f"{session}/report.json") as f:
    report = json.load(f)

# Score: total and every category, exactly as published.
check("total", report["score"]["total"]["value"] == score.total, f'{report["score"]["total"]} vs {score.total}')
check("pass score", report["case"]["pass_score"]["value"] == score.pass_score, f'{report["case"]["pass_score"]} vs {score.pass_score}')
# Completed: every criterion but the time limit met in the final criteria message; passed: completed
# with a final total at or above the pass score.
crit.met = list(crit.met)  # lcm-gen's decoder gives an iterator: read it once
completed = bool(score.final_score) and all(bool(m) or k == "time_limit" for k, m in zip(crit.kind, crit.met))
check("completed", report["case"]["completed"] == completed, report["case"]["completed"])
check("passed", report["case"]["passed"] == (completed and score.total >= score.pass_score), report["case"]["passed"])
check("final", report["score"]["final"] == bool(score.final_score))
cats = {c["name"]: c["value"]["value"] for c in report["score"]["categories"]}
check("categories", cats == dict(zip(score.name, score.value)), f"{cats} vs {dict(zip(score.name, score.value))}")
check("the categories' inputs reproduce the score", report["score"]["inputs_reproduce_published_score"] is True)
check("case id", report["case"]["id"] == score.case_id)
check("formula version", report["formula_version"] == tot.formula_version and tot.formula_version >= 1)

# Criteria.
rc = report["criteria"]
check("criteria count", len(rc) == crit.n, f"{len(rc)} vs {crit.n}")
met = list(crit.met)
for i, c in enumerate(rc[:crit.n]):
    check(f"criterion {i}", (c["kind"], c["target"], c["value"]["value"], c["threshold"]["value"], c["progress"]["value"], c["met"]) ==
          (crit.kind[i], crit.target[i], crit.value[i], crit.threshold[i], crit.progress[i], bool(met[i])), str(c))

# Totals: contacts, path lengths (all and per instrument), forces, iatrogenic events.
t = report["totals"]
for key, val in [("retina_contacts", tot.retina_contacts), ("path_length", tot.path_length_mm),
                 ("peak_retina_force", tot.peak_retina_force_un), ("time_over_force_limit", tot.time_over_force_limit_s),
                 ("iatrogenic_events", tot.iatrogenic_events), ("retina_tears", tot.retina_tears)]:
    check(f"totals {key}", t[key]["value"] == val, f'{t[key]["value"]} vs {val}')
check("per-instrument totals", [(i["kind"], i["path_length"]["value"], i["retina_contacts"]["value"]) for i in t["instruments"]] ==
      list(zip(tot.instrument_kind, tot.instrument_path_mm, tot.instrument_contacts)))
check("per-instrument paths add up to the total", math.isclose(sum(tot.instrument_path_mm), tot.path_length_mm, rel_tol=1e-9))

# Events: every one in the report, counted by name.
counts = {}
for e in evts:
    counts[e.what] = counts.get(e.what, 0) + 1
check("event counts", {k: v["value"] for k, v in report["event_counts"].items()} == counts, f'{report["event_counts"]} vs {counts}')
check("event list", len(report["events"]) == len(evts))

# Hands: samples and the sampled tip path (inside the eye) recomputed here.
for hand in report["hands"]:
    own = [s for s in states if s.instrument_id == hand["tracker"]]
    check(f"hand {hand['tracker']} samples", hand["samples"] == len(own))
    path, prev = 0.0, None
    for s in own:
        inside = s.port_id >= 0 and s.insertion_mm > 0
        if prev is not None and inside and prev.port_id >= 0 and prev.insertion_mm > 0 and s.t_s > prev.t_s:
            path += math.dist(s.tip_mm, prev.tip_mm)
        prev = s
    check(f"hand {hand['tracker']} sampled path", math.isclose(hand["sampled_path_length"]["value"], path, rel_tol=1e-9, abs_tol=1e-9),
          f'{hand["sampled_path_length"]["value"]} vs {path}')
    peak = max((s.retina_force_un for s in own), default=0.0)
    check(f"hand {hand['tracker']} peak force", hand["peak_retina_force"]["value"] == peak)

# The pedals' travel and the macula's light dose: every sample of the log (the fixture's 2000 are
# under the report's 2500-point thinning), axis by axis. (The fixture's forceps peel uses no pedal:
# the telemetry contract test checks the travel of a pressed pedal against the vacuum it set.)
c = report["controls"]
check("controls samples", c["t"] == [m.t_s for m in ctrls], f'{len(c["t"])} vs {len(ctrls)}')
for name, attr in [("vitrectomy_pedal_travel", "vitrectomy_pedal_travel"), ("microscope_pedal_travel", "microscope_pedal_travel")]:
    check(f"{name} axes", len(c[name]) == 4, len(c[name]))
    for a in range(4):
        check(f"{name} axis {a}", c[name][a] == [getattr(m, attr)[a] for m in ctrls])
check("macular light dose", c["macula_light_dose"] == [m.macula_light_dose_j_cm2 for m in ctrls])
check("the dose only accumulates", all(b >= a for a, b in zip(c["macula_light_dose"], c["macula_light_dose"][1:])))
check("light dose limit", c["light_dose_limit"] == ctrls[-1].light_dose_limit_j_cm2 and c["light_dose_limit"] > 0, c["light_dose_limit"])

# The main job's console summary (from the in-memory metrics) against the report.
summary = open(f"{session}/summary.txt").read()
m = re.search(r"score\s+(\d+) / 100", summary)
check("summary total", m and int(m.group(1)) == round(report["score"]["total"]["value"]), m and m.group(0))
m = re.search(r"handling: path ([\d.]+) mm, (\d+) retina contacts .*peak retina force (\d+) uN", summary)
check("summary handling line", m is not None, "not found")
if m:
    check("summary path", abs(float(m.group(1)) - t["path_length"]["value"]) <= 0.05, m.group(0))
    check("summary contacts", int(m.group(2)) == t["retina_contacts"]["value"], m.group(0))
    check("summary peak force", abs(int(m.group(3)) - t["peak_retina_force"]["value"]) <= 0.5, m.group(0))
m = re.search(r"iatrogenic events (\d+)", summary)
check("summary iatrogenic events", m and int(m.group(1)) == t["iatrogenic_events"]["value"])
# The session must be one worth checking: contacts and harm happened.
check("the fixture session touched the retina", t["retina_contacts"]["value"] > 0 and t["iatrogenic_events"]["value"] > 0)

for f in failures:
    print("FAIL", f)
print(f"{len(events)} log events; score {score.total:.3f}; {tot.retina_contacts} contacts; path {tot.path_length_mm:.3f} mm; "
      f"{len(evts)} events; {len(failures)} failures")
sys.exit(1 if failures else 0)

#!/usr/bin/env python3
"""The guided calibration (label calibration): vitreo-calibrate without --non-interactive, at the
simulated calibration rig in real time, its emulators playing the scripted technician's motions
(rig/config/sim-calibration.technician.toml) while this test answers the prompts as a technician at
the bench would: Enter to start each step, the pivot's Enter only once the tip rests in the divot.

The pivot is first ended too early on purpose (Enter twice while the tip is still on its way): the
step fails, is offered again, and passes the second time. The calibration it writes is checked
against the truth the emulator scripts inject (rig/config/sim/calibration-*.sim), independently of
the tool's own numbers; a technician who gives up at once leaves no file.

When the tip rests in the divot comes from the scripted run's recording (its `step pivot` window),
not from the guided tool.

usage: guided_test.py VITREO_CALIBRATE SOURCE_DIR
"""
import math
import os
import re
import subprocess
import sys
import tempfile
import time

calibrate, source = sys.argv[1], sys.argv[2]
rig = os.path.join(source, "rig/config/sim-calibration.toml")
technician = os.path.join(source, "rig/config/sim-calibration.technician.toml")
failures = []


def check(what, ok, detail=""):
    print(("ok: " if ok else "FAIL: ") + what + ("" if ok else f" ({detail})"))
    if not ok:
        failures.append(what)


work = tempfile.mkdtemp(prefix="vitreo-guided-")
scripted = subprocess.run([calibrate, "--rig", rig, "--out", os.path.join(work, "scripted.toml"), "--non-interactive"],
                          capture_output=True, text=True, timeout=300)
check("the scripted run passes (it gives the technician's timeline)", scripted.returncode == 0, scripted.stdout[-400:])
pivot_window = None
with open(os.path.join(work, "scripted.recording")) as f:
    for line in f:
        if line.startswith("step pivot "):
            pivot_window = tuple(float(x) for x in line.split()[4:6])
            break
check("the recording has the pivot's window", pivot_window is not None)

out_path = os.path.join(work, "guided.toml")
tool = subprocess.Popen([calibrate, "--rig", rig, "--out", out_path, "--technician-script", technician],
                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
log = []
prompt = re.compile(r"^step (\d+) of (\d+) \[\s*([\d.]+) s\] (\S+): (.*)$")
pivot_tries = 0
retries = 0
started = time.monotonic()


def send(text):
    tool.stdin.write(text + "\n")
    tool.stdin.flush()


for line in tool.stdout:
    line = line.rstrip("\n")
    log.append(line)
    m = prompt.match(line)
    if m:
        t, instruction = float(m.group(3)), m.group(5)
        if "swing the handle" in instruction:
            pivot_tries += 1
            if pivot_tries == 1:
                send("")  # started while the hand is still on its way to the divot …
                time.sleep(0.3)
                send("")  # … and ended at once: too few poses, too little spread
            else:
                time.sleep(max(0.0, pivot_window[0] + 0.2 - t))  # the tip rests in the divot now
                send("")
        else:
            send("")
    elif line.startswith("  Enter: do it again"):
        retries += 1
        send("" if retries < 4 else "q")
    if time.monotonic() - started > 240:
        tool.kill()
        break
rc = tool.wait(timeout=60)
text = "\n".join(log)
check("the guided run ends with the calibration written", rc == 0 and "result: PASS" in text and os.path.exists(out_path),
      f"rc {rc}: " + text[-1500:])
check("it told each step (15, the clocks measured throughout) and showed live feedback",
      "step 15 of 15" in text and re.search(r"\d+ samples, spread [\d.]+°, RMS", text) is not None
      and re.search(r"\] moving \([\d.]+ mm\)", text) is not None and re.search(r"reads [\d.]+ \(lowest", text) is not None, text[-800:])
check("the pivot ended too early failed and was done again", pivot_tries == 2 and retries == 1, f"{pivot_tries} tries, {retries} retries")
# Each touch was taken once the tip was still on its own point: every fiducial's own residual is
# small (a touch taken on the way, or on the point before, would be millimetres off).
residuals = re.search(r"residual per fiducial \(mm\):((?: [\d.]+)+)", text)
check("every touch was taken on its own point, held still", residuals is not None and max(float(x) for x in residuals.group(1).split()) < 0.05,
      residuals and residuals.group(1))

# Against the truth injected into the emulators: tip offset (0.8, -0.5, 14.0) mm, the fixture's ports.
if os.path.exists(out_path):
    import tomllib
    cal = tomllib.load(open(out_path, "rb"))
    tip = cal["instrument"][0]["tip_offset_mm"]
    tip_error = math.dist(tip, [0.8, -0.5, 14.0])
    check("tip offset within 0.1 mm", tip_error < 0.1, tip_error)
    rho = math.sqrt(144 - 4.6 ** 2)
    ports = {p["port"]: p["position_mm"] for p in cal["port"]}
    port_error = max(math.dist(ports[i], [(-1 if i == 0 else 1) * rho * math.cos(math.pi / 6), rho * 0.5, 4.6]) for i in (0, 1))
    check("ports within 0.2 mm", port_error < 0.2, port_error)
    pedal = {(p["pedal"], p["axis"]): (p["lo"], p["hi"]) for p in cal["pedal"]}
    pedal_error = max(abs(pedal[(0, 0)][0] - 0.07), abs(pedal[(0, 0)][1] - 0.91), abs(pedal[(0, 1)][0] - 0.12), abs(pedal[(0, 1)][1] - 0.86))
    check("pedal ranges within 0.02", pedal_error < 0.02, pedal_error)
    print(f"guided: tip {tip_error:.4f} mm, ports {port_error:.4f} mm, pedals {pedal_error:.4f}")
check("the guided run left its recording", os.path.exists(os.path.join(work, "guided.recording")))

# Giving up at once: nothing written, the previous calibration kept.
with open(os.path.join(work, "kept.toml"), "w") as f:
    f.write("the previous calibration\n")
quit_run = subprocess.run([calibrate, "--rig", rig, "--out", os.path.join(work, "kept.toml"), "--technician-script", technician],
                          input="q\n", capture_output=True, text=True, timeout=60)
check("q gives up: exit 3, the previous file kept", quit_run.returncode == 3 and "given up" in quit_run.stderr
      and open(os.path.join(work, "kept.toml")).read() == "the previous calibration\n", quit_run.returncode)

for f in failures:
    print("FAIL", f)
if failures:
    print("\n".join(log[-60:]))
sys.exit(1 if failures else 0)

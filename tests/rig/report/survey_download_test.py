#!/usr/bin/env python3
"""The survey form as an instructor uses it: headless Chromium, driven through the DevTools protocol
(over --remote-debugging-pipe: NUL-separated JSON on descriptors 3 and 4, no extra library), opens the
session's report.html from the file, the answers are chosen in the form (each select set and its
change event fired, as a choice does; the subject typed as keystrokes), and "Save survey.json" is
pressed with a real mouse click. The file the browser downloads is the page's own output: saved into
the session folder, vitreo-report reads it, checks it and shows it with its rating.

usage: survey_download_test.py VITREO_REPORT SESSION_DIR
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

report, session = sys.argv[1], sys.argv[2]
work = tempfile.mkdtemp()
signal.alarm(90)  # a hang fails the test instead of blocking the suite


def fail(why):
    print("FAIL", why)
    sys.exit(1)


# A copy of the session folder with a fresh report (no survey yet).
folder = os.path.join(work, "session")
os.makedirs(folder)
for name in ("telemetry.lcmlog", "session.lcmlog", "trainee.txt"):
    if os.path.exists(os.path.join(session, name)):
        shutil.copy(os.path.join(session, name), folder)
subprocess.run([report, folder, "--generated", "test"], check=True, stdout=subprocess.DEVNULL)
downloads = os.path.join(work, "downloads")
os.makedirs(downloads)

# Chromium reads commands on descriptor 3 and writes replies and events on descriptor 4.
to_chrome_r, to_chrome_w = os.pipe()
from_chrome_r, from_chrome_w = os.pipe()


def wire_pipes():
    hi_r, hi_w = os.dup(to_chrome_r) + 100, os.dup(from_chrome_w) + 100
    os.dup2(to_chrome_r, hi_r)
    os.dup2(from_chrome_w, hi_w)
    os.dup2(hi_r, 3)
    os.dup2(hi_w, 4)


chrome = subprocess.Popen(
    ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", f"--user-data-dir={work}/profile",
     "--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>", "--remote-debugging-pipe", "--window-size=1200,2000",
     "about:blank"],
    preexec_fn=wire_pipes, pass_fds=(3, 4), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
os.close(to_chrome_r)
os.close(from_chrome_w)
buffer = b""
next_id = 0
pending_events = []


def read_message():
    global buffer
    while b"\0" not in buffer:
        chunk = os.read(from_chrome_r, 1 << 16)
        if not chunk:
            fail("chromium closed the DevTools pipe")
        buffer += chunk
    msg, buffer = buffer.split(b"\0", 1)
    return json.loads(msg)


def send(method, params=None, session_id=None):
    global next_id
    next_id += 1
    msg = {"id": next_id, "method": method, "params": params or {}}
    if session_id:
        msg["sessionId"] = session_id
    os.write(to_chrome_w, json.dumps(msg).encode() + b"\0")
    while True:
        m = read_message()
        if m.get("id") == next_id:
            if "error" in m:
                fail(f"{method}: {m['error']}")
            return m.get("result", {})
        pending_events.append(m)


def wait_event(method, predicate=lambda p: True, timeout_s=30):
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        for i, m in enumerate(pending_events):
            if m.get("method") == method and predicate(m.get("params", {})):
                return pending_events.pop(i)["params"]
        pending_events.append(read_message())
    fail(f"no {method} within {timeout_s} s")


try:
    target = send("Target.createTarget", {"url": "about:blank"})["targetId"]
    sid = send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    send("Browser.setDownloadBehavior", {"behavior": "allow", "downloadPath": downloads, "eventsEnabled": True})
    send("Page.enable", {}, sid)
    send("Page.navigate", {"url": "file://" + os.path.join(folder, "report.html")}, sid)
    wait_event("Page.loadEventFired")

    def js(expr):
        r = send("Runtime.evaluate", {"expression": expr, "returnByValue": True, "awaitPromise": True}, sid)
        if "exceptionDetails" in r:
            fail(f"page script: {r['exceptionDetails']}")
        return r["result"].get("value")

    def centre_of(selector):
        box = js(f"(() => {{ const e = document.querySelector({json.dumps(selector)}); e.scrollIntoView({{block: 'center'}});"
                 " const r = e.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; })()")
        if not box:
            fail(f"{selector} not on the page")
        return box

    def click(selector):
        x, y = centre_of(selector)
        for kind in ("mousePressed", "mouseReleased"):
            send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left", "clickCount": 1}, sid)

    # The subject typed, the date typed, the answers chosen.
    click("#survey-form input[name=subject]")
    send("Input.insertText", {"text": "fellow-07"}, sid)
    click("#survey-form input[name=date]")
    send("Input.insertText", {"text": "2026-11-27"}, sid)

    def choose(name, value):
        ok = js(f"(() => {{ const s = document.querySelector('#survey-form [name={name}]'); if (!s || s.disabled) return false;"
                f" s.value = {json.dumps(value)}; if (s.value !== {json.dumps(value)}) return false;"
                " s.dispatchEvent(new Event('change', {bubbles: true})); return true; })()")
        if not ok:
            fail(f"the form has no enabled choice {value} for {name}")

    choose("accomplished", "true")
    choose("errors_small", "true")
    choose("workload_acceptable", "false")  # → the workload page
    choose("level", "medium")
    for cat in ("tracking", "physical_interface", "instrumentation"):
        choose(f"cat_{cat}", "somewhat_high")
    choose("ins_forceps", "very_good")
    click("#survey-form input[name=comment_forceps]")
    send("Input.insertText", {"text": "grips well"}, sid)
    click("#survey-form textarea[name=comments]")
    send("Input.insertText", {"text": "typed in the browser"}, sid)

    click("#survey-save")
    done = wait_event("Browser.downloadProgress", lambda p: p.get("state") in ("completed", "canceled"))
    if done["state"] != "completed":
        fail(f"the download was {done['state']}")
finally:
    chrome.terminate()
    chrome.wait(timeout=30)

saved = os.path.join(downloads, "survey.json")
if not os.path.exists(saved):
    fail(f"no survey.json among the downloads: {os.listdir(downloads)}")
survey = json.load(open(saved))
expect = {"format": "vitreo-survey-1", "subject": "fellow-07", "date": "2026-11-27", "accomplished": True, "errors_small": True,
          "workload_acceptable": False, "level": "medium", "comments": "typed in the browser"}
for k, v in expect.items():
    if survey.get(k) != v:
        fail(f"downloaded survey.json: {k} = {survey.get(k)!r}, chosen {v!r}")
if survey["categories"] != {c: "somewhat_high" for c in ("tracking", "physical_interface", "instrumentation")}:
    fail(f"categories {survey['categories']}")
if survey["instruments"].get("forceps") != {"rating": "very_good", "comment": "grips well"}:
    fail(f"instruments {survey['instruments']}")

# Saved into the session folder, the next report reads and shows it.
shutil.copy(saved, folder)
out = subprocess.run([report, folder, "--generated", "test"], capture_output=True, text=True)
if "survey: modified Cooper-Harper rating 5.0 of 10" not in out.stdout:
    fail(f"vitreo-report did not show the downloaded survey (workload page, medium: rating 5):\n{out.stdout}{out.stderr}")
shown = json.load(open(os.path.join(folder, "report.json")))["survey"]
if shown["subject"] != "fellow-07" or shown["cooper_harper_rating"]["value"] != 5:
    fail(f"report.json survey: {shown}")
shutil.rmtree(work)
print("survey download: the form's file read back by vitreo-report, rating 5 of 10")

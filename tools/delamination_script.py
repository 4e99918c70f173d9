#!/usr/bin/env python3
"""delamination_script.py STALKS CASE MEMBRANE OUT [tip_h] [roll] [slope_deg] [speed] [kind] [port_t] [passes]

Writes a surgical script (scenes/scripts/README.md) that delaminates an elevated band with horizontal
scissors: for each stalk, the jaws are opened 1.4 mm back along the shaft, slid in along it until the
closed tip stands tip_h mm above the wall, and closed three times (0.1 mm to either side of the stalk,
then 0.15 mm deeper), so that the stalk lies about half-way along the jaws' mouth.

STALKS is a table of the band's stalks in the settled start, one line "A index holds strong toward
across height force" each, with a "# centroid ... height H" line: toward/across are where the strand
crosses 0.55 mm above the wall, in the script's frame at the band's centroid (the ray from the globe's
centre met with the tangent plane there — how surgical_script.cpp resolves toward_port_mm/across_mm).
It was printed from the settled 5k start by a probe program (not shipped) reading the case with
rig/scene_io/case_loader.hpp; port_t is the port's distance in that tangent plane, slope_deg the
shaft's angle to it, roll the roll that turns the jaws into the plane most nearly parallel to the
retina (the vitrector's port-inward roll less 90°). The traction cases' scripts say which values.

Why this shape: the jaws (1 mm, 25° half-opening) cut a stalk only where they sweep across it while
closing (core/instruments/topology_adapter.cpp); a stalk's strand moves once its neighbours are cut,
and a single close a stalk missed one in five.
"""
import sys, math
dump, case, mem, out = sys.argv[1:5]
tip_h = float(sys.argv[5]) if len(sys.argv) > 5 else 0.3
roll = float(sys.argv[6]) if len(sys.argv) > 6 else 15.7
slope_deg = float(sys.argv[7]) if len(sys.argv) > 7 else 32.8
speed = float(sys.argv[8]) if len(sys.argv) > 8 else 2.0
kind = sys.argv[9] if len(sys.argv) > 9 else 'test'
ch = None; stalks = []
for line in open(dump):
    if line.startswith('# centroid'): ch = float(line.split('height')[1].split(',')[0])
    if line.startswith('A '):
        f = line.split()
        if f[2] == 'gone': continue
        stalks.append((float(f[4]), float(f[5])))
cs, sn = math.cos(math.radians(slope_deg)), math.sin(math.radians(slope_deg))
hinge_back = 1.0 * cs          # horizontal hinge offset toward the port from the closed tip
reach = 0.906 * cs             # open jaw tips, horizontally from the hinge
place = 0.5 * cs               # where the first stalk sits from the hinge
half = math.radians(22.0)
PORT_T = float(sys.argv[10]) if len(sys.argv) > 10 else 10.27
# band axis by PCA, to order stalks along it
n = len(stalks); mt = sum(s[0] for s in stalks)/n; ma = sum(s[1] for s in stalks)/n
stt = sum((s[0]-mt)**2 for s in stalks); saa = sum((s[1]-ma)**2 for s in stalks); sta = sum((s[0]-mt)*(s[1]-ma) for s in stalks)
ang = 0.5*math.atan2(2*sta, stt-saa); ax = (math.cos(ang), math.sin(ang))
order = sorted(range(n), key=lambda i: (stalks[i][0]-mt)*ax[0] + (stalks[i][1]-ma)*ax[1])
left = set(range(n)); sectors = []
for i in order:
    if i not in left: continue
    t, a = stalks[i]
    # the shaft's horizontal direction toward the port (at PORT_T along toward, across 0)
    dx, dy = PORT_T - t, -a; L = math.hypot(dx, dy); dx /= L; dy /= L
    P = (t - (hinge_back - place) * dx, a - (hinge_back - place) * dy)      # the closed tip
    H = (P[0] + hinge_back * dx, P[1] + hinge_back * dy)
    got = []
    for j in list(left):
        rx, ry = stalks[j][0] - H[0], stalks[j][1] - H[1]
        dt = -(rx * dx + ry * dy); da = rx * (-dy) + ry * dx
        if 0.08 < dt < reach - 0.05 and abs(da) < math.tan(half) * dt: got.append(j)
    if i not in got: got.append(i)
    for j in got: left.discard(j)
    sectors.append((P[0], P[1], dx, dy))
hdr = f'''[script]
version = 1
case = "{case}"
kind = "{kind}"
summary = "SUMMARY"
duration_s = DURATION
[[hand]]
tracker = 0
speed_mm_s = 8.0
[[hand.waypoint]]
to = "port"
above_mm = 3.0
duration_s = 0.0
tool = "scissors"
jaws = 1.0
'''
PASSES = int(sys.argv[11]) if len(sys.argv) > 11 else 1
plan = sectors + (sectors[::-1] if PASSES > 1 else [])
body = ''; T = 2.0; stand = 1.4
DITHER = [(-0.1, 0.0), (0.1, 0.0), (0.0, -0.15)]
def wp(t, a, extra):
    return f'''[[hand.waypoint]]
to = "membrane.{mem}"
toward_port_mm = {t:.3f}
across_mm = {a:.3f}
above_mm = {tip_h - ch:.3f}
''' + extra
for k, (t0, a0, dx, dy) in enumerate(plan):
    for j, (lat, rad) in enumerate(DITHER):
        # lat: sideways of the shaft; rad: along it (negative: deeper, away from the port)
        t = t0 + lat * (-dy) + rad * dx; a = a0 + lat * dx + rad * dy
        if j == 0:
            body += wp(t, a, f'standoff_mm = {stand}\nroll_deg = {roll}\njaws = 0.0\nspeed_mm_s = 4.0\n')
            # The expert centres the microscope's field on each stalk as the jaws slide in to it.
            body += wp(t, a, f'speed_mm_s = {speed}\n' + ('look_at = "target"\n' if kind == 'expert' else ''))
            T += 1.2 + stand / speed
        else:
            body += wp(t0 + DITHER[j-1][0] * (-dy) + DITHER[j-1][1] * dx, a0 + DITHER[j-1][0] * dx + DITHER[j-1][1] * dy, 'duration_s = 0.15\njaws = 0.0\n')
            body += wp(t, a, 'duration_s = 0.15\n')
            T += 0.3
        body += wp(t, a, 'duration_s = 0.25\njaws = 1.0\n')
        T += 0.25
body += f'''[[hand.waypoint]]
to = "membrane.{mem}"
toward_port_mm = {plan[-1][0]:.3f}
across_mm = {plan[-1][1]:.3f}
above_mm = {tip_h - ch:.3f}
standoff_mm = {stand}
speed_mm_s = {speed}
[[hand.waypoint]]
to = "port"
above_mm = 3.0
'''
open(out, 'w').write(hdr.replace('DURATION', f'{T + 3:.1f}') + body)
print(f'{n} stalks, {len(sectors)} sectors, duration {T+3:.1f}', file=sys.stderr)

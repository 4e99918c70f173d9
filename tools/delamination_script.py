#!/usr/bin/env python3
"""delamination_script.py SITES CASE MEMBRANE OUT [--kind K] [--tip-h MM] [--roll DEG] [--slope-deg DEG]
                          [--speed MM_S] [--tremor MM --seed N] [--side MM] [--deeper MM]
                          [--order along|back|far-first] [--passes N] [--retreat MM] [--summary TEXT] [--comment FILE]

Writes a surgical script (scenes/scripts/README.md) that delaminates an elevated band with horizontal
scissors: for each stalk, the jaws are opened 1.4 mm back along the shaft, slid in along it until the
closed tip stands tip_h mm above the wall, and closed three times (0.1 mm to either side of the stalk,
then 0.15 mm deeper), so that the stalk lies about half-way along the jaws' mouth.

SITES is the band's attachment-site table in the settled start, as `vitreo-cases sites CASE MEMBRANE`
prints it: one line "site N attachment state strength ts as tc ac foot_h" per lattice site, where
(ts, as) is where the stalk's strand crosses 0.55 mm above the wall in the frame of the site's own
landmark (membrane.NAME.site.N: the wall under the stalk's foot; toward_port_mm points at the hand's
port) and (tc, ac) the same in the frame of the band's centre. Every waypoint names its stalk's site,
so the script follows the stalks wherever a mesh puts them: the sites are fixed in millimetres by
the case (attachment_spacing_mm), the same at 5k and at the case's own resolution. The table from
either resolution gives nearly the same script; the shipped ones are written from the 5k table.

The stalks are cut in order along the band (its long axis in the centre's frame), or the row farther
from the port first (--order far-first: the circumferential band's experts, whose far stalks' strands
move once their near neighbours are cut), and --passes 2 goes back over them all; roll is the roll
that turns the jaws into the plane most nearly parallel to the retina (the vitrector's port-inward
roll less 90°), slope_deg the shaft's angle to the fundus there (it sets how far the hinge stands
back from the closed tip).

The shipped scripts, from `vitreo-cases sites scenes/CASE.toml BAND --retina-vertices 5000`:
  traction_anteroposterior (ap_band) expert: --roll 15.7
                                     clumsy: --roll 15.7 --tip-h 0.12 --speed 3 --tremor 0.02 --seed 3
  traction_circumferential (band)    expert: --roll 26.2 --order far-first --passes 2
                                     clumsy: the expert's, with --tip-h 0.18 --speed 3 --tremor 0.03 --seed 3 --retreat 3
each with --kind, --summary and the file's own comment block (--comment).

Why this shape: the jaws (1 mm, 25° half-opening) cut a stalk only where they sweep across it while
closing (core/instruments/topology_adapter.cpp); a stalk's strand moves once its neighbours are cut,
and a single close missed one stalk in five.
"""
import argparse
import math

p = argparse.ArgumentParser()
p.add_argument('sites'); p.add_argument('case'); p.add_argument('membrane'); p.add_argument('out')
p.add_argument('--kind', default='expert')
p.add_argument('--tip-h', type=float, default=0.25)
p.add_argument('--roll', type=float, default=15.7)
p.add_argument('--slope-deg', type=float, default=32.8)
p.add_argument('--speed', type=float, default=2.0)
p.add_argument('--tremor', type=float, default=0.0)
p.add_argument('--seed', type=int, default=1)
p.add_argument('--summary', default='')
p.add_argument('--side', type=float, default=0.1, help='each stalk: closes this far to either side of it (mm)')
p.add_argument('--deeper', type=float, default=0.15, help='then one this far deeper, away from the port (mm)')
p.add_argument('--order', default='along', choices=['along', 'back', 'far-first'], help='along the band, back along it, or the far row (away from the port) first')
p.add_argument('--passes', type=int, default=1, help='2: then back along the band again, for stalks a close missed; 3: and along it once more')
p.add_argument('--retreat', type=float, default=0.0, help='after each stalk, back the open jaws this much farther out along the shaft before the next (mm)')
p.add_argument('--comment', help='a file whose text heads the script (its comment block)')
a = p.parse_args()

stalks = []  # (site, ts, as, tc, ac)
for line in open(a.sites):
    f = line.split()
    if not f or f[0] != 'site' or f[2] == 'none' or f[3] == 'gone':
        continue
    stalks.append((int(f[1]), float(f[5]), float(f[6]), float(f[7]), float(f[8])))
n = len(stalks)
# The band's long axis in the centre's frame (principal axis), to cut the stalks in order along it.
mt = sum(s[3] for s in stalks) / n; ma = sum(s[4] for s in stalks) / n
stt = sum((s[3] - mt) ** 2 for s in stalks); saa = sum((s[4] - ma) ** 2 for s in stalks)
sta = sum((s[3] - mt) * (s[4] - ma) for s in stalks)
ang = 0.5 * math.atan2(2 * sta, stt - saa)
along = lambda s: (s[3] - mt) * math.cos(ang) + (s[4] - ma) * math.sin(ang)
order = sorted(stalks, key=along)
if a.order == 'back':
    order = order[::-1]
elif a.order == 'far-first':  # toward_port_mm from the centre: the far row has the smaller values
    mid = sorted(s[3] for s in stalks)[n // 2]
    order = sorted((s for s in stalks if s[3] < mid), key=along) + sorted((s for s in stalks if s[3] >= mid), key=along)

back = 0.5 * math.cos(math.radians(a.slope_deg))  # the closed tip stands this far past the stalk, away from the port
stand = 1.4
DITHER = [(-a.side, 0.0), (a.side, 0.0), (0.0, -a.deeper)]  # (sideways, along the shaft: negative is deeper)


def wp(site, t, c, extra):
    return (f'[[hand.waypoint]]\nto = "membrane.{a.membrane}.site.{site}"\ntoward_port_mm = {t:.3f}\n'
            f'across_mm = {c:.3f}\nabove_mm = {a.tip_h:.3f}\n' + extra)


body = ''; T = 2.0
plan = [s for k in range(a.passes) for s in (order if k % 2 == 0 else order[::-1])]  # there, back, there...
for site, ts, cs, _, _ in plan:
    # In the site's frame the port lies straight along toward_port_mm: the shaft's sideways is across.
    t0, c0 = ts - back, cs
    for j, (lat, rad) in enumerate(DITHER):
        t, c = t0 + rad, c0 + lat
        if j == 0:
            body += wp(site, t, c, f'standoff_mm = {stand}\nroll_deg = {a.roll}\njaws = 0.0\nspeed_mm_s = 4.0\n')
            # The expert centres the microscope's field on each stalk as the jaws slide in to it.
            body += wp(site, t, c, f'speed_mm_s = {a.speed}\n' + ('look_at = "target"\n' if a.kind == 'expert' else ''))
            T += 1.2 + stand / a.speed
        else:
            pl, pr = DITHER[j - 1]
            body += wp(site, t0 + pr, c0 + pl, 'duration_s = 0.15\njaws = 0.0\n')
            body += wp(site, t, c, 'duration_s = 0.15\n')
            T += 0.3
        body += wp(site, t, c, 'duration_s = 0.25\njaws = 1.0\n')
        T += 0.25
    if a.retreat > 0:  # a novice backs out to look again before each stalk: time and path spent for nothing
        body += wp(site, t0, c0, f'standoff_mm = {stand + a.retreat}\nspeed_mm_s = 4.0\n')
        T += (stand + a.retreat) / 4.0
site, ts, cs, _, _ = plan[-1]
body += wp(site, ts - back, cs, f'standoff_mm = {stand}\nspeed_mm_s = {a.speed}\n')
body += '[[hand.waypoint]]\nto = "port"\nabove_mm = 3.0\n'

head = open(a.comment).read() if a.comment else ''
summary = a.summary or (f'horizontal scissors slid under the elevated band along their own shaft, closed across each of its '
                        f'{n} stalks (three closes a stalk, 0.1 mm either side and 0.15 mm deeper), jaws {a.tip_h} mm off the retina')
script = f'''[script]
version = 1
case = "{a.case}"
kind = "{a.kind}"
summary = "{summary}"
duration_s = {T + 3:.1f}
'''
if a.tremor > 0:
    script += f'tremor_mm = {a.tremor}\nseed = {a.seed}\n'
script += '''[[hand]]
tracker = 0
speed_mm_s = 8.0
[[hand.waypoint]]
to = "port"
above_mm = 3.0
duration_s = 0.0
tool = "scissors"
jaws = 1.0
'''
open(a.out, 'w').write(head + script + body)
print(f'{n} stalks, duration {T + 3:.1f} s', flush=True)

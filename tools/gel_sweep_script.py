#!/usr/bin/env python3
"""Writes the gel cases' surgical scripts (scenes/scripts/README.md): a vitrector sweeping the inner
vitreous shells in rings around the eye's optical axis, posterior pole first, with the light pipe
following it when the hand uses one. Rings and waypoints are too many to write by hand, so the
scripts in scenes/scripts/ are this tool's output; rerun it after changing the anatomy.

  tools/gel_sweep_script.py core_vitrectomy expert > scenes/scripts/core_vitrectomy.expert.toml

Geometry (eye frame, mm; anterior is +z): the default anatomy's inner wall radius by polar angle from
the posterior pole (measured on the settled core_vitrectomy start; the gel shells lie 2.5 mm inside
one another, anatomy.gel_shell_spacing_mm), the lens and the two working ports. Waypoints are offsets
from the case's region of interest (the fovea at the pole, 11.05 mm behind the centre), so they do
not depend on the retina's resolution. Points whose straight shaft would pass within 0.8 mm of the
lens are left out."""
import math
import sys

WALL_RADIUS_BY_10_DEG = [11.05, 11.06, 11.08, 11.12, 11.16, 11.19, 11.23, 11.27, 11.29, 11.29, 11.24, 11.13]
SHELL_SPACING = 2.5
ROI = (0.0, 0.0, -11.05)
WORKING_1, WORKING_2 = (-7.107, 4.103, 6.670), (7.107, 4.103, 6.670)
LENS_Z, LENS_RADIUS, LENS_HALF_THICKNESS = 6.45, 4.75, 2.0

# What each script does: the inner shells to sweep, speed (mm/s), ring spacing along the shell (mm),
# the last ring's polar angle (deg), vacuum, light pipe, passes (a second one offset by half a
# spacing), hunting moves through the empty centre before the sweep.
PLANS = {
    ("core_vitrectomy", "expert"): dict(shells=(2, 1), speed=3.0, spacing=2.2, theta_max=90, vacuum=1.0, light=True, passes=1, hunts=0,
        summary="sweeps the two inner shells in rings 2.2 mm apart at 3 mm/s, full vacuum and 10 000 cpm, the light pipe following 4 mm back"),
    ("core_vitrectomy", "clumsy"): dict(shells=(2, 1), speed=4.5, spacing=3.0, theta_max=90, vacuum=1.0, light=False, passes=2, hunts=30,
        summary="no light pipe: hunts for the gel through the centre, then sweeps too fast with rings too far apart and needs a second pass"),
    ("exercise_remove_gel", "expert"): dict(shells=(1,), speed=3.0, spacing=2.2, theta_max=90, vacuum=1.0, light=True, passes=1, hunts=0,
        summary="sweeps the inner shell in rings 2.2 mm apart at 3 mm/s, full vacuum and 10 000 cpm, the light pipe following 4 mm back"),
    ("exercise_remove_gel", "clumsy"): dict(shells=(1,), speed=4.5, spacing=3.0, theta_max=90, vacuum=1.0, light=False, passes=2, hunts=30,
        summary="no light pipe: hunts for the gel through the centre, then sweeps too fast with rings too far apart and needs a second pass"),
}


def shell_radius(shell, theta_deg):
    i = min(int(theta_deg // 10), len(WALL_RADIUS_BY_10_DEG) - 2)
    f = theta_deg / 10.0 - i
    return (1 - f) * WALL_RADIUS_BY_10_DEG[i] + f * WALL_RADIUS_BY_10_DEG[i + 1] - SHELL_SPACING * shell


def near_lens(port, p, margin=0.8):
    for i in range(101):
        u = i / 100.0
        q = [port[j] + u * (p[j] - port[j]) for j in range(3)]
        e = (q[0] ** 2 + q[1] ** 2) / (LENS_RADIUS + margin) ** 2 + ((q[2] - LENS_Z) / (LENS_HALF_THICKNESS + margin)) ** 2
        if e < 1.0:
            return True
    return False


def plan_points(plan):
    points = []
    for i in range(plan["hunts"]):  # back and forth across the mid-vitreous
        points.append((3.0 * math.cos(2.4 * i), 3.0 * math.sin(2.4 * i), -3.0 - 2.0 * (i % 2)))
    for p in range(plan["passes"]):
        for shell in plan["shells"]:
            r0 = shell_radius(shell, 0.0)
            theta, ring = math.degrees(p * 0.5 * plan["spacing"] / r0), 0
            while theta <= plan["theta_max"]:
                r = shell_radius(shell, theta)
                n = max(1, int(2 * math.pi * r * math.sin(math.radians(theta)) / 1.5))  # 1.5 mm chords
                phis = [2 * math.pi * i / n for i in range(n + 1)] if theta > 0 else [0.0]
                if ring % 2:
                    phis.reverse()
                s, c = math.sin(math.radians(theta)), math.cos(math.radians(theta))
                points += [(r * s * math.cos(phi), r * s * math.sin(phi), -r * c) for phi in phis]
                ring += 1
                theta += math.degrees(plan["spacing"] / r)
    return [p for p in points if not near_lens(WORKING_1, p) and not (plan["light"] and near_lens(WORKING_2, p))]


def offset(p):
    return "[" + ", ".join(f"{p[j] - ROI[j]:.3f}" for j in range(3)) + "]"


def write(case, kind):
    plan = PLANS[(case, kind)]
    points = plan_points(plan)
    times = [3.0]  # both hands at the first point by then
    for a, b in zip(points, points[1:]):
        times.append(times[-1] + math.dist(a, b) / plan["speed"])
    out = [f"""# {case}, the {kind}: {plan['summary']}.
# Written by tools/gel_sweep_script.py ({len(points)} waypoints); edit the plan there, not here.
[script]
version = 1
case = "{case}"
kind = "{kind}"
summary = "{plan['summary']}"
duration_s = {math.ceil(times[-1] + 4)}.0

[[hand]]
tracker = 0
speed_mm_s = {plan['speed']}

[[hand.waypoint]]
to = "port"
above_mm = 3.0
duration_s = 0.0
tool = "vitrector"
cut_rate = 1.0
"""]
    for i, p in enumerate(points):
        w = f'[[hand.waypoint]]\nto = "roi"\noffset_mm = {offset(p)}\n'
        if i == 0:
            w += f"duration_s = 2.5\nvacuum = {plan['vacuum']}\n"
        if plan["light"]:
            w += f"at_s = {times[i]:.2f}\n"
        out.append(w)
    out.append('[[hand.waypoint]]\nto = "port"\nabove_mm = 3.0\nspeed_mm_s = 8.0\nvacuum = 0.0\n')
    if plan["light"]:
        out.append(f"[[hand]]  # the light pipe: 4 mm back from the vitrector's point, aimed at it\ntracker = 1\nspeed_mm_s = {plan['speed']}\n")
        for i, p in enumerate(points):
            d = 2.5 if i == 0 else times[i] - times[i - 1]
            out.append(f'[[hand.waypoint]]\nto = "roi"\noffset_mm = {offset(p)}\nstandoff_mm = 4.0\nat_s = {times[i]:.2f}\nduration_s = {d:.3f}\n')
        out.append('[[hand.waypoint]]\nto = "port"\nabove_mm = 3.0\nspeed_mm_s = 8.0\n')
    sys.stdout.write("\n".join(out))


if __name__ == "__main__":
    if len(sys.argv) != 3 or (sys.argv[1], sys.argv[2]) not in PLANS:
        sys.exit("usage: gel_sweep_script.py CASE KIND, with CASE KIND one of: " + ", ".join(" ".join(k) for k in PLANS))
    write(sys.argv[1], sys.argv[2])

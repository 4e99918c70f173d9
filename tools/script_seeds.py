#!/usr/bin/env python3
"""script_seeds.py CASE [CASE...] [--kind K | --script FILE] [--seeds 1-10] [--retina-vertices N] [--duration S]
                       [--jobs J] [--out DIR] [--vitreo PATH] [--require-rate R]

Plays each case's surgical script through the whole stack (the main job, `vitreo --unpaced` without
frames or replay) once per sensor-noise seed (`vitreo --script-seed N`) and prints what each seed
gave: the score, whether every criterion was met, each criterion's value, the iatrogenic events and
the final state hash; then how often the criteria were met, and met cleanly (no iatrogenic event).

A shipped script fixes its tracker noise and tremor with `seed = 1`, so one session says what that
one noise sample gave. The same hand with another sample is another seed: an outcome that holds
over seeds is the technique's; one that flips between seeds was decided by the noise, and so is also
tipped by any change of the solver's bits (core/tissue/MEASUREMENTS.md, twenty-first session).

  tools/script_seeds.py scenes/low_membrane_macula.toml --seeds 1-10
  tools/script_seeds.py scenes/exercise_cut_path.toml --kind clumsy --seeds 1,4,9 --retina-vertices 0
  tools/script_seeds.py scenes/*.toml --seeds 1-4 --vitreo OTHER_BUILD/rig/app/vitreo

Several cases play one after the other, each with its own table, then one line a case (met, met
cleanly, score median and range): how a change of the solver moves every expert at once. A file
given among several that has no script of the kind (scenes/materials.toml) is passed over, said so.

--kind picks scenes/scripts/CASE.KIND.toml beside the case (default expert); --script any other.
--retina-vertices is vitreo's (default 5000, the rig's; 0 the case's own). --duration cuts every
session short (vitreo --duration). Sessions run --jobs at a time (default 2) after the first, which
settles the case's start into a cache beside the sessions for the rest. Every session's folder (its
report.json, telemetry and recording) is kept under OUT/seed-N, OUT/CASE/seed-N for several cases
(default: a new folder under /tmp, printed).
--require-rate R exits 1 when the criteria were met cleanly in fewer than R (0..1) of a case's seeds.
Exit status 2: a session that did not run or wrote no report (its output is printed).
"""
import argparse
import concurrent.futures
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile


def parse_seeds(text):
    seeds = []
    for part in text.split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", part)
        if not m:
            raise argparse.ArgumentTypeError(f"seeds: expected N, N-M or a comma list of them, got '{text}'")
        first = int(m.group(1))
        last = int(m.group(2)) if m.group(2) else first
        if last < first:
            raise argparse.ArgumentTypeError(f"seeds: {first}-{last} runs backwards")
        seeds.extend(range(first, last + 1))
    if len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"seeds: '{text}' names a seed twice")
    return seeds


def default_vitreo():
    here = pathlib.Path(__file__).resolve().parent.parent
    for candidate in (here / "build/release/rig/app/vitreo", here / "build/test/rig/app/vitreo"):
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    return shutil.which("vitreo") or "vitreo"


def run_seed(args, case, script, seed, out):
    folder = out / f"seed-{seed}"
    cmd = [args.vitreo, "--case", str(case), "--script", script, "--script-seed", str(seed),
           "--retina-vertices", str(args.retina_vertices), "--no-render", "--no-verify", "--unpaced",
           "--out", str(folder), "--cache", str(out / "cache")]
    if args.duration is not None:
        cmd += ["--duration", str(args.duration)]
    p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    report = folder / "report.json"
    if p.returncode != 0 or not report.is_file():
        return {"seed": seed, "error": f"vitreo exited {p.returncode}" + ("" if report.is_file() else ", no report.json"),
                "output": p.stdout + p.stderr}
    r = json.loads(report.read_text())
    hash_match = re.search(r"state hash\s+([0-9a-f]{16})", p.stdout)
    criteria = [{"kind": c["kind"], "target": c["target"], "value": c["value"]["value"],
                 "threshold": c["threshold"]["value"], "met": bool(c["met"])} for c in r["criteria"]]
    return {
        "seed": seed,
        "score": r["score"]["total"]["value"],
        "passed": bool(r["case"]["passed"]),
        "criteria": criteria,
        "all_met": bool(criteria) and all(c["met"] for c in criteria),
        "iatrogenic": int(r["totals"]["iatrogenic_events"]["value"]),
        "hash": hash_match.group(1) if hash_match else "?",
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", nargs="+", help="the case file(s) (scenes/CASE.toml)")
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--kind", default="expert", help="scenes/scripts/CASE.KIND.toml beside the case (default expert)")
    which.add_argument("--script", help="any other script for the case")
    ap.add_argument("--seeds", type=parse_seeds, default=parse_seeds("1-10"), help="N, N-M or a comma list (default 1-10)")
    ap.add_argument("--retina-vertices", type=int, default=5000, help="vitreo's --retina-vertices (default 5000; 0 the case's own)")
    ap.add_argument("--duration", type=float, help="cut every session to this many seconds")
    ap.add_argument("--jobs", type=int, default=2, help="sessions at a time (default 2)")
    ap.add_argument("--out", help="folder for the sessions (default: a new one under /tmp)")
    ap.add_argument("--vitreo", default=default_vitreo(), help="the vitreo program (default: this tree's build, else PATH)")
    ap.add_argument("--require-rate", type=float, help="exit 1 below this share of seeds meeting every criterion cleanly")
    args = ap.parse_args()
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    if args.require_rate is not None and not 0.0 <= args.require_rate <= 1.0:
        ap.error("--require-rate must lie in 0..1")
    cases = [pathlib.Path(c) for c in args.case]
    if args.script and len(cases) > 1:
        ap.error("--script plays one case's script: give one case, or --kind for several")
    plan = []  # (case, script)
    for case in cases:
        if not case.is_file():
            ap.error(f"{case}: no such case file")
        script = args.script or str(case.parent / "scripts" / f"{case.stem}.{args.kind}.toml")
        if pathlib.Path(script).is_file():
            plan.append((case, script))
        elif len(cases) == 1:
            ap.error(f"{script}: no such script")
        else:
            print(f"{case}: no {args.kind} script ({script}): passed over", flush=True)
    if not plan:
        ap.error(f"none of the files has a {args.kind} script")
    out = pathlib.Path(args.out) if args.out else pathlib.Path(tempfile.mkdtemp(prefix="script-seeds-"))
    out.mkdir(parents=True, exist_ok=True)

    status = 0
    tallies = []  # (case, (met, clean, n, median, low, high) or None where a session failed)
    for case, script in plan:
        folder = out if len(plan) == 1 else out / case.stem
        folder.mkdir(parents=True, exist_ok=True)
        code, tally = play_case(args, case, script, folder)
        status = max(status, code)
        tallies.append((case.stem, tally))
    if len(plan) > 1:
        print(f"\n{'case':<28}  {'met':<8}  {'cleanly':<8}  score median (range)")
        for name, tally in tallies:
            if tally is None:
                print(f"{name:<28}  a session did not run or wrote no report (its output is above)")
                continue
            met, clean, n, median, low, high = tally
            print(f"{name:<28}  {f'{met} of {n}':<8}  {f'{clean} of {n}':<8}  {median:.1f} ({low:.1f}-{high:.1f})")
    return status


def play_case(args, case, script, out):
    """Plays one case's script over the seeds and prints its table; returns (exit code, tally)."""
    resolution = "the case's own resolution" if args.retina_vertices == 0 else f"{args.retina_vertices} retina vertices"
    print(f"{case.stem}: {script} at {resolution}, seeds {','.join(map(str, args.seeds))}; sessions in {out}", flush=True)
    # The first session settles the case's start into the cache; the rest read it.
    results = [run_seed(args, case, script, args.seeds[0], out)]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results += list(pool.map(lambda s: run_seed(args, case, script, s, out), args.seeds[1:]))

    failed = [r for r in results if "error" in r]
    for r in failed:
        print(f"seed {r['seed']}: {r['error']}\n{r['output']}", file=sys.stderr)
    if failed:
        return 2, None
    print(f"{'seed':>6}  {'score':>5}  {'passed':<6}  {'criteria met':<12}  {'iatrogenic':>10}  {'state hash':<16}  criteria")
    for r in results:
        crit = "; ".join(f"{c['kind']} {c['target']} {c['value']:.3g} (goal {c['threshold']:.3g})" for c in r["criteria"])
        print(f"{r['seed']:>6}  {r['score']:>5.1f}  {'yes' if r['passed'] else 'no':<6}  {'yes' if r['all_met'] else 'no':<12}  "
              f"{r['iatrogenic']:>10}  {r['hash']:<16}  {crit}")
    n = len(results)
    met = sum(r["all_met"] for r in results)
    clean = sum(r["all_met"] and r["iatrogenic"] == 0 for r in results)
    scores = sorted(r["score"] for r in results)
    median = scores[n // 2] if n % 2 else 0.5 * (scores[n // 2 - 1] + scores[n // 2])
    print(f"criteria met in {met} of {n} seeds, cleanly (no iatrogenic event) in {clean}; "
          f"score median {median:.1f}, range {scores[0]:.1f}-{scores[-1]:.1f}", flush=True)
    tally = (met, clean, n, median, scores[0], scores[-1])
    if args.require_rate is not None and clean < args.require_rate * n:
        print(f"{case.stem}: below the required rate: {clean} of {n} < {args.require_rate:g}", file=sys.stderr)
        return 1, tally
    return 0, tally

if __name__ == "__main__":
    sys.exit(main())

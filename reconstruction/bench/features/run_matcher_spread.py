#!/usr/bin/env python3
"""How much the SfM's camera error moves with the matcher's random draw (issue 24).

For each matcher (`--search`) and seed (`--random-seed`: the hashing's directions, the k-d
forest's trees), runs `auv recon match`, `sfm` and `evaluate` on one survey and appends a row to
a JSON-lines results file. Resumable: rows already in the file are skipped; files of several
machines or sessions merge by concatenation. `--report` prints, per matcher, the spread of the
match time and of the camera error, so that two matchers are compared on distributions rather
than on one run each.

  reconstruction/bench/features/run_matcher_spread.py --survey auv_runs/survey-canyon-full \\
      --matchers cascade_hash,kdtree --seeds 0-4 --results bench_results/matcher_spread.jsonl
  reconstruction/bench/features/run_matcher_spread.py --report bench_results/matcher_spread.jsonl

Needs `auv` on PATH (source install/setup.bash) and a survey with features/ and a simulation
(for evaluate's ground truth). The survey's features/matches/, sparse/ and evaluation.json are
rewritten by every run.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time


def seeds_of(text):
    seeds = []
    for part in text.split(","):
        if "-" in part:
            first, last = part.split("-")
            seeds.extend(range(int(first), int(last) + 1))
        else:
            seeds.append(int(part))
    return seeds


def done_rows(path):
    rows = []
    if os.path.exists(path):
        with open(path) as f:
            for number, line in enumerate(f, 1):
                line = line.strip()
                if not line:
                    continue
                try:
                    rows.append(json.loads(line))
                except ValueError:
                    print(f"{path}:{number}: not a JSON row, skipped", file=sys.stderr)
    return rows


def run(command, log):
    with open(log, "a") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        return subprocess.run(command, stdout=out, stderr=subprocess.STDOUT).returncode


def one_run(survey, matcher, seed, threads, log):
    row = {"survey": survey, "search": matcher, "random_seed": seed, "threads": threads,
           "load_at_start": os.getloadavg()[0], "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
    try:
        row["commit"] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                                       text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        row["commit"] = "unknown"
    start = time.monotonic()
    if run(["auv", "recon", "match", survey, "--threads", str(threads), "--search", matcher,
            "--random-seed", str(seed)], log) != 0:
        row["failed"] = "match"
        return row
    row["match_wall_s"] = round(time.monotonic() - start, 1)
    with open(os.path.join(survey, "report.json")) as f:
        match = json.load(f)["stages"]["match"]
    row["verified_pairs"] = match["verified_pairs"]
    row["verified_matches"] = match["verified_matches"]
    if run(["auv", "recon", "sfm", survey, "--threads", str(threads)], log) != 0:
        row["failed"] = "sfm"
        return row
    if run(["auv", "recon", "evaluate", survey], log) != 0:
        row["failed"] = "evaluate"
        return row
    with open(os.path.join(survey, "evaluation.json")) as f:
        evaluation = json.load(f)
    row["registered"] = evaluation["images"]["registered"]
    row["keyframes"] = evaluation["images"]["keyframes"]
    error = evaluation["camera_error"]
    row["position_mm"] = {k: round(1000 * v, 2) for k, v in error["position_m"].items()}
    row["rotation_deg"] = {k: round(v, 4) for k, v in error["rotation_deg"].items()}
    return row


def spread(values):
    if not values:
        return "-"
    if len(values) == 1:
        return f"{values[0]:.2f}"
    return (f"{statistics.mean(values):.2f} ± {statistics.stdev(values):.2f} "
            f"[{min(values):.2f}–{max(values):.2f}]")


def report(path):
    rows = [r for r in done_rows(path) if "failed" not in r]
    print(f"| search | runs | match s | verified pairs | registered | position median mm | "
          f"position max mm | rotation median ° |")
    print("|---|---:|---|---|---|---|---|---|")
    for matcher in sorted({r["search"] for r in rows}):
        mine = [r for r in rows if r["search"] == matcher]
        print(f"| {matcher} | {len(mine)} | {spread([r['match_wall_s'] for r in mine])} | "
              f"{spread([r['verified_pairs'] for r in mine])} | "
              f"{spread([r['registered'] for r in mine])} | "
              f"{spread([r['position_mm']['median'] for r in mine])} | "
              f"{spread([r['position_mm']['max'] for r in mine])} | "
              f"{spread([r['rotation_deg']['median'] for r in mine])} |")
    failed = [r for r in done_rows(path) if "failed" in r]
    if failed:
        print(f"\n{len(failed)} runs failed: " +
              ", ".join(f"{r['search']} seed {r['random_seed']} at {r['failed']}" for r in failed))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--survey")
    parser.add_argument("--matchers", default="cascade_hash,kdtree")
    parser.add_argument("--seeds", default="0-4", help="e.g. 0-4 or 0,3,7")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--results", default="bench_results/matcher_spread.jsonl")
    parser.add_argument("--report", metavar="RESULTS", help="print the table of a results file")
    args = parser.parse_args()
    if args.report:
        report(args.report)
        return 0
    if not args.survey or not os.path.exists(os.path.join(args.survey, "features", "index.csv")):
        parser.error("--survey must name a survey with features/index.csv")
    os.makedirs(os.path.dirname(os.path.abspath(args.results)), exist_ok=True)
    log = args.results + ".log"
    done = {(r["survey"], r["search"], r["random_seed"]) for r in done_rows(args.results)}
    for seed in seeds_of(args.seeds):
        for matcher in args.matchers.split(","):
            if (args.survey, matcher, seed) in done:
                continue
            print(f"matcher_spread: {matcher} seed {seed}", flush=True)
            row = one_run(args.survey, matcher, seed, args.threads, log)
            with open(args.results, "a") as f:
                f.write(json.dumps(row) + "\n")
            print("  " + json.dumps(row), flush=True)
    report(args.results)
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Mission campaign (benchmark, not a test): the world's inspection mission over many seeds.

For each world, seed and planner mode it runs `auv launch bringup/launch/vehicle.yaml
auto_mission:=true replanning:=<mode>` (simulator with navigation drift, mapping, planning,
mission, controller), reads the mission report (`<run>/mission/summary.json`), and compares each
completed query's executed true path with the oracle shortest path between the same two points
on the world's true map at the planner's clearance (`planning_oracle` on `auv sim octomap`): in
the horizontal plane for a query at fixed depth, in 3-D within the query's depth band otherwise;
twice: on a fine true map (0.1 m) and on the true map at the planner's own resolution (0.5 m:
what the planner could do knowing the world in advance). Figures: success, recoveries, contacts,
minimum true clearance, navigation error, path length / oracle, mission and wall time.

Resumable and mergeable: each finished run appends one JSON line to --results (default
bench_results/mission_campaign.jsonl); a run whose key (world, seed, planner mode and the
configuration: launch file and arguments, objective, navigation, prior map, real-time factor)
is already there is skipped, so a campaign stopped or killed goes on where it was by running
the same command again, and only the run in progress is lost. `campaign_table.py` (or
--report) turns one or more such files into the Markdown tables.

  components/mission/bench/run_mission_campaign.py [--worlds canyon,breakwater,dead_end_bay]
      [--seeds 20] [--first-seed 1] [--planner repair,scratch] [--real-time-factor 4]
      [--results FILE.jsonl] [--domain 45] [--keep-runs]
      [--navigation drift|ideal] [--launch FILE]   # ideal: no drift or noise; FILE: vehicle.yaml
      [--launch-arg NAME:=VALUE]...   # e.g. map_resolution:=0.25
      [--prior-map]   # the mapping starts from the true map: no exploration left
  components/mission/bench/run_mission_campaign.py --report ROWS.jsonl...   # the tables only
  components/mission/bench/run_mission_campaign.py --evaluate RUN_DIR...   # finished runs again
"""
import argparse
import datetime
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import campaign_table  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
LAUNCH = os.path.join(ROOT, "bringup", "launch", "vehicle.yaml")
RESULTS = os.path.join(ROOT, "bench_results", "mission_campaign.jsonl")
PLANNERS = ("repair", "scratch", "restart")  # the planning component's `replanning`
CLEARANCE = 1.2  # m, the planner's hull_radius + safety_margin (planning defaults)
ORACLE_GRID = 0.2  # m
TRUE_MAP_RESOLUTION = 0.1  # m
MAP_RESOLUTION = 0.5  # m, the mapping component's default
# `--navigation ideal`: the simulator's navigation without drift or noise, so that what is left
# of path length / oracle is the planner's and the mapping's own (exploration, quantisation).
IDEAL_NAVIGATION = ("navigation: {dvl_scale_error: 0, dvl_velocity_noise: 0, "
                    "dvl_dropout_rate: 0, dvl_dropout_roughness_gain: 0, heading_bias_deg: 0, "
                    "heading_random_walk_deg: 0, heading_noise_deg: 0, attitude_noise_deg: 0, "
                    "gyro_noise: 0}\n")


def find_program(name):
    """A program of the merged install: bin/ or lib/<package>/."""
    install = os.path.join(ROOT, "install")
    for folder in ("bin", "lib/auv_planning", "lib/auv_mission"):
        path = os.path.join(install, folder, name)
        if os.path.exists(path):
            return path
    found = shutil.which(name)
    if not found:
        sys.exit(f"run_mission_campaign: {name} not found (build the workspace first)")
    return found


def query_specs(mission):
    """Per query of a mission file: whether it plans at fixed depth and its depth band (the
    query's min_depth / max_depth, else its bounds' z range)."""
    defaults = mission.get("defaults") or {}
    specs = []
    for query in mission["queries"]:
        merged = {**defaults, **query}
        bounds = merged.get("bounds") or {}
        low = float(merged.get("min_depth") or 0.0)
        high = float(merged.get("max_depth") or 0.0)
        if high <= low:  # no band: the bounds are the limits
            low = float(bounds["min"][2]) if bounds.get("min") else 0.0
            high = float(bounds["max"][2]) if bounds.get("max") else None
        specs.append({"fixed_depth": bool(merged.get("fixed_depth", False)),
                      "band": [low, high]})
    return specs


def oracle_arguments(spec, start, goal):
    """planning_oracle's mode arguments and the end points: the plane of the start at fixed
    depth; in 3-D the band, with the end points moved into it (depth control keeps the vehicle
    within centimetres of it, and the oracle refuses a point outside)."""
    if spec is None or spec["fixed_depth"]:
        return ["--fixed-depth"], start, goal
    low, high = spec["band"]
    arguments = ["--min-depth", str(low)]
    if high is not None:
        arguments += ["--max-depth", str(high)]

    def inside(point):
        z = max(point[2], low)
        return [point[0], point[1], min(z, high) if high is not None else z]
    return arguments, inside(start), inside(goal)


def oracle_length(true_map, start, goal, spec=None, clearance=CLEARANCE, extra=()):
    mode, start, goal = oracle_arguments(spec, start, goal)
    out = subprocess.run(
        [find_program("planning_oracle"), "--map", true_map, "--start", ",".join(map(str, start)),
         "--goal", ",".join(map(str, goal)), "--clearance", str(clearance), *mode,
         "--grid", str(ORACLE_GRID), "--quiet", *extra], capture_output=True, text=True)
    if out.returncode != 0:
        return None, out.stderr.strip()
    return float(out.stdout.strip().split()[0]), ""


def true_map_for(world, seed, cache, resolution):
    suffix = "" if resolution == TRUE_MAP_RESOLUTION else f"-{resolution}"
    path = os.path.join(cache, f"{world}-{seed}-true{suffix}.bt")
    if not os.path.exists(path):
        subprocess.run([find_program("auv"), "sim", "octomap", world, "--seed", str(seed),
                        "--resolution", str(resolution), "--out", path], check=True,
                       stdout=subprocess.DEVNULL)
    return path


def estimated_at(events, t, after):
    """The navigation estimate the mission log recorded nearest to `t` (first event at or after
    it when `after`, else the last one at or before it)."""
    rows = [e for e in events if (e[0] >= t - 1e-6 if after else e[0] <= t + 1e-6)]
    if not rows:
        return None
    return (rows[0] if after else rows[-1])[1]


def read_events(events_path):
    """(t, navigation estimate) of every row of a mission log's events.csv."""
    events = []
    if not os.path.exists(events_path):
        return events
    with open(events_path) as lines:
        next(lines, None)
        for line in lines:
            fields = line.split(",")
            try:
                events.append((float(fields[0]), [float(v) for v in fields[5:8]]))
            except (ValueError, IndexError):
                continue
    return events


def own_map_ratios(run_dir, summary, specs):
    """Executed length / the shortest path on the map the vehicle had at the end (its mission
    log's map.bt, in the navigation frame, unknown = free) between the navigation estimates at
    the query's start and end: what hindsight on its own map allows. The oracle keeps its
    clearance from voxel centres; the planner keeps CLEARANCE from the voxel's box, i.e. up to
    half a voxel more, so the oracle gets CLEARANCE + MAP_RESOLUTION / 2."""
    map_path = os.path.join(run_dir, "mission", "map.bt")
    events_path = os.path.join(run_dir, "mission", "events.csv")
    if not os.path.exists(map_path) or not os.path.exists(events_path):
        return [], ["no mission/map.bt or events.csv"]
    events = read_events(events_path)
    ratios, errors = [], []
    for query in summary["queries"]:
        if not query["succeeded"]:
            continue
        start = estimated_at(events, query["start_t"], True)
        end = estimated_at(events, query["end_t"], False)
        if start is None or end is None:
            errors.append(f"query {query['index']}: no navigation estimate in events.csv")
            continue
        spec = specs[query["index"]] if query["index"] < len(specs) else None
        length, error = oracle_length(map_path, start, end, spec,
                                      CLEARANCE + 0.5 * MAP_RESOLUTION, ("--pad", "30"))
        if length is None:
            errors.append(f"query {query['index']}: {error}")
            continue
        ratios.append(query["executed_length_m"] / length)
    return [round(r, 3) for r in ratios], errors


def evaluate(row, world, seed, run_dir, summary, cache):
    """Adds the summary's figures and the path ratios against the oracles to `row`."""
    row.update({k: summary.get(k) for k in ("state", "message", "duration_s", "collisions",
                                            "min_true_clearance_m", "max_navigation_error_m",
                                            "executed_length_m")})
    row["recoveries"] = summary.get("recoveries", 0)
    mission = yaml.safe_load(open(os.path.join(run_dir, "mission.yaml")))["mission"]
    specs = query_specs(mission)
    results = {}
    for key, resolution in (("path_ratios", TRUE_MAP_RESOLUTION),
                            ("path_ratios_map_res", MAP_RESOLUTION)):
        true_map = true_map_for(world, seed, cache, resolution)
        ratios = []
        for query in summary["queries"]:
            index = query["index"]
            spec = specs[index] if index < len(specs) else None
            result = results.setdefault(index, {
                "index": index, "name": mission["queries"][index].get("name")
                if index < len(mission["queries"]) else None,
                "succeeded": query["succeeded"], "path_m": query.get("executed_length_m"),
                "oracle": "2d" if spec is None or spec["fixed_depth"] else "3d"})
            if not query["succeeded"]:
                continue
            # Same end points as the vehicle: start and end of the executed query.
            length, error = oracle_length(true_map, query["start"], query["end"], spec)
            if length:
                ratios.append(query["executed_length_m"] / length)
                if resolution == TRUE_MAP_RESOLUTION:
                    result["oracle_m"] = round(length, 3)
                    result["ratio"] = round(query["executed_length_m"] / length, 3)
                else:
                    result["ratio_map_res"] = round(query["executed_length_m"] / length, 3)
            else:
                row.setdefault("oracle_errors", []).append(error)
        row[key] = [round(r, 3) for r in ratios]
    row["query_results"] = [results[i] for i in sorted(results)]
    events_path = os.path.join(run_dir, "mission", "events.csv")
    if os.path.exists(events_path):
        # Planner cancels of the active waypoint (blocked root or approach): each holds the
        # vehicle and replans from where it is.
        with open(events_path) as events:
            row["cancels"] = sum(1 for line in events if "/cancel," in line)
    row["path_ratios_own_map"], own_errors = own_map_ratios(run_dir, summary, specs)
    if own_errors:
        row["own_map_errors"] = own_errors
    row["queries"] = f'{sum(q["succeeded"] for q in summary["queries"])}/' \
                     f'{len(mission["queries"])}'


def ideal_navigation_scenario(world, seed, runs_dir):
    """The generated world's scenario with IDEAL_NAVIGATION appended (same mesh and queries)."""
    folder = os.path.join(runs_dir, "worlds", f"{world}-{seed}")
    subprocess.run([find_program("auv"), "sim", "generate", world, "--seed", str(seed),
                    "--out", folder], check=True, stdout=subprocess.DEVNULL)
    scenario = os.path.join(folder, f"{world}.yaml")
    with open(scenario) as text:
        if any(line.startswith("navigation:") for line in text):
            sys.exit(f"run_mission_campaign: {scenario} already has a navigation section")
    with open(scenario, "a") as text:
        text.write(IDEAL_NAVIGATION)
    return scenario


def map_resolution(args):
    """The map resolution the launch runs at: its map_resolution argument, else the default."""
    for argument in args.launch_arg:
        name, _, value = argument.partition(":=")
        if name == "map_resolution":
            return float(value)
    return MAP_RESOLUTION


def campaign_dir(runs_dir, results, config):
    """Where this campaign's run folders go: one folder per results file and configuration, so
    that two campaigns (another objective, another rows file) never overwrite each other's runs;
    the worlds' true maps stay shared in runs_dir."""
    stem = os.path.splitext(os.path.basename(results))[0]
    digest = hashlib.sha1(json.dumps(config, sort_keys=True).encode()).hexdigest()[:8]
    return os.path.join(runs_dir, f"{stem}-{digest}")


def run_mission(world, seed, planner, args, runs_dir, out_dir):
    run_dir = os.path.join(out_dir, f"{world}-{seed}-{planner}")
    shutil.rmtree(run_dir, ignore_errors=True)
    scenario = world if args.navigation == "drift" else \
        ideal_navigation_scenario(world, seed, runs_dir)
    command = [find_program("auv"), "launch", args.launch, f"world:={scenario}", f"seed:={seed}",
               "auto_mission:=true", f"real_time_factor:={args.real_time_factor}",
               f"domain:={args.domain}", f"run_dir:={run_dir}", f"objective:={args.objective}",
               f"replanning:={planner}"]
    command += args.launch_arg
    if args.prior_map:
        # The true map is in the world frame the run navigates in: nothing to align.
        command += [f"initial_map:={true_map_for(world, seed, runs_dir, map_resolution(args))}",
                    "align_initial_map:=false"]
    started = time.monotonic()
    with open(os.path.join(out_dir, f"{world}-{seed}-{planner}.log"), "w") as log:
        try:
            code = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    wall = time.monotonic() - started
    summary_path = os.path.join(run_dir, "mission", "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else None
    return run_dir, code, wall, summary


def git_commit():
    """The checked-out commit, with -dirty when tracked files differ from it."""
    def git(*arguments):
        out = subprocess.run(["git", "-C", ROOT, *arguments], capture_output=True, text=True)
        return out.stdout.strip() if out.returncode == 0 else ""
    commit = git("rev-parse", "--short=12", "HEAD") or "unknown"
    return commit + ("-dirty" if git("status", "--porcelain", "--untracked-files=no") else "")


# Consecutive runs without a report after which the campaign stops instead of writing a row
# for every run left (a broken launch fails each in a second).
MAX_RUNS_WITHOUT_REPORT = 3


def configuration(args):
    """What besides world, seed and planner mode makes two runs the same experiment."""
    return {"launch": os.path.relpath(os.path.abspath(args.launch), ROOT),
            "launch_args": sorted(args.launch_arg), "objective": args.objective,
            "navigation": args.navigation, "prior_map": args.prior_map,
            "real_time_factor": args.real_time_factor}


def row_key(world, seed, planner, config):
    return json.dumps({"world": world, "seed": seed, "planner": planner, "config": config},
                      sort_keys=True)


def done_keys(path):
    """Keys of the runs already in the results file (a line cut off by a crash is ignored). A
    run that left no report (the launch failed, e.g. a bad argument) is run again; its row
    stays as evidence and the new one replaces it in the tables."""
    if not os.path.exists(path):
        return set()
    return {row.get("key") for row in campaign_table.read_rows([path])
            if row.get("state") != "NO REPORT"}


def append_row(path, row):
    """One line per finished run, on disk before the next run starts."""
    with open(path, "a") as results:
        results.write(json.dumps(row) + "\n")
        results.flush()
        os.fsync(results.fileno())


def evaluate_runs(run_dirs, args):
    """Path ratios of finished runs (<world>-<seed>[-<planner>] folders with
    mission/summary.json), appended to the results file like campaign runs."""
    rows = []
    config = configuration(args)
    for run_dir in run_dirs:
        run_dir = os.path.abspath(run_dir)
        name = os.path.basename(run_dir.rstrip("/"))
        planner = "repair"
        for mode in PLANNERS:
            if name.endswith("-" + mode):
                name, planner = name[:-len(mode) - 1], mode
        world, _, seed = name.rpartition("-")
        summary_path = os.path.join(run_dir, "mission", "summary.json")
        if not world or not seed.isdigit() or not os.path.exists(summary_path):
            sys.exit(f"run_mission_campaign: {run_dir}: not a <world>-<seed>[-<planner>] run "
                     "folder with mission/summary.json")
        row = {"key": row_key(world, int(seed), planner, config), "world": world,
               "seed": int(seed), "planner": planner, **config, "commit": git_commit(),
               "evaluated": True, "run": run_dir}
        evaluate(row, world, int(seed), run_dir, json.load(open(summary_path)),
                 os.path.dirname(run_dir))
        append_row(args.results, row)
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", default="canyon,breakwater,dead_end_bay",
                        help="comma-separated world names (any the simulator knows) or scenario "
                             "files")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--planner", default="repair",
                        help="comma-separated planner modes, each run per world and seed: "
                             "repair (the paper's tree repair), scratch (OMPL's RRTstar from "
                             "scratch on every map change), restart (the repair planner's tree "
                             "restarted on every map change: tree repair without the reuse)")
    parser.add_argument("--real-time-factor", type=float, default=4.0,
                        help="simulated seconds per wall second (at 8 the 2-core machine "
                             "starved the stack); stated in every table")
    parser.add_argument("--results", default=RESULTS,
                        help="rows file (.jsonl): finished runs are appended, runs already in "
                             "it are skipped (default: bench_results/mission_campaign.jsonl)")
    parser.add_argument("--domain", type=int, default=45)
    parser.add_argument("--timeout", type=float, default=3600.0, help="s of wall time per mission")
    parser.add_argument("--objective", default="visibility", choices=["visibility", "path_length"])
    parser.add_argument("--navigation", default="drift", choices=["drift", "ideal"],
                        help="drift: the simulator's defaults; ideal: no drift or noise")
    parser.add_argument("--launch", default=LAUNCH,
                        help="the vehicle's launch file (default: bringup/launch/vehicle.yaml)")
    parser.add_argument("--launch-arg", action="append", default=[], metavar="NAME:=VALUE",
                        help="another argument of the launch file, e.g. map_resolution:=0.25 "
                             "(repeatable)")
    parser.add_argument("--prior-map", action="store_true",
                        help="the mapping starts from the world's true map at the map resolution "
                             "(initial_map): nothing is left to explore, so what remains of path "
                             "/ oracle is the objective's and the planner's own (use with "
                             "--navigation ideal: the prior map is in the true frame)")
    parser.add_argument("--keep-runs", action="store_true", help="keep the run folders whole")
    parser.add_argument("--seed-major", action="store_true",
                        help="run seed by seed across the worlds (default: world by world)")
    parser.add_argument("--evaluate", nargs="+", metavar="RUN_DIR",
                        help="only evaluate finished run folders (no missions are run)")
    parser.add_argument("--report", nargs="+", metavar="ROWS",
                        help="only print the tables of these rows files (campaign_table.py)")
    args = parser.parse_args()

    if args.report:
        print(campaign_table.report(campaign_table.read_rows(args.report)))
        return
    os.makedirs(os.path.dirname(os.path.abspath(args.results)), exist_ok=True)
    if args.evaluate:
        evaluate_runs(args.evaluate, args)
        print(campaign_table.report(campaign_table.read_rows([args.results])))
        return
    planners = args.planner.split(",")
    for planner in planners:
        if planner not in PLANNERS:
            sys.exit(f"run_mission_campaign: --planner: expected {', '.join(PLANNERS)}, got "
                     f"'{planner}'")
    runs_dir = os.path.join(ROOT, "bench_results", "mission_campaign_runs")
    os.makedirs(runs_dir, exist_ok=True)
    worlds = args.worlds.split(",")
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    # Seed by seed across the worlds: a campaign stopped early still covers every world. The
    # modes of one world and seed run one after the other, so a comparison is never half made.
    order = [(w, s) for s in seeds for w in worlds] if args.seed_major else \
        [(w, s) for w in worlds for s in seeds]
    config = configuration(args)
    out_dir = campaign_dir(runs_dir, args.results, config)
    os.makedirs(out_dir, exist_ok=True)
    done = done_keys(args.results)
    commit = git_commit()
    no_report = 0  # runs in a row that left no report: the launch itself is broken
    for world, seed in order:
        for planner in planners:
            key = row_key(world, seed, planner, config)
            if key in done:
                print(f"skipped (in {os.path.relpath(args.results)}): {world} seed {seed} "
                      f"{planner}", flush=True)
                continue
            load = os.getloadavg()[0]
            started = datetime.datetime.now().isoformat(timespec="seconds")
            run_dir, code, wall, summary = run_mission(world, seed, planner, args, runs_dir,
                                                      out_dir)
            row = {"key": key, "world": world, "seed": seed, "planner": planner, **config,
                   "commit": commit, "started": started, "exit": code, "wall_s": round(wall, 1),
                   "load_average": [round(load, 2), round(os.getloadavg()[0], 2)],
                   "run": os.path.relpath(run_dir, ROOT)}
            if summary:
                evaluate(row, world, seed, run_dir, summary, runs_dir)
            else:
                row["state"] = "NO REPORT"
            append_row(args.results, row)
            done.add(key)
            print(json.dumps(row), flush=True)
            no_report = no_report + 1 if row.get("state") == "NO REPORT" else 0
            if no_report == MAX_RUNS_WITHOUT_REPORT:
                sys.exit(f"run_mission_campaign: {no_report} runs in a row left no report (the "
                         f"last: {os.path.relpath(run_dir, ROOT)}, its launch log beside it): "
                         "the launch itself fails (a mixed workspace? source this checkout's "
                         "install/setup.bash); stopped. Those runs are redone when the same "
                         "command runs again.")
            if not args.keep_runs and not row.get("collisions"):  # runs with contacts: evidence
                for sub in ("ground_truth",):
                    shutil.rmtree(os.path.join(run_dir, sub), ignore_errors=True)
    print(campaign_table.report(campaign_table.read_rows([args.results])))


if __name__ == "__main__":
    main()

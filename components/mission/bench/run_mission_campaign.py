#!/usr/bin/env python3
"""Mission campaign (benchmark, not a test): the world's inspection mission over many seeds.

For each world and seed it runs `auv launch bringup/launch/vehicle.yaml auto_mission:=true`
(simulator with navigation drift, mapping, planning, mission, controller), reads the mission
report (`<run>/mission/summary.json`), and compares each completed query's executed true path
with the oracle shortest path between the same two points on the world's true map at the
planner's clearance (`planning_oracle` on `auv sim octomap`), twice: on a fine true map (0.1 m)
and on the true map at the planner's own resolution (0.5 m: what the planner could do knowing
the world in advance; narrow gaps that 0.5 m cells close are closed for both). Figures: success,
collisions, minimum true clearance, navigation error, path length / oracle, wall time. Results go
to bench_results/mission_campaign_<stamp>.{md,json}.

  components/mission/bench/run_mission_campaign.py [--worlds canyon,breakwater,dead_end_bay]
      [--seeds 20] [--first-seed 1] [--real-time-factor 8] [--domain 45] [--keep-runs]
      [--navigation drift|ideal] [--launch FILE]   # ideal: no drift or noise; FILE: vehicle.yaml
      [--launch-arg NAME:=VALUE]...   # e.g. map_resolution:=0.25
      [--prior-map]   # the mapping starts from the true map: no exploration left
  components/mission/bench/run_mission_campaign.py --evaluate RUN_DIR...   # finished runs again
"""
import argparse
import datetime
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
LAUNCH = os.path.join(ROOT, "bringup", "launch", "vehicle.yaml")
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


def oracle_length(true_map, start, goal):
    out = subprocess.run(
        [find_program("planning_oracle"), "--map", true_map, "--start", ",".join(map(str, start)),
         "--goal", ",".join(map(str, goal)), "--clearance", str(CLEARANCE), "--fixed-depth",
         "--grid", str(ORACLE_GRID), "--quiet"], capture_output=True, text=True)
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


def own_map_ratios(run_dir, summary):
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
        out = subprocess.run(
            [find_program("planning_oracle"), "--map", map_path,
             "--start", ",".join(map(str, start)), "--goal", ",".join(map(str, end)),
             "--clearance", str(CLEARANCE + 0.5 * MAP_RESOLUTION), "--fixed-depth", "--pad", "30",
             "--grid", str(ORACLE_GRID), "--quiet"], capture_output=True, text=True)
        if out.returncode != 0:
            errors.append(f"query {query['index']}: {out.stderr.strip()}")
            continue
        ratios.append(query["executed_length_m"] / float(out.stdout.strip().split()[0]))
    return [round(r, 3) for r in ratios], errors


def evaluate(row, world, seed, run_dir, summary, cache):
    """Adds the summary's figures and the path ratios against the oracles to `row`."""
    row.update({k: summary[k] for k in ("state", "message", "duration_s", "collisions",
                                        "min_true_clearance_m", "max_navigation_error_m",
                                        "executed_length_m")})
    mission = yaml.safe_load(open(os.path.join(run_dir, "mission.yaml")))["mission"]
    for key, resolution in (("path_ratios", TRUE_MAP_RESOLUTION),
                            ("path_ratios_map_res", MAP_RESOLUTION)):
        true_map = true_map_for(world, seed, cache, resolution)
        ratios = []
        for query in summary["queries"]:
            if not query["succeeded"]:
                continue
            # Same end points as the vehicle: start and end of the executed query.
            length, error = oracle_length(true_map, query["start"], query["end"])
            if length:
                ratios.append(query["executed_length_m"] / length)
            else:
                row.setdefault("oracle_errors", []).append(error)
        row[key] = [round(r, 3) for r in ratios]
    events_path = os.path.join(run_dir, "mission", "events.csv")
    if os.path.exists(events_path):
        # Planner cancels of the active waypoint (blocked root or approach): each holds the
        # vehicle and replans from where it is.
        with open(events_path) as events:
            row["cancels"] = sum(1 for line in events if "/cancel," in line)
    row["path_ratios_own_map"], own_errors = own_map_ratios(run_dir, summary)
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


def run_mission(world, seed, args, runs_dir):
    run_dir = os.path.join(runs_dir, f"{world}-{seed}")
    shutil.rmtree(run_dir, ignore_errors=True)
    scenario = world if args.navigation == "drift" else \
        ideal_navigation_scenario(world, seed, runs_dir)
    command = [find_program("auv"), "launch", args.launch, f"world:={scenario}", f"seed:={seed}",
               "auto_mission:=true", f"real_time_factor:={args.real_time_factor}",
               f"domain:={args.domain}", f"run_dir:={run_dir}", f"objective:={args.objective}"]
    command += args.launch_arg
    if args.prior_map:
        command.append(f"initial_map:={true_map_for(world, seed, runs_dir, map_resolution(args))}")
    started = time.monotonic()
    with open(os.path.join(runs_dir, f"{world}-{seed}.log"), "w") as log:
        try:
            code = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=args.timeout).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    wall = time.monotonic() - started
    summary_path = os.path.join(run_dir, "mission", "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else None
    return run_dir, code, wall, summary


def write_results(rows, worlds, stamp, setup, quiet=False):
    """The campaign table (per world) and every run, as .md and .json in bench_results/."""
    results_dir = os.path.join(ROOT, "bench_results")
    lines = [f"# Mission campaign {stamp}", "",
             f"{setup}; clearance {CLEARANCE} m; "
             f"oracle: planning_oracle on the true map at {TRUE_MAP_RESOLUTION} m and at the "
             f"planner's {MAP_RESOLUTION} m, grid {ORACLE_GRID} m, between the executed query's "
             "true start and end; on the vehicle's final map (mission/map.bt, navigation frame) "
             f"at clearance {CLEARANCE} m + half a voxel between the navigation estimates at "
             "the query's start and end.", "",
             "| world | runs | succeeded | collisions (runs with any) | min true clearance (m) | "
             f"path / oracle {TRUE_MAP_RESOLUTION} m median (max) | path / oracle "
             f"{MAP_RESOLUTION} m median (max) | path / oracle on the vehicle's final map "
             "median (max) | max nav error (m) | wall s / run |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for world in worlds:
        mine = [r for r in rows if r["world"] == world]
        done = [r for r in mine if r.get("state") == "SUCCEEDED"]
        collided = [r for r in mine if r.get("collisions", 0) > 0]
        clearances = [r["min_true_clearance_m"] for r in mine
                      if r.get("min_true_clearance_m") is not None]
        ratios = [x for r in mine for x in r.get("path_ratios", [])]
        ratios_map_res = [x for r in mine for x in r.get("path_ratios_map_res", [])]
        ratios_own = [x for r in mine for x in r.get("path_ratios_own_map", [])]
        nav = [r["max_navigation_error_m"] for r in mine if r.get("max_navigation_error_m")]
        walls = [r["wall_s"] for r in mine if r.get("wall_s") is not None]
        def cell(values, text):
            return text(values) if values else "-"
        def median_max(v):
            return f"{statistics.median(v):.3f} ({max(v):.3f})"
        lines.append(" | ".join([
            f"| {world}", str(len(mine)), str(len(done)),
            f"{sum(r.get('collisions', 0) for r in mine)} ({len(collided)})",
            cell(clearances, lambda v: f"{min(v):.2f}"), cell(ratios, median_max),
            cell(ratios_map_res, median_max), cell(ratios_own, median_max),
            cell(nav, lambda v: f"{max(v):.2f}"),
            cell(walls, lambda v: f"{statistics.mean(v):.0f}")]) + " |")
    lines += ["", "Per run:", "", "```"] + [json.dumps(r) for r in rows] + ["```"]
    md = os.path.join(results_dir, f"mission_campaign_{stamp}.md")
    open(md, "w").write("\n".join(lines) + "\n")
    json.dump(rows, open(os.path.join(results_dir, f"mission_campaign_{stamp}.json"), "w"),
              indent=1)
    if not quiet:
        print("\n".join(lines[:len(worlds) + 6]))
        print(f"results: {md}")


def evaluate_runs(run_dirs):
    """Path ratios of finished runs (<world>-<seed> folders with mission/summary.json)."""
    rows = []
    for run_dir in run_dirs:
        run_dir = os.path.abspath(run_dir)
        world, _, seed = os.path.basename(run_dir.rstrip("/")).rpartition("-")
        summary_path = os.path.join(run_dir, "mission", "summary.json")
        if not world or not seed.isdigit() or not os.path.exists(summary_path):
            sys.exit(f"run_mission_campaign: {run_dir}: not a <world>-<seed> run folder with "
                     "mission/summary.json")
        row = {"world": world, "seed": int(seed), "run": run_dir}
        evaluate(row, world, int(seed), run_dir, json.load(open(summary_path)),
                 os.path.dirname(run_dir))
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", default="canyon,breakwater,dead_end_bay")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--real-time-factor", type=float, default=8.0)
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
    parser.add_argument("--keep-runs", action="store_true", help="keep the run folders")
    parser.add_argument("--seed-major", action="store_true",
                        help="run seed by seed across the worlds (default: world by world)")
    parser.add_argument("--evaluate", nargs="+", metavar="RUN_DIR",
                        help="only evaluate finished run folders (no missions are run)")
    args = parser.parse_args()

    stamp = datetime.datetime.now().strftime("%Y%m%d_%H%M%S")
    if not args.evaluate:
        stamp += f"_d{args.domain}"  # campaigns started together on other domains differ
    if args.evaluate:
        rows = evaluate_runs(args.evaluate)
        worlds = list(dict.fromkeys(r["world"] for r in rows))
        write_results(rows, worlds, stamp, f"evaluation of {len(rows)} finished runs")
        return
    runs_dir = os.path.join(ROOT, "bench_results", f"mission_campaign_{stamp}")
    os.makedirs(runs_dir, exist_ok=True)
    rows = []
    worlds = args.worlds.split(",")
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    # Seed by seed across the worlds: a campaign stopped early still covers every world.
    order = [(w, s) for s in seeds for w in worlds] if args.seed_major else \
        [(w, s) for w in worlds for s in seeds]
    setup = (f"{os.path.relpath(args.launch, ROOT)}, auto_mission, objective {args.objective}, "
             f"real_time_factor {args.real_time_factor}, navigation "
             + ("drift on (simulator defaults)" if args.navigation == "drift" else
                "ideal (no drift, no noise)")
             + (", prior map: the true map (initial_map)" if args.prior_map else "")
             + "".join(f", {a}" for a in args.launch_arg))
    for world, seed in order:
        run_dir, code, wall, summary = run_mission(world, seed, args, runs_dir)
        row = {"world": world, "seed": seed, "exit": code, "wall_s": round(wall, 1)}
        if summary:
            evaluate(row, world, seed, run_dir, summary, runs_dir)
        else:
            row["state"] = "NO REPORT"
        rows.append(row)
        print(json.dumps(row), flush=True)
        if not args.keep_runs and not row.get("collisions"):  # runs with contacts: evidence
            for sub in ("ground_truth",):
                shutil.rmtree(os.path.join(run_dir, sub), ignore_errors=True)
        # After every run: a campaign stopped early keeps what it measured.
        write_results(rows, worlds, stamp, setup, quiet=True)
    write_results(rows, worlds, stamp, setup)


if __name__ == "__main__":
    main()

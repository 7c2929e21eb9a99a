#!/usr/bin/env python3
"""Fault campaign (benchmark, not a test): vehicle processes killed mid-mission.

For each world, seed and fault it runs the world's inspection mission as the mission campaign
does (`auv launch bringup/launch/vehicle.yaml auto_mission:=true`, navigation drift on) and,
once the mission has started, waits a seeded random time (--after, simulated seconds) and
kills one vehicle process with SIGKILL (`kill:controller`, `kill:mapping`, `kill:planning`,
`kill:mission`): the launch restarts it (restart: on-failure) and the component resumes its
state (docs/reliability.md); or has the simulator inject a sensor fault at that time
(`sonar_silent` 10-60 s, `navigation_silent` 3-20 s, `dvl_lost` 10-60 s, `navigation_jump`
3-8 m in a random direction). Each row says what was expected (the mission completes) and what
happened: the mission's end state, contacts, minimum true clearance, restarts, the time to
recover, and whether every file of the run is whole.

Time to recover (wall seconds, and simulated seconds at the real-time factor): from the kill
to the first waypoint of a query issued after it (the planner's and the mission handler's way
back re-issues the query in progress); for `kill:controller`, to the restarted controller's
first waypoint command (one back before the mission noticed is commanded without a re-issue);
for `kill:mapping`, which does not stop the mission, to its "resumed the map" line.

Each row also says how starved the vehicle stack was: `cpu_wait_ratio`, the time its
processes waited for a CPU while runnable per second they ran (CpuWait), with the load
average at the start and `--note` (what else ran on the machine).

Resumable and mergeable like run_mission_campaign.py: one JSON line per finished run in
--results (default bench_results/fault_campaign.jsonl); runs already there are skipped.

  components/mission/bench/run_fault_campaign.py [--worlds canyon,breakwater,dead_end_bay]
      [--seeds 5] [--first-seed 1] [--faults kill:controller,kill:mapping,kill:planning,
      kill:mission,sonar_silent,navigation_silent,dvl_lost,navigation_jump] [--after 40,400] [--real-time-factor 4] [--domain 46] [--results FILE]
  components/mission/bench/run_fault_campaign.py --report ROWS.jsonl...
"""
import argparse
import csv
import datetime
import json
import math
import os
import random
import signal
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import campaign_table  # noqa: E402
from run_mission_campaign import (LAUNCH, ROOT, append_row, find_program,  # noqa: E402
                                  git_commit)

RESULTS = os.path.join(ROOT, "bench_results", "fault_campaign.jsonl")
KILLS = ("kill:controller", "kill:mapping", "kill:planning", "kill:mission")
# Sensor faults the simulator injects (its `faults` parameter, vehicle.yaml's sim_faults):
# how long (s, simulated) a window lasts, drawn uniformly; a jump's size in m.
SENSOR_FAULTS = {"sonar_silent": (10.0, 60.0), "navigation_silent": (3.0, 20.0),
                 "dvl_lost": (10.0, 60.0), "navigation_jump": (3.0, 8.0)}
FAULTS = KILLS + tuple(SENSOR_FAULTS)
# Files a run must leave whole: the mission log (CSV rows of the header's width), the progress
# and summary (parseable), the final map.
CSV_FILES = ("events.csv", "waypoints.csv", "paths.csv")


def descendants(pid):
    """Pids of every process below `pid` (from /proc)."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as stat:
                parent = int(stat.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(parent, []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def component_pid(launch_pid, component):
    """The pid of `auv run <component>:<component>` under the launch, or None."""
    wanted = f"{component}:{component}"
    for pid in descendants(launch_pid):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as cmdline:
                argv = cmdline.read().split(b"\0")
        except OSError:
            continue
        if b"run" in argv and wanted.encode() in argv:
            return pid
    return None


class CpuWait:
    """How long the launch's processes waited for a CPU while runnable, per second they ran
    (/proc/<pid>/task/*/schedstat, sampled every 2 s; a process killed between samples loses its
    last 2 s). The measure of a starved stack that a load average is not: work beside the
    campaign at idle priority raises the load average but not this."""

    def __init__(self, launch_pid):
        self.launch_pid = launch_pid
        self.last = {}  # (pid, tid) -> (run ns, wait ns)
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._sample, daemon=True)
        self.thread.start()

    def _sample(self):
        while not self.done.wait(2.0):
            for pid in descendants(self.launch_pid):
                try:
                    tids = os.listdir(f"/proc/{pid}/task")
                except OSError:
                    continue
                for tid in tids:
                    try:
                        with open(f"/proc/{pid}/task/{tid}/schedstat") as stat:
                            run, wait = (int(v) for v in stat.read().split()[:2])
                    except (OSError, ValueError):
                        continue
                    self.last[(pid, tid)] = (run, wait)

    def ratio(self):
        self.done.set()
        self.thread.join()
        run = sum(r for r, _ in self.last.values())
        wait = sum(w for _, w in self.last.values())
        return round(wait / run, 3) if run else None


def newest_query(run_dir):
    """The largest query id of the waypoints in the mission's waypoints.csv so far (0: none)."""
    path = os.path.join(run_dir, "mission", "waypoints.csv")
    try:
        with open(path) as rows:
            return max((int(r["query_id"]) for r in csv.DictReader(rows)
                        if (r.get("query_id") or "").isdigit()), default=0)
    except OSError:
        return 0


def files_whole(run_dir):
    """Names of the run's files that are missing or damaged (empty: all whole)."""
    mission = os.path.join(run_dir, "mission")
    damaged = []
    for name in CSV_FILES:
        path = os.path.join(mission, name)
        try:
            with open(path) as rows:
                reader = csv.reader(rows)
                width = len(next(reader))
                if any(len(row) != width for row in reader if row):
                    damaged.append(name)
        except (OSError, StopIteration):
            damaged.append(name)
    for name in ("progress.yaml", "summary.json"):
        path = os.path.join(mission, name)
        try:
            with open(path) as text:
                (json.load if name.endswith(".json") else _load_yaml)(text)
        except Exception:  # noqa: BLE001 - any failure to read is damage
            damaged.append(name)
    if not os.path.exists(os.path.join(mission, "map.bt")):
        damaged.append("map.bt")
    return damaged


def _load_yaml(text):
    import yaml
    return yaml.safe_load(text)


def sensor_fault(fault, at, rng):
    """The simulator's fault entry for `fault` at `at` s (sensors/sensor_faults.h)."""
    low, high = SENSOR_FAULTS[fault]
    if fault == "navigation_jump":
        size, heading = rng.uniform(low, high), rng.uniform(-math.pi, math.pi)
        return f"navigation_jump@{at:.1f}:{size * math.cos(heading):.2f}," \
               f"{size * math.sin(heading):.2f}"
    return f"{fault}@{at:.1f}+{rng.uniform(low, high):.1f}"


def restarted_marker(log, component, pid):
    """Whether the launch log shows `component`, killed as `pid`, doing its job again: the
    mapping resumed its checkpoint; the controller accepted a waypoint command (a controller
    back before the mission noticed is commanded without any re-issue)."""
    killed = log.find(f"{component} (pid {pid}) killed")
    if killed < 0:
        return False
    after = log[killed:]
    if component == "mapping":
        return "resumed the map from" in after
    return any(line.startswith("[controller]") and " WAYPOINT (" in line
               for line in after.splitlines())


def kill_during(launch, component, after_sim, args, run_dir, log_path, result):
    """Kills `component` `after_sim` simulated seconds after the mission started and measures
    the time until the mission (the mapping, for its own kill) is back (into `result`)."""
    started = time.monotonic()
    progress = os.path.join(run_dir, "mission", "progress.yaml")
    while not os.path.exists(progress) and launch.poll() is None and \
            time.monotonic() - started < 600:
        time.sleep(0.2)
    mission_started = time.monotonic()
    deadline = mission_started + after_sim / args.real_time_factor
    while launch.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    pid = component_pid(launch.pid, component) if launch.poll() is None else None
    if not pid:
        result["not_injected_because"] = "the mission ended first" \
            if launch.poll() is not None else f"no {component} process found"
        return
    before = newest_query(run_dir)
    os.kill(pid, signal.SIGKILL)
    killed = time.monotonic()
    result.update(injected=True, killed_pid=pid,
                  killed_at_wall_s=round(killed - mission_started, 1))
    while launch.poll() is None and time.monotonic() - killed < args.timeout:
        time.sleep(0.2)
        if component in ("mapping", "controller"):
            with open(log_path, errors="replace") as text:
                back = restarted_marker(text.read(), component, pid)
        else:
            back = newest_query(run_dir) > before
        if back:
            result["recovery_wall_s"] = round(time.monotonic() - killed, 2)
            result["recovery_sim_s"] = round((time.monotonic() - killed) *
                                             args.real_time_factor, 1)
            return


def run_fault(world, seed, fault, args, out_dir):
    """One mission with one fault; returns the row's measured part."""
    kill = fault in KILLS
    component = fault.split(":", 1)[1] if kill else None
    rng = random.Random(f"{world}-{seed}-{fault}")
    after_sim = rng.uniform(*args.after)
    run_dir = os.path.join(out_dir, f"{world}-{seed}-{component or fault}")
    subprocess.run(["rm", "-rf", run_dir], check=True)
    log_path = os.path.join(out_dir, f"{world}-{seed}-{component or fault}.log")
    command = [find_program("auv"), "launch", LAUNCH, f"world:={world}", f"seed:={seed}",
               "auto_mission:=true", f"real_time_factor:={args.real_time_factor}",
               f"domain:={args.domain}", f"run_dir:={run_dir}"]
    result = {"after_sim_s": round(after_sim, 1), "injected": False}
    if not kill:
        # Simulated time since the start: the mission begins within seconds of it.
        result["sim_faults"] = sensor_fault(fault, after_sim, rng)
        command.append(f"sim_faults:={result['sim_faults']}")
    started = time.monotonic()
    with open(log_path, "w") as log:
        launch = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                  start_new_session=True)
        cpu_wait = CpuWait(launch.pid)
        try:
            if kill:
                kill_during(launch, component, after_sim, args, run_dir, log_path, result)
            launch.wait(timeout=max(1.0, args.timeout - (time.monotonic() - started)))
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGINT)
            launch.wait(timeout=30)
            result["timeout"] = True
        result["cpu_wait_ratio"] = cpu_wait.ratio()
    result["exit"] = launch.returncode
    result["wall_s"] = round(time.monotonic() - started, 1)
    with open(log_path, errors="replace") as text:
        lines = text.read().splitlines()
    result["restarts"] = sum(1 for line in lines if line.startswith("[launch]") and
                             "restarting in" in line)
    result["events"] = {name: sum(1 for line in lines if name in line)
                        for name in ("RESUMED", "PLANNER_REISSUE", "RECOVERY_START",
                                     "RECOVERY_REISSUE")}
    summary_path = os.path.join(run_dir, "mission", "summary.json")
    if os.path.exists(summary_path):
        summary = json.load(open(summary_path))
        result.update({k: summary.get(k) for k in ("state", "message", "duration_s",
                                                    "collisions", "min_true_clearance_m",
                                                    "recoveries")})
        if not kill:  # the fault came while the mission ran (it starts within seconds)
            result["injected"] = (summary.get("duration_s") or 0) > after_sim
    else:
        result["state"] = "NO REPORT"
    result["damaged_files"] = files_whole(run_dir)
    result["run"] = os.path.relpath(run_dir, ROOT)
    return result


def report(rows):
    """Per fault: runs, injected, completed, contacts, damaged files, recovery times."""
    lines = ["| fault | runs | injected | mission completed | held / aborted (reason) | "
             "contacts | damaged files | recovery (sim s, median [min–max]) |",
             "|---|---|---|---|---|---|---|---|"]
    for fault in FAULTS:
        mine = [r for r in rows if r.get("fault") == fault]
        if not mine:
            continue
        injected = [r for r in mine if r.get("injected")]
        done = [r for r in injected if r.get("state") == "SUCCEEDED"]
        other = [f'{r.get("state")}: {(r.get("message") or "")[:60]}' for r in injected
                 if r.get("state") != "SUCCEEDED"]
        times = [r["recovery_sim_s"] for r in injected if "recovery_sim_s" in r]
        lines.append(
            f"| {fault} | {len(mine)} | {len(injected)} | {len(done)}/{len(injected)} | "
            f"{'; '.join(other) or '—'} | {sum(r.get('collisions') or 0 for r in mine)} | "
            f"{sum(len(r.get('damaged_files') or []) for r in mine)} | "
            f"{campaign_table.median_range(times, 1) if times else '—'} |")
    kills = [r for r in rows if r.get("fault") in KILLS and r.get("injected")]
    if kills:
        done = sum(1 for r in kills if r.get("state") == "SUCCEEDED")
        waits = [r["cpu_wait_ratio"] for r in rows if r.get("cpu_wait_ratio") is not None]
        lines.append("")
        lines.append(f"Process crashes: {done}/{len(kills)} missions completed "
                     f"({100.0 * done / len(kills):.1f} %) on "
                     f"{', '.join(sorted({r['world'] for r in kills}))}.")
        if waits:
            lines.append(f"CPU wait of the stack (s waiting per s running), median "
                         f"[min–max] over {len(waits)} rows: "
                         f"{campaign_table.median_range(waits, 3)}.")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--worlds", default="canyon,breakwater,dead_end_bay")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--faults", default=",".join(KILLS),
                        help=f"comma-separated, of: {', '.join(FAULTS)}")
    parser.add_argument("--after", default="40,400",
                        help="simulated seconds after the mission's start: the kill comes at a "
                             "seeded uniform time in this range")
    parser.add_argument("--real-time-factor", type=float, default=4.0)
    parser.add_argument("--domain", type=int, default=46)
    parser.add_argument("--timeout", type=float, default=3600.0, help="s of wall time per run")
    parser.add_argument("--results", default=RESULTS)
    parser.add_argument("--note", default="",
                        help="recorded in each row: what else ran on the machine, say")
    parser.add_argument("--report", nargs="+", metavar="ROWS",
                        help="only print the table of these rows files")
    args = parser.parse_args()
    if args.report:
        print(report(campaign_table.read_rows(args.report)))
        return
    faults = args.faults.split(",")
    for fault in faults:
        if fault not in FAULTS:
            sys.exit(f"run_fault_campaign: --faults: expected {', '.join(FAULTS)}, got '{fault}'")
    try:
        low, high = (float(v) for v in args.after.split(","))
        assert 0 <= low <= high
    except (ValueError, AssertionError):
        sys.exit(f"run_fault_campaign: --after: expected LOW,HIGH seconds, got '{args.after}'")
    args.after = (low, high)
    os.makedirs(os.path.dirname(os.path.abspath(args.results)), exist_ok=True)
    out_dir = os.path.join(ROOT, "bench_results", "fault_campaign_runs")
    os.makedirs(out_dir, exist_ok=True)
    done = {row.get("key") for row in campaign_table.read_rows([args.results])} \
        if os.path.exists(args.results) else set()
    commit = git_commit()
    config = {"real_time_factor": args.real_time_factor, "after": list(args.after)}
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        for world in args.worlds.split(","):
            for fault in faults:
                key = json.dumps({"world": world, "seed": seed, "fault": fault,
                                  "config": config}, sort_keys=True)
                if key in done:
                    continue
                row = {"key": key, "world": world, "seed": seed, "fault": fault, **config,
                       "expected": "mission completed", "commit": commit,
                       "started": datetime.datetime.now().isoformat(timespec="seconds"),
                       "load_average": round(os.getloadavg()[0], 2)}
                if args.note:
                    row["note"] = args.note
                row.update(run_fault(world, seed, fault, args, out_dir))
                append_row(args.results, row)
                print(json.dumps(row), flush=True)
    print(report(campaign_table.read_rows([args.results])))


if __name__ == "__main__":
    main()

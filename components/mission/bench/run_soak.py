#!/usr/bin/env python3
"""Soak (benchmark, not a test): one long mission, its processes' memory and timing sampled.

It launches `bringup/launch/vehicle.yaml` (no auto mission), takes the world's inspection
mission from the run folder, repeats its queries --loops times (the vehicle goes round the site
again and again) and starts that as one mission. While it runs it samples, every
--sample-period wall seconds, the resident memory (VmRSS) and CPU share of each vehicle process
(controller, mapping, planning, mission; a restarted process is followed under its new pid),
and from the topics: the control loop's period (stamps of `control/thrusters`, one per control
step) and the map-update latency (arrival of `map/update`, in simulated time, minus its stamp,
the newest data it holds; a FULL map carries the stamp of the increment before it, so the p99
includes up to full_map_period of age). Figures per 10 simulated minutes: p99 control period,
p50 and p99 map-update latency, RSS per process; memory growth from the second window (the
first is the warm-up) to the last, against the bound (--growth-bound, 5 %; needs 3 windows).

Writes into --out (default bench_results/soak/<world>-<date>): samples.jsonl, windows.json,
summary.json and memory.svg (RSS per process over simulated time).

  components/mission/bench/run_soak.py [--world canyon] [--loops 12] [--real-time-factor 4]
      [--domain 48] [--sample-period 5] [--out DIR]
"""
import argparse
import datetime
import json
import os
import subprocess
import sys
import threading
import time

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_fault_campaign import component_pid  # noqa: E402
from run_mission_campaign import LAUNCH, ROOT, find_program  # noqa: E402

PROCESSES = ("controller", "mapping", "planning", "mission")
WINDOW_S = 600.0  # simulated seconds per window
TICKS = os.sysconf("SC_CLK_TCK")
PAGE_KB = os.sysconf("SC_PAGE_SIZE") // 1024


def process_sample(pid):
    """(RSS in MiB, CPU seconds so far) of `pid`, or None when it is gone."""
    try:
        with open(f"/proc/{pid}/statm") as statm:
            rss_pages = int(statm.read().split()[1])
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
        return rss_pages * PAGE_KB / 1024.0, (int(fields[11]) + int(fields[12])) / TICKS
    except (OSError, IndexError, ValueError):
        return None


class StampReader:
    """`auv topic echo <topic> --field header.stamp` in the background: (wall arrival, stamp
    in simulated seconds) per message."""

    def __init__(self, topic, env):
        self.samples = []
        self.process = subprocess.Popen(
            [find_program("auv"), "topic", "echo", topic, "--field", "header.stamp"],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
            env=env)
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        stamp = {}
        for line in self.process.stdout:
            line = line.strip()
            if line.startswith("sec:"):
                stamp["sec"] = int(line.split(":", 1)[1])
            elif line.startswith("nanosec:"):
                stamp["nanosec"] = int(line.split(":", 1)[1])
            elif line == "---" and len(stamp) == 2:
                self.samples.append((time.monotonic(), stamp["sec"] + 1e-9 * stamp["nanosec"]))
                stamp = {}

    def stop(self):
        self.process.terminate()
        self.process.wait(timeout=10)


def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * (len(ordered) - 1) + 0.5))] if ordered else None


def sim_time_at(wall, clock):
    """Simulated time at wall time `wall`, from (wall, sim) pairs of the control loop."""
    if not clock:
        return None
    lo, hi = 0, len(clock) - 1
    while lo < hi:  # the last pair at or before `wall`
        mid = (lo + hi + 1) // 2
        if clock[mid][0] <= wall:
            lo = mid
        else:
            hi = mid - 1
    return clock[lo][1] + (wall - clock[lo][0]) * ARGS.real_time_factor


def windows(samples, control, maps):
    """Per 10 simulated minutes: p99 control period, p99 map latency, mean RSS per process."""
    out = {}
    for (_, a), (_, b) in zip(control, control[1:]):
        if b > a:
            out.setdefault(int(a // WINDOW_S), {}).setdefault("periods", []).append(b - a)
    for wall, stamp in maps:
        now = sim_time_at(wall, control)
        if now is not None:
            out.setdefault(int(now // WINDOW_S), {}).setdefault("latencies", []).append(now - stamp)
    for row in samples:
        if row.get("sim_s") is None:
            continue
        slot = out.setdefault(int(row["sim_s"] // WINDOW_S), {})
        slot.setdefault("rss", {}).setdefault(row["process"], []).append(row["rss_mib"])
    table = []
    for index in sorted(out):
        slot = out[index]
        table.append({
            "window": index, "from_sim_s": index * WINDOW_S,
            "control_period_p99_ms": round(1e3 * percentile(slot.get("periods", []), 0.99), 2)
            if slot.get("periods") else None,
            "map_latency_p50_s": round(percentile(slot.get("latencies", []), 0.5), 3)
            if slot.get("latencies") else None,
            "map_latency_p99_s": round(percentile(slot.get("latencies", []), 0.99), 3)
            if slot.get("latencies") else None,
            "rss_mib": {p: round(sum(v) / len(v), 1) for p, v in slot.get("rss", {}).items()}})
    return table


def memory_svg(samples, path):
    """RSS per process over simulated time, one polyline each."""
    points = [r for r in samples if r.get("sim_s") is not None]
    if not points:
        return
    width, height, pad = 800, 400, 50
    t_max = max(r["sim_s"] for r in points) or 1.0
    m_max = max(r["rss_mib"] for r in points) or 1.0
    colours = dict(zip(PROCESSES, ("#d62728", "#1f77b4", "#2ca02c", "#9467bd")))
    lines = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}">',
             f'<text x="{pad}" y="20">RSS (MiB, max {m_max:.0f}) over simulated time '
             f'(s, max {t_max:.0f})</text>']
    for process in PROCESSES:
        mine = [r for r in points if r["process"] == process]
        xy = " ".join(f'{pad + (width - 2 * pad) * r["sim_s"] / t_max:.1f},'
                      f'{height - pad - (height - 2 * pad) * r["rss_mib"] / m_max:.1f}'
                      for r in mine)
        lines.append(f'<polyline fill="none" stroke="{colours[process]}" points="{xy}"/>')
        lines.append(f'<text x="{width - pad - 80}" y="{40 + 15 * PROCESSES.index(process)}" '
                     f'fill="{colours[process]}">{process}</text>')
    lines.append("</svg>")
    with open(path, "w") as svg:
        svg.write("\n".join(lines) + "\n")


def main():
    global ARGS
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--world", default="canyon")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--loops", type=int, default=12,
                        help="times the world's mission is flown in one mission (canyon: ~10 "
                             "simulated minutes each, so 12 is 2 simulated hours)")
    parser.add_argument("--real-time-factor", type=float, default=4.0)
    parser.add_argument("--domain", type=int, default=48)
    parser.add_argument("--sample-period", type=float, default=5.0, help="wall seconds")
    parser.add_argument("--growth-bound", type=float, default=0.05,
                        help="largest accepted RSS growth after the first window (fraction)")
    parser.add_argument("--out")
    ARGS = args = parser.parse_args()
    if args.loops < 1:
        sys.exit("run_soak: --loops must be >= 1")
    out = args.out or os.path.join(
        ROOT, "bench_results", "soak",
        f"{args.world}-{datetime.datetime.now().strftime('%Y%m%dT%H%M%S')}")
    os.makedirs(out, exist_ok=True)
    run_dir = os.path.join(out, "run")
    env = dict(os.environ, AUV_DOMAIN_ID=str(args.domain))
    launch_log = open(os.path.join(out, "launch.log"), "w")
    launch = subprocess.Popen(
        [find_program("auv"), "launch", LAUNCH, f"world:={args.world}", f"seed:={args.seed}",
         f"real_time_factor:={args.real_time_factor}", f"domain:={args.domain}",
         f"run_dir:={run_dir}"], stdout=launch_log, stderr=subprocess.STDOUT,
        start_new_session=True)
    control = maps = None
    samples = []
    try:
        mission_file = os.path.join(run_dir, "mission.yaml")
        for _ in range(600):
            if os.path.exists(mission_file) or launch.poll() is not None:
                break
            time.sleep(0.5)
        mission = yaml.safe_load(open(mission_file))
        queries = mission["mission"]["queries"]
        mission["mission"]["queries"] = [dict(q, name=f"{q.get('name', 'q')}-loop{k + 1}")
                                         for k in range(args.loops) for q in queries]
        mission["mission"]["name"] = f"soak-{args.world}"
        soak_file = os.path.join(out, "soak_mission.yaml")
        with open(soak_file, "w") as text:
            yaml.safe_dump(mission, text, sort_keys=False)
        control = StampReader("control/thrusters", env)
        maps = StampReader("map/update", env)
        runner = subprocess.Popen(
            [find_program("auv"), "mission", "start", soak_file, "--wait", "--report", run_dir,
             "--timeout", "300"], stdout=open(os.path.join(out, "mission.log"), "w"),
            stderr=subprocess.STDOUT, env=env)
        started = time.monotonic()
        last_cpu = {}
        while runner.poll() is None and launch.poll() is None:
            time.sleep(args.sample_period)
            now = time.monotonic()
            sim_s = sim_time_at(now, control.samples)
            for process in PROCESSES:
                pid = component_pid(launch.pid, process)
                sample = process_sample(pid) if pid else None
                if not sample:
                    continue
                rss, cpu = sample
                previous = last_cpu.get(process)
                share = (cpu - previous[1]) / (now - previous[0]) \
                    if previous and previous[2] == pid else None
                last_cpu[process] = (now, cpu, pid)
                samples.append({"wall_s": round(now - started, 1),
                                "sim_s": round(sim_s, 1) if sim_s is not None else None,
                                "process": process, "pid": pid, "rss_mib": round(rss, 2),
                                "cpu": round(share, 3) if share is not None else None})
    finally:
        for reader in (control, maps):
            if reader:
                reader.stop()
        os.killpg(launch.pid, 2)
        launch.wait(timeout=60)
    with open(os.path.join(out, "samples.jsonl"), "w") as rows:
        for row in samples:
            rows.write(json.dumps(row) + "\n")
    table = windows(samples, control.samples, maps.samples)
    with open(os.path.join(out, "windows.json"), "w") as text:
        json.dump(table, text, indent=1)
    memory_svg(samples, os.path.join(out, "memory.svg"))
    growth = {}
    if len(table) >= 3:  # the first window is the warm-up
        for process in PROCESSES:
            first = table[1]["rss_mib"].get(process)
            last = table[-1]["rss_mib"].get(process)
            if first and last:
                growth[process] = round(last / first - 1.0, 4)
    summary_path = os.path.join(run_dir, "mission", "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    result = {"world": args.world, "loops": args.loops, "real_time_factor": args.real_time_factor,
              "mission_state": summary.get("state"), "duration_s": summary.get("duration_s"),
              "collisions": summary.get("collisions"), "windows": len(table),
              "rss_growth_after_warm_up": growth, "growth_bound": args.growth_bound,
              "growth_within_bound": all(g <= args.growth_bound for g in growth.values())
              if growth else None}
    with open(os.path.join(out, "summary.json"), "w") as text:
        json.dump(result, text, indent=1)
    print(json.dumps(result, indent=1))
    print(json.dumps(table, indent=1))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Two-visit change campaign (benchmark, not a test): the canyon visited again after seeded changes,
over many change seeds, each compared with the first visit and scored against the truth.

One first visit is shared by every seed (the site before): the canyon mission, its survey and its
reconstruction (`make_canyon_survey.sh`, `auv recon run`). Then per change seed:

  1. `auv sim generate canyon --seed <world seed> --epoch 2 --changes-seed <seed>`: the same site
     with seeded changes (a fallen block, a removed and a moved boulder, growth, scour, a bleached
     patch) under the first query's route;
  2. the second visit: the mission from the first visit's map (`align_initial_map`: the prior is
     registered to the new sonar returns before it is trusted), its cameras and survey
     (`make_canyon_survey.sh --world <epoch-2 scenario> --initial-map <visit 1>/mission/map.bt`);
  3. `auv recon run`, `auv recon compare <visit 1> <visit 2>`, `auv recon evaluate <visit 2>`.

Each seed appends one JSON line to --results: the changes placed, the prior map's alignment,
the mission's outcome, per true region its status (detected / missed / not measured) and volume
error, the clusters' verdicts (true / false), the false change on stable surface, the
registration and the time of every step. A seed whose key (world, world seed, change seed,
stretch of the route) is already in the file is skipped, so a
campaign stopped or killed goes on where it was by running the same command again (only the seed
in progress is redone; a finished visit folder without a row is refused, not redone over;
--retry-failed runs failed seeds again); files from several machines are merged by --report,
which pools them (the last row of a seed counts):

  reconstruction/bench/change/run_two_visit_campaign.py [--seeds 8] [--first-seed 1]
      [--world-seed 1] [--changes-along F,T] [--work DIR] [--results FILE.jsonl] [--domain 47]
      [--control]
  reconstruction/bench/change/run_two_visit_campaign.py --report ROWS.jsonl...
  reconstruction/bench/change/run_two_visit_campaign.py --rescore --results NEW.jsonl [--work DIR]

--control also flies a control visit: the site unchanged (`auv sim generate --epoch 2
--no-changes`), where every change found is false (key changes_seed "none").

--rescore runs only compare and evaluate again on every finished seed in --work (after a change
to either; the missions and reconstructions are kept) and writes their rows to --results.

Figures pooled over seeds (issue 21): recall = detected / (detected + missed) over the true
regions of >= 10 cm measured by both visits; precision = true / (true + false) clusters; false
change = significant core points in clusters on stable surface / measured stable core points;
block volumes (add / remove / move) within 20 %.
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

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
SURVEY_SCRIPT = os.path.join(ROOT, "reconstruction", "bench", "pipeline", "make_canyon_survey.sh")
RESULTS = os.path.join(ROOT, "bench_results", "two_visit_campaign.jsonl")
WORK = os.path.join(ROOT, "bench_results", "two_visit")
CONTROL = "none"  # the changes seed of a control visit: nothing changed
WORLD = "canyon"  # make_canyon_survey.sh films the canyon's first traverse


def log(message):
    print(f"[{datetime.datetime.now():%H:%M:%S}] {message}", flush=True)


def run(command, log_file):
    """Runs `command` with its output in `log_file`; raises with the log's tail on failure."""
    with open(log_file, "a") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        status = subprocess.call(command, stdout=out, stderr=subprocess.STDOUT, cwd=ROOT)
    if status != 0:
        with open(log_file) as f:
            tail = "".join(f.readlines()[-15:])
        raise RuntimeError(f"{' '.join(command[:4])} exited with {status}:\n{tail}")


def read_json(path, default=None):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return default


def git_commit():
    try:
        return subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                       text=True, stderr=subprocess.DEVNULL).strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def first_visit(args):
    """The shared first visit: mission, survey, reconstruction. Reused once it finished."""
    folder = os.path.join(args.work, f"{WORLD}-w{args.world_seed}-visit1")
    run_dir, survey = os.path.join(folder, "run"), os.path.join(folder, "survey")
    done = os.path.join(folder, "DONE")
    if os.path.exists(done):
        return run_dir, survey
    log(f"first visit -> {folder}")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    log_file = os.path.join(folder, "log.txt")
    run([SURVEY_SCRIPT, "--world", WORLD, "--seed", str(args.world_seed), "--run", run_dir,
         "--survey", survey, "--domain", str(args.domain)], log_file)
    run(["auv", "recon", "run", survey], log_file)
    open(done, "w").close()
    return run_dir, survey


def region_rows(change):
    rows = []
    for r in change.get("regions", []):
        errors = r.get("errors", {})
        rows.append({
            "name": r["name"], "type": r["type"], "status": r["status"],
            "magnitude_m": r.get("magnitude_m"), "measured_fraction": r.get("measured_fraction"),
            "hit_fraction": r.get("hit_fraction"),
            "volume_true_m3": errors.get("volume_true_m3"),
            "volume_relative": errors.get("volume_relative"),
            "volume_within_20_percent": errors.get("volume_within_20_percent"),
            "mean_distance_error_m": errors.get("mean_distance_m")})
    return rows


def cluster_rows(change):
    return [{"verdict": c["verdict"], "region": c.get("region"), "area_m2": c.get("area_m2"),
             "mean_distance_m": c.get("mean_distance_m"),
             "max_abs_distance_m": c.get("max_abs_distance_m"),
             "centroid": c.get("centroid")} for c in change.get("clusters", [])]


def visit_folder(args, seed):
    return os.path.join(args.work, f"{WORLD}-w{args.world_seed}-changes{seed}")


def second_visit(args, seed, visit1_run, visit1_survey):
    """One change seed: site, mission, survey, reconstruction, compare, evaluate -> one row."""
    folder = visit_folder(args, seed)
    shutil.rmtree(folder, ignore_errors=True)  # a seed in progress when stopped is redone
    os.makedirs(folder)
    log_file = os.path.join(folder, "log.txt")
    site, run_dir = os.path.join(folder, "site"), os.path.join(folder, "run")
    survey = os.path.join(folder, "survey")
    row = new_row(args, seed)
    step_start = time.time()

    def timed(name, command):
        nonlocal step_start
        run(command, log_file)
        row["seconds"][name] = round(time.time() - step_start, 1)
        step_start = time.time()

    try:
        generate = ["auv", "sim", "generate", WORLD, "--seed", str(args.world_seed), "--epoch",
                    "2", "--out", site]
        generate += ["--no-changes"] if seed == CONTROL else ["--changes-seed", str(seed)]
        if args.changes_along and seed != CONTROL:
            generate += ["--changes-along", args.changes_along]
        timed("generate", generate)
        timed("mission_and_render",
              [SURVEY_SCRIPT, "--world", os.path.join(site, f"{WORLD}_epoch2.yaml"), "--seed",
               str(args.world_seed + 1), "--run", run_dir, "--survey", survey, "--initial-map",
               os.path.join(visit1_run, "mission", "map.bt"), "--domain", str(args.domain)])
        mission_facts(row, run_dir)
        timed("reconstruction", ["auv", "recon", "run", survey])
    except RuntimeError as error:
        row["status"] = "failed"
        row["error"] = str(error)
        return row
    score(row, folder, visit1_survey)
    return row


def mission_facts(row, run_dir):
    """The second visit's mission outcome and its prior map's alignment, into its row."""
    summary = read_json(os.path.join(run_dir, "mission", "summary.json"), {})
    row["mission"] = {k: summary.get(k) for k in ("state", "collisions", "min_true_clearance_m",
                                               "max_navigation_error_m", "duration_s")}
    row["prior_alignment"] = read_json(os.path.join(run_dir, "maps", "prior_alignment.json"))


def score(row, folder, visit1_survey):
    """compare and evaluate of a seed's finished second visit, into its row."""
    survey, log_file = os.path.join(folder, "survey"), os.path.join(folder, "log.txt")
    try:
        for name, command in (("compare", ["auv", "recon", "compare", visit1_survey, survey]),
                              ("evaluate", ["auv", "recon", "evaluate", survey])):
            start = time.time()
            run(command, log_file)
            row["seconds"][name] = round(time.time() - start, 1)
    except RuntimeError as error:
        row["status"] = "failed"
        row["error"] = str(error)
        return
    report = read_json(os.path.join(survey, "change", "report.json"), {})
    change = read_json(os.path.join(survey, "evaluation.json"), {}).get("change", {})
    row["status"] = change.get("status", "not evaluated")
    row["compare"] = {"registration": report.get("registration"),
                      "seconds": report.get("seconds"),
                      "core_points_measured": report.get("core_points_measured"),
                      "core_points_significant": report.get("core_points_significant")}
    row["scores"] = {k: change.get(k) for k in ("regions_scored", "clusters_scored", "stable")}
    row["regions"] = region_rows(change)
    row["clusters"] = cluster_rows(change)


def rescore(args):
    """compare + evaluate again on the finished seeds of --work; rows to --results."""
    visit1_survey = os.path.join(args.work, f"{WORLD}-w{args.world_seed}-visit1", "survey")
    old = {json.dumps(r["key"], sort_keys=True): r for r in load_rows([args.old_results])}
    for seed in [CONTROL] + list(range(args.first_seed, args.first_seed + args.seeds)):
        folder = visit_folder(args, seed)
        if not os.path.exists(os.path.join(folder, "survey", "evaluation.json")):
            continue  # not finished (or in progress in another campaign)
        row = new_row(args, seed)
        row["seconds"] = old.get(json.dumps(key(args, seed), sort_keys=True), {}).get(
            "seconds", {})  # the mission's and reconstruction's, kept
        mission_facts(row, os.path.join(folder, "run"))
        log(f"rescoring change seed {seed}")
        score(row, folder, visit1_survey)
        with open(args.results, "a") as out:
            out.write(json.dumps(row) + "\n")
    report([args.results])


def new_row(args, seed):
    return {"key": key(args, seed), "world": WORLD, "world_seed": args.world_seed,
            "changes_seed": seed, "changes_along": args.changes_along, "commit": git_commit(),
            "date": datetime.date.today().isoformat(), "seconds": {}}


def key(args, seed):
    return {"world": WORLD, "world_seed": args.world_seed, "changes_seed": seed,
            "changes_along": args.changes_along or "default"}


def load_rows(paths):
    rows = []
    for path in paths:
        if not os.path.exists(path):
            continue
        with open(path) as f:
            for number, line in enumerate(f, 1):
                if not line.strip():
                    continue
                try:
                    rows.append(json.loads(line))
                except ValueError:
                    print(f"{path}:{number}: not a JSON row, skipped (a run killed while "
                          "writing?)", file=sys.stderr)
    return rows


def percent(part, whole):
    return f"{100.0 * part / whole:.1f} %" if whole else "n/a"


def report(paths):
    """Per seed and pooled figures of one or more result files (later rows of a key win)."""
    rows = {json.dumps(r["key"], sort_keys=True): r for r in load_rows(paths)}
    rows = sorted(rows.values(), key=lambda r: (r["world_seed"], str(r["changes_seed"]).zfill(6)))
    print("| change seed | mission | prior aligned | detected / measured | not measured | "
          "true / false clusters | false change (clusters) | block volumes | reg. RMS | "
          "recon + compare |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    pooled = {"detected": 0, "missed": 0, "not_measured": 0, "true": 0, "false": 0,
              "stable": 0, "stable_false": 0}
    volumes, by_type, failed, controls = [], {}, 0, []
    for r in rows:
        if r.get("status") != "evaluated":
            failed += 1
            print(f"| {r['changes_seed']} | {r.get('status')}: "
                  f"{(r.get('error') or '').splitlines()[0] if r.get('error') else ''} "
                  "| | | | | | | | |")
            continue
        s = r["scores"]
        rs, cs, st = s["regions_scored"], s["clusters_scored"], s["stable"]
        if r["changes_seed"] == CONTROL:  # not pooled: its clusters are all false
            controls.append(f"control visit (nothing changed): {cs['false']} false clusters, "
                            f"false change in clusters "
                            f"{percent(st['core_points_significant_in_clusters'], st['core_points_measured'])}"
                            f", all significant {percent(st['core_points_significant'], st['core_points_measured'])}")
            continue
        pooled["detected"] += rs["detected"]
        pooled["missed"] += rs["missed"]
        pooled["not_measured"] += rs["not_measured"]
        pooled["true"] += cs["true"]
        pooled["false"] += cs["false"]
        pooled["stable"] += st["core_points_measured"]
        pooled["stable_false"] += st["core_points_significant_in_clusters"]
        blocks = []
        for region in r["regions"]:
            t = by_type.setdefault(region["type"], {})
            t[region["status"]] = t.get(region["status"], 0) + 1
            if region.get("volume_relative") is not None and region["type"] in (
                    "add", "remove", "move"):
                volumes.append(region["volume_relative"])
                blocks.append(f"{region['name']} {100 * region['volume_relative']:+.0f} %")
        prior = r.get("prior_alignment") or {}
        aligned = prior.get("state") or prior.get("status") or ("yes" if prior else "n/a")
        reg = (r["compare"].get("registration") or {}).get("rms_m")
        secs = r["seconds"]
        print(f"| {r['changes_seed']} | {r['mission'].get('state')} | {aligned} | "
              f"{rs['detected']} / {rs['detected'] + rs['missed']} | {rs['not_measured']} | "
              f"{cs['true']} / {cs['false']} | "
              f"{percent(st['core_points_significant_in_clusters'], st['core_points_measured'])}"
              f" | {', '.join(blocks) or '-'} | "
              f"{'%.1f cm' % (100 * reg) if reg is not None else 'n/a'} | "
              f"{secs.get('reconstruction', 0) + secs.get('compare', 0):.0f} s |")
    measured = pooled["detected"] + pooled["missed"]
    clusters = pooled["true"] + pooled["false"]
    within = sum(1 for v in volumes if abs(v) <= 0.2)
    print()
    print(f"{len(rows)} seeds ({failed} failed or not evaluated); pooled: recall "
          f"{pooled['detected']}/{measured} ({percent(pooled['detected'], measured)}), "
          f"{pooled['not_measured']} regions not measured; precision {pooled['true']}/{clusters} "
          f"({percent(pooled['true'], clusters)}); false change in clusters "
          f"{percent(pooled['stable_false'], pooled['stable'])} of the stable core points; "
          f"block volumes within 20 %: {within}/{len(volumes)}"
          + (f" (median |error| {100 * statistics.median(abs(v) for v in volumes):.0f} %)"
             if volumes else ""))
    for line in controls:
        print(line)
    print("per type: " + "; ".join(f"{t}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items()))
                                   for t, c in sorted(by_type.items())))


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=8, help="change seeds to run")
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument("--world-seed", type=int, default=1, help="the canyon's seed")
    parser.add_argument("--changes-along", default="",
                        help="F,T: the stretch of the first query's route the changes are "
                             "placed under (auv sim generate's default when empty)")
    parser.add_argument("--work", default=WORK, help="folder of the visits")
    parser.add_argument("--results", default=RESULTS)
    parser.add_argument("--domain", type=int, default=47, help="DDS domain of the missions")
    parser.add_argument("--control", action="store_true",
                        help="also a control visit of the unchanged site")
    parser.add_argument("--rescore", action="store_true",
                        help="compare + evaluate again on the finished seeds of --work")
    parser.add_argument("--old-results", default=RESULTS,
                        help="--rescore: the rows whose mission figures are carried over")
    parser.add_argument("--retry-failed", action="store_true",
                        help="run again the seeds whose row says failed (the report keeps "
                             "the last row of a seed)")
    parser.add_argument("--report", nargs="+", metavar="ROWS.jsonl",
                        help="print the figures of these result files and stop")
    return parser.parse_args()


def main():
    args = parse_args()
    if args.report:
        report(args.report)
        return
    if shutil.which("auv") is None:
        sys.exit("run_two_visit_campaign: `auv` not found: source install/setup.bash first")
    args.work = os.path.abspath(args.work)
    args.results = os.path.abspath(args.results)
    os.makedirs(os.path.dirname(args.results), exist_ok=True)
    if args.rescore:
        if os.path.abspath(args.old_results) == args.results:
            sys.exit("run_two_visit_campaign: --rescore writes new rows: give --results a new file")
        rescore(args)
        return
    done = {json.dumps(r["key"], sort_keys=True) for r in load_rows([args.results])
            if not (args.retry_failed and r.get("status") == "failed")}
    seeds = [CONTROL] if args.control else []
    seeds += list(range(args.first_seed, args.first_seed + args.seeds))
    seeds = [s for s in seeds if json.dumps(key(args, s), sort_keys=True) not in done]
    # A finished visit whose row is not in --results (another file, a lost line) is not
    # redone over: its folder is the only copy of its mission and reconstruction.
    for seed in seeds:
        finished = os.path.join(visit_folder(args, seed), "survey", "evaluation.json")
        if os.path.exists(finished):
            sys.exit(f"run_two_visit_campaign: {finished} exists but change seed {seed} has no "
                     f"row in {args.results}: give the --results that holds it, or move the "
                     "folder away to run the visit again")
    log(f"{len(seeds)} visits to run (the others are in {args.results})")
    if not seeds:
        report([args.results])
        return
    visit1_run, visit1_survey = first_visit(args)
    for seed in seeds:
        log(f"change seed {seed}")
        row = second_visit(args, seed, visit1_run, visit1_survey)
        with open(args.results, "a") as out:  # one line per finished seed: resumable
            out.write(json.dumps(row) + "\n")
        log(f"change seed {seed}: {row['status']} "
            f"{json.dumps(row.get('scores', {}).get('clusters_scored'))}")
    report([args.results])


if __name__ == "__main__":
    main()

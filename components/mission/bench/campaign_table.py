#!/usr/bin/env python3
"""Markdown tables of mission campaign rows (run_mission_campaign.py --results FILE.jsonl).

  components/mission/bench/campaign_table.py ROWS.jsonl... [--out TABLES.md]

Reads one or more .jsonl files (one finished run per line; several sessions' files merge, a
run present twice counts once: the last row of its key wins) and prints, per real-time factor:
per world and planner mode the runs, successes, recoveries, contacts, minimum true clearance and
path / oracle per query; then the baseline comparisons (tree repair against each from-scratch
planner present: medians of path length and mission time over the seeds both modes finished).
"""
import argparse
import json
import statistics
import sys


def read_rows(paths):
    """Rows of every file, the last of each key kept; lines that do not parse (a run cut off
    while its line was written) are skipped with a note on stderr."""
    rows = {}
    for path in paths:
        with open(path) as lines:
            for number, line in enumerate(lines, 1):
                line = line.strip()
                if not line:
                    continue
                try:
                    row = json.loads(line)
                except json.JSONDecodeError:
                    print(f"campaign_table: {path}:{number}: not a JSON row, skipped",
                          file=sys.stderr)
                    continue
                rows[row.get("key") or json.dumps(row, sort_keys=True)] = row
    return list(rows.values())


def median_range(values, digits=2):
    if not values:
        return "-"
    return (f"{statistics.median(values):.{digits}f} "
            f"({min(values):.{digits}f}–{max(values):.{digits}f})")


def rtf_text(rtf):
    return "as fast as possible" if rtf == 0 else f"{rtf:g}×"


def outcome_table(rows, rtf):
    lines = [f"Real-time factor {rtf_text(rtf)}; path ÷ oracle per succeeded query, against "
             "the 3-D oracle where the query plans in 3-D and the 2-D one at fixed depth "
             "(same clearance).", "",
             "| world | planner | real-time factor | runs | succeeded | recoveries used (runs) "
             "| runs with contacts | min true clearance: min (median) | path ÷ oracle per "
             "query: median (range) | mission time s: median |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    groups = sorted({(r["world"], r.get("planner", "repair")) for r in rows})
    for world, planner in groups:
        mine = [r for r in rows if r["world"] == world and r.get("planner", "repair") == planner]
        done = [r for r in mine if r.get("state") == "SUCCEEDED"]
        recoveries = [r.get("recoveries", 0) or 0 for r in mine]
        contacts = [r for r in mine if (r.get("collisions") or 0) > 0]
        clearances = [r["min_true_clearance_m"] for r in mine
                      if r.get("min_true_clearance_m") is not None]
        ratios = [q["ratio"] for r in mine for q in r.get("query_results", [])
                  if q.get("ratio") is not None]
        times = [r["duration_s"] for r in done if r.get("duration_s") is not None]
        clearance = (f"{min(clearances):.2f} m ({statistics.median(clearances):.2f})"
                     if clearances else "-")
        time = f"{statistics.median(times):.0f}" if times else "-"
        lines.append(f"| {world} | {planner} | {rtf_text(rtf)} | {len(mine)} | {len(done)} | "
                     f"{sum(recoveries)} ({sum(1 for x in recoveries if x)}) | "
                     f"{len(contacts)} | {clearance} | {median_range(ratios)} | {time} |")
    return lines


BASELINES = {"scratch": "OMPL's RRTstar from scratch",
             "restart": "the repair planner's tree restarted, no reuse"}


def comparison_table(rows, rtf, baseline):
    """Repair against `baseline` on the (world, seed) pairs both finished successfully."""
    lines = [f"Tree repair against the baseline `{baseline}` ({BASELINES[baseline]}), real-time "
             f"factor {rtf_text(rtf)}: medians over the seeds both modes completed (executed "
             "path length of the whole mission, mission time).", "",
             f"| world | real-time factor | seeds | path length m: repair / {baseline} | mission "
             f"time s: repair / {baseline} | path ÷ oracle median: repair / {baseline} | repair "
             "better? |",
             "|---|---|---|---|---|---|---|"]
    done = {}
    for r in rows:
        if r.get("state") == "SUCCEEDED":
            done[(r["world"], r["seed"], r.get("planner", "repair"))] = r
    any_row = False
    for world in sorted({r["world"] for r in rows}):
        seeds = sorted({s for (w, s, p) in done if w == world and p == "repair"} &
                       {s for (w, s, p) in done if w == world and p == baseline})
        if not seeds:
            continue
        any_row = True
        pick = {p: [done[(world, s, p)] for s in seeds] for p in ("repair", baseline)}
        length = {p: statistics.median(r["executed_length_m"] for r in pick[p]) for p in pick}
        time = {p: statistics.median(r["duration_s"] for r in pick[p]) for p in pick}
        ratio = {}
        for p in pick:
            values = [q["ratio"] for r in pick[p] for q in r.get("query_results", [])
                      if q.get("ratio") is not None]
            ratio[p] = f"{statistics.median(values):.2f}" if values else "-"
        shorter = length["repair"] < length[baseline]
        faster = time["repair"] < time[baseline]
        verdict = ("yes" if shorter and faster else "length only" if shorter
                   else "time only" if faster else "no")
        lines.append(f"| {world} | {rtf_text(rtf)} | {len(seeds)} | {length['repair']:.1f} / "
                     f"{length[baseline]:.1f} | {time['repair']:.0f} / {time[baseline]:.0f} | "
                     f"{ratio['repair']} / {ratio[baseline]} | {verdict} |")
    return lines if any_row else []


def report(rows):
    """The Markdown text: one outcome table and one comparison (if any) per real-time factor."""
    out = []
    for rtf in sorted({r.get("real_time_factor", 0) for r in rows}):
        mine = [r for r in rows if r.get("real_time_factor", 0) == rtf]
        commits = sorted({r.get("commit", "?") for r in mine})
        out += [f"### Real-time factor {rtf_text(rtf)} ({len(mine)} runs; commits "
                f"{', '.join(commits)})", ""]
        out += outcome_table(mine, rtf) + [""]
        for baseline in BASELINES:
            comparison = comparison_table(mine, rtf, baseline)
            if comparison:
                out += comparison + [""]
    return "\n".join(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("rows", nargs="+", help="campaign rows (.jsonl)")
    parser.add_argument("--out", help="also write the tables to this Markdown file")
    args = parser.parse_args()
    rows = read_rows(args.rows)
    if not rows:
        sys.exit("campaign_table: no rows in " + ", ".join(args.rows))
    text = report(rows)
    print(text)
    if args.out:
        with open(args.out, "w") as out:
            out.write(text + "\n")


if __name__ == "__main__":
    main()

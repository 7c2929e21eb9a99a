#!/usr/bin/env python3
"""Parsing and reporting for run_bench.sh (middleware benchmark).

Subcommands:
  ddsperf-latency LOG SIZE        ddsperf ping output -> one RESULT line
  ddsperf-throughput LOG SIZE QOS ddsperf sub output  -> one RESULT line
  report RAW CSV MD               tagged RESULT lines -> CSV, markdown tables (also printed)
  compare RAW [RAW ...]           run-to-run spread of the ratios of several runs (markdown)

RESULT lines are `RESULT key=value ...`; run_bench.sh prefixes each with test, impl and pair.
Ratios are performance ratios (1.0 = parity, >= 0.9 is the goal): anchor latency / our
latency, and our throughput / anchor throughput.
"""

import csv
import re
import sys

GOAL = 0.9


def parse_result(line):
    """`RESULT a=1 b=x` -> {'a': '1', 'b': 'x'} (None if not a RESULT line)."""
    line = line.strip()
    if not line.startswith("RESULT"):
        return None
    fields = {}
    for token in line.split()[1:]:
        key, _, value = token.partition("=")
        fields[key] = value
    return fields


def result_line(fields):
    return "RESULT " + " ".join(f"{k}={v}" for k, v in fields.items())


# ddsperf ping prints per second (one-way = RTT/2):
# [pid] 2.000  host:pid size 1024 mean 11.5us min 5.1us 50% 12.5us 90% 14.9us 99% 20.0us max 421.8us cnt 42859
LAT_RE = re.compile(r"^\[\d+\]\s+([\d.]+)\s+\S+\s+size\s+(\d+)\s+mean\s+([\d.]+)(us|ms|s)\s+"
                    r"min\s+([\d.]+)(us|ms|s)\s+50%\s+([\d.]+)(us|ms|s)\s+90%\s+([\d.]+)(us|ms|s)\s+"
                    r"99%\s+([\d.]+)(us|ms|s)\s+max\s+([\d.]+)(us|ms|s)\s+cnt\s+(\d+)")
UNIT_US = {"us": 1.0, "ms": 1e3, "s": 1e6}


def ddsperf_latency(log, size):
    intervals = []
    with open(log, errors="replace") as f:
        for line in f:
            m = LAT_RE.match(line)
            if not m:
                continue
            g = m.groups()
            cnt = int(g[14])
            if cnt == 0:
                continue
            intervals.append({
                "t": float(g[0]),
                "mean": float(g[2]) * UNIT_US[g[3]],
                "min": float(g[4]) * UNIT_US[g[5]],
                "p50": float(g[6]) * UNIT_US[g[7]],
                "p90": float(g[8]) * UNIT_US[g[9]],
                "p99": float(g[10]) * UNIT_US[g[11]],
                "max": float(g[12]) * UNIT_US[g[13]],
                "cnt": cnt,
            })
    fields = {"tool": "ddsperf", "vendor": "cyclonedds", "role": "ping", "qos": "command",
              "size": str(size)}
    if not intervals:
        fields["status"] = "no_data"
        return result_line(fields)
    total = sum(i["cnt"] for i in intervals)
    # ddsperf reports per-second percentiles only: combine them weighted by count.
    wavg = lambda k: sum(i[k] * i["cnt"] for i in intervals) / total
    span = max(1.0, len(intervals))  # each interval is one second
    fields.update({
        "status": "ok", "count": str(total), "intervals": str(len(intervals)),
        "rtt_min_us": f"{2 * min(i['min'] for i in intervals):.3f}",
        "rtt_mean_us": f"{2 * wavg('mean'):.3f}",
        "rtt_median_us": f"{2 * wavg('p50'):.3f}",
        "rtt_p90_us": f"{2 * wavg('p90'):.3f}",
        "rtt_p99_us": f"{2 * wavg('p99'):.3f}",
        "rtt_max_us": f"{2 * max(i['max'] for i in intervals):.3f}",
        "oneway_median_us": f"{wavg('p50'):.3f}",
        "oneway_p90_us": f"{wavg('p90'):.3f}",
        "roundtrips_per_s": f"{total / span:.1f}",
    })
    return result_line(fields)


# ddsperf sub prints per second (cumulative total/lost, then this interval's delta/lost):
# [pid] 2.000  size 16384 total 187168 lost 8678 delta 114418 lost 4716 rate 114.42 kS/s ...
THR_RE = re.compile(r"^\[\d+\]\s+([\d.]+)\s+size\s+(\d+)\s+total\s+(\d+)\s+lost\s+(\d+)\s+"
                    r"delta\s+(\d+)\s+lost\s+(\d+)\s+rate")


def ddsperf_throughput(log, size, qos):
    lines = []
    with open(log, errors="replace") as f:
        for line in f:
            if ": gone" in line and lines:
                break  # the publisher left: later intervals are partial
            m = THR_RE.match(line)
            if m:
                t, _, total, lost, delta, dlost = m.groups()
                lines.append((float(t), int(total), int(lost), int(delta), int(dlost)))
    data = [l for l in lines if l[3] > 0]
    fields = {"tool": "ddsperf", "vendor": "cyclonedds", "role": "sub", "qos": qos,
              "size": str(size)}
    if not data:
        fields["status"] = "no_data"
        return result_line(fields)
    # Drop the first interval (discovery, ramp-up), as our sub drops its first sub_warmup_s;
    # intervals after the publisher left were cut off above.
    steady = data[1:] if len(data) >= 2 else data
    received = sum(l[3] for l in steady)
    lost = sum(l[4] for l in steady)
    window = steady[-1][0] - steady[0][0] + 1.0  # intervals are one second each
    rate = received / window
    fields.update({
        "status": "ok", "received": str(data[-1][1]), "counted": str(received),
        "lost": str(lost),
        "loss_pct": f"{100.0 * lost / (received + lost) if received + lost else 0:.2f}",
        "window_s": f"{window:.3f}", "msgs_per_s": f"{rate:.1f}",
        "mb_per_s": f"{rate * size / 1e6:.2f}",
    })
    return result_line(fields)


# ---------------------------------------------------------------------------------------
# Report

SIZE_NAMES = {64: "64 B", 1024: "1 KiB", 16384: "16 KiB", 262144: "256 KiB", 4194304: "4 MiB"}
PAIRS = ["cyclonedds->cyclonedds", "fastdds->fastdds", "fastdds->cyclonedds",
         "cyclonedds->fastdds"]
# Each mode of our layer and its like-for-like raw anchor: the executor hand-off against raw
# programs whose listener wakes an application thread, middleware-thread callbacks against
# raw programs answering inside the listener (and ddsperf, which does the same).
MODES = [("executor", "thread"), ("middleware", "listener")]
TABLES = [("latency", "command", "latency"), ("throughput", "command", "throughput `command`"),
          ("throughput", "sensor_data", "throughput `sensor_data`")]


def size_name(n):
    n = int(n)
    if n in SIZE_NAMES:
        return SIZE_NAMES[n]
    return f"{n} B"


def num(r, key):
    try:
        return float(r[key])
    except (KeyError, ValueError, TypeError):
        return None


def meets(value):
    """Judged on the two decimals printed, so a row never shows 0.90 and a ✗ together."""
    return value is not None and round(value, 2) >= GOAL


def ratio_text(value):
    if value is None:
        return "n/a"
    return f"{value:.2f}" + ("" if meets(value) else " ✗")


def fmt_us(v):
    if v is None:
        return "n/a"
    return f"{v:.1f}" if v < 1000 else f"{v:,.0f}"


def fmt_rate(v):
    return "n/a" if v is None else f"{v:,.0f}"


def ok(r):
    return r is not None and r.get("status") == "ok"


def dispatch_of(r):
    # Runs before the dispatch option existed: ours was always the executor, raw the listener.
    if "dispatch" in r and r["dispatch"] not in ("", "-"):
        return r["dispatch"]
    return "executor" if r.get("impl") == "ours" else "listener"


def find(rows, test, impl, pair, size, qos=None, dispatch=None):
    for r in rows:
        if (r.get("test") == test and r.get("impl") == impl and r.get("pair") == pair
                and r.get("size") == size and (qos is None or r.get("qos") == qos)
                and (dispatch is None or dispatch_of(r) == dispatch)):
            return r
    return None


def value_of(test, r):
    if not ok(r):
        return None
    return num(r, "oneway_median_us" if test == "latency" else "msgs_per_s")


def ratio(test, ours, anchor):
    """Performance ratio: anchor latency / ours, or ours throughput / anchor (1.0 = parity)."""
    o, a = value_of(test, ours), value_of(test, anchor)
    if o is None or a is None or o <= 0 or a <= 0:
        return None
    return a / o if test == "latency" else o / a


def ratios(rows, test, qos, modes=None):
    """{(mode, size, pair): ratio} for every row where ours and its anchor were measured."""
    out = {}
    sizes = sorted({r["size"] for r in rows if r.get("impl") == "ours"}, key=int)
    for mode, anchor in modes or MODES:
        for size in sizes:
            for pair in PAIRS:
                ours = find(rows, test, "ours", pair, size, qos, mode)
                raw = find(rows, test, "raw", pair, size, qos, anchor)
                if ours is None or raw is None:
                    continue
                out[(mode, size, pair)] = ratio(test, ours, raw)
    return out


def median(values):
    v = sorted(values)
    if not v:
        return None
    mid = len(v) // 2
    return v[mid] if len(v) % 2 else (v[mid - 1] + v[mid]) / 2


def latency_table(rows, sizes):
    out = ["| size | pair (ping->pong) | ours executor µs | p90 µs | raw thread µs | ratio | "
           "ours middleware µs | p90 µs | raw listener µs | ratio | ddsperf µs | ratio |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for size in sizes:
        for pair in PAIRS:
            cells = []
            any_ours = False
            for mode, anchor in MODES:
                ours = find(rows, "latency", "ours", pair, size, dispatch=mode)
                raw = find(rows, "latency", "raw", pair, size, dispatch=anchor)
                any_ours = any_ours or ours is not None
                if ours is None:
                    cells += ["-", "-"]
                else:
                    status = "" if ok(ours) else f" ({ours.get('status')})"
                    cells += [fmt_us(value_of("latency", ours)) + status,
                              fmt_us(num(ours, "oneway_p90_us") if ok(ours) else None)]
                if raw is None:
                    cells += ["-", "-"]
                else:
                    cells += [fmt_us(value_of("latency", raw)),
                              ratio_text(ratio("latency", ours, raw)) if ours else "-"]
            if not any_ours:
                continue
            dp = find(rows, "latency", "ddsperf", pair, size)
            mw = find(rows, "latency", "ours", pair, size, dispatch="middleware")
            if dp is None:
                cells += ["-", "-"]
            else:
                cells += [fmt_us(value_of("latency", dp)),
                          ratio_text(ratio("latency", mw, dp)) if mw else "-"]
            out.append(f"| {size_name(size)} | {pair} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def throughput_table(rows, sizes, qos):
    out = ["| size | pair (pub->sub) | ours executor msg/s | loss % | raw thread msg/s | loss % | "
           "ratio | ours middleware msg/s | loss % | raw listener msg/s | loss % | ratio | "
           "ddsperf msg/s | ratio |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def rate_loss(r):
        if r is None:
            return ["-", "-"]
        status = "" if ok(r) else f" ({r.get('status')})"
        loss = num(r, "loss_pct") if ok(r) else None
        return [fmt_rate(value_of("throughput", r)) + status,
                "n/a" if loss is None else f"{loss:.1f}"]

    for size in sizes:
        for pair in PAIRS:
            cells = []
            any_ours = False
            for mode, anchor in MODES:
                ours = find(rows, "throughput", "ours", pair, size, qos, mode)
                raw = find(rows, "throughput", "raw", pair, size, qos, anchor)
                any_ours = any_ours or ours is not None
                cells += rate_loss(ours) + rate_loss(raw)
                cells.append(ratio_text(ratio("throughput", ours, raw)) if ours and raw else "-")
            if not any_ours:
                continue
            dp = find(rows, "throughput", "ddsperf", pair, size, qos)
            mw = find(rows, "throughput", "ours", pair, size, qos, "middleware")
            if dp is None:
                cells += ["-", "-"]
            else:
                cells += [fmt_rate(value_of("throughput", dp)),
                          ratio_text(ratio("throughput", mw, dp)) if mw else "-"]
            out.append(f"| {size_name(size)} | {pair} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def short_row(size, pair):
    return f"{size_name(size)} {pair.replace('cyclonedds', 'cyc').replace('fastdds', 'fast')}"


# Not like for like, for comparison with earlier runs: before the middleware mode existed the
# page compared the executor mode with the raw listener anchor.
CROSS = ("executor", "listener")


def summary_table(rows):
    """How far from the goal, per table and mode: rows >= GOAL, the median ratio and the rows
    below the goal."""
    out = [f"| table | ours mode (anchor) | rows ≥ {GOAL} | median ratio | min–max | "
           f"rows below {GOAL} |",
           "|---|---|---:|---:|---|---|"]
    for test, qos, title in TABLES:
        for mode, anchor in MODES + [CROSS]:
            vals = ratios(rows, test, qos, [(mode, anchor)])
            if not vals:
                continue
            good = [v for v in vals.values() if v is not None]
            below = [f"{short_row(k[1], k[2])} ({'n/a' if v is None else f'{v:.2f}'})"
                     for k, v in vals.items() if not meets(v)]
            med = median(good)
            rng = f"{min(good):.2f}–{max(good):.2f}" if good else "n/a"
            label = f"{mode} (raw {anchor})" + (" *" if (mode, anchor) == CROSS else "")
            out.append(f"| {title} | {label} | {len(vals) - len(below)}/{len(vals)} | "
                       f"{'n/a' if med is None else f'{med:.2f}'} | {rng} | "
                       f"{', '.join(below) if below else '–'} |")
    out.append("")
    out.append("\\* not like for like (executor hand-off against listener dispatch): the "
               "comparison earlier runs reported.")
    return "\n".join(out)


CSV_FIELDS = ["test", "impl", "pair", "dispatch", "qos", "size", "status", "count",
              "rtt_median_us", "rtt_p90_us", "rtt_p99_us", "oneway_median_us", "oneway_p90_us",
              "roundtrips_per_s", "sent", "received", "counted", "lost", "loss_pct",
              "window_s", "msgs_per_s", "mb_per_s", "tool", "domain"]


def read_raw(raw):
    rows = []
    meta = {}
    with open(raw) as f:
        for line in f:
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition(":")
                meta[key.strip()] = value.strip()
                continue
            r = parse_result(line)
            if r is not None:
                rows.append(r)
    return rows, meta


def report(raw, csv_path, md_path):
    rows, meta = read_raw(raw)
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow(r)
    sizes = sorted({r["size"] for r in rows if r.get("impl") == "ours"}, key=int)
    md = []
    if meta:
        md.append("Run: " + "; ".join(f"{k}: {v}" for k, v in meta.items()))
        md.append("")
    md.append("Each mode of our layer beside its like-for-like raw anchor: executor (callbacks "
              "on the executor thread) vs raw thread (listener wakes an application thread), "
              "middleware (CallbackThread::MIDDLEWARE) vs raw listener (answers in the "
              "listener); ddsperf beside middleware. Ratio = anchor latency / ours, or ours "
              f"throughput / anchor (1.0 = parity; ✗ below {GOAL}); \"-\": not measured.")
    md.append("")
    if any(r.get("test") == "latency" for r in rows):
        md.append("### Round-trip latency (`command` profile: reliable, keep-last 10)")
        md.append("")
        md.append("One-way = RTT/2, medians over the measured round trips (ddsperf: "
                  "count-weighted mean of its per-second medians).")
        md.append("")
        md.append(latency_table(rows, sizes))
    for qos, title in (("command", "reliable, keep-last 10"),
                       ("sensor_data", "best effort, keep-last 5")):
        if not any(r.get("qos") == qos and r.get("test") == "throughput" for r in rows):
            continue
        md.append("")
        md.append(f"### Throughput, `{qos}` profile ({title}), publisher unthrottled")
        md.append("")
        md.append("Samples delivered per second to the subscriber's application in the steady "
                  "window; loss = sequence gaps.")
        md.append("")
        md.append(throughput_table(rows, sizes, qos))
    md.append("")
    md.append("### How far from the goal")
    md.append("")
    md.append(summary_table(rows))
    text = "\n".join(md) + "\n"
    with open(md_path, "w") as f:
        f.write(text)
    print(text)
    below = []
    for r in rows:
        if r.get("impl") == "ours" and not ok(r):
            below.append(f"{r.get('test')} {r.get('pair')} {dispatch_of(r)} {r.get('qos')} "
                         f"{r.get('size')}: {r.get('status')}")
    if below:
        print("Failed measurements:\n  " + "\n  ".join(below))


def compare(raws):
    """Run-to-run spread: the median ratio per table and mode in each run, and every row's
    ratio in each run side by side."""
    runs = []
    for raw in raws:
        rows, meta = read_raw(raw)
        runs.append((raw, meta, {(test, qos): ratios(rows, test, qos)
                                 for test, qos, _ in TABLES}))
    out = ["| table | ours mode (anchor) | " + " | ".join(
               f"run {i + 1}: median (rows ≥ {GOAL})" for i in range(len(runs))) + " |",
           "|---|---|" + "---:|" * len(runs)]
    for test, qos, title in TABLES:
        for mode, anchor in MODES:
            cells = []
            for _, _, rs in runs:
                vals = [v for k, v in rs[(test, qos)].items() if k[0] == mode and v is not None]
                met = sum(1 for v in vals if meets(v))
                med = median(vals)
                cells.append("n/a" if med is None else f"{med:.2f} ({met}/{len(vals)})")
            out.append(f"| {title} | {mode} (raw {anchor}) | " + " | ".join(cells) + " |")
    out.append("")
    for i, (raw, meta, _) in enumerate(runs):
        out.append(f"run {i + 1}: {raw}; load average at start: "
                   f"{meta.get('load average at start', '?')}; "
                   f"{meta.get('elapsed', '').strip() or '?'}")
    out.append("")
    out.append("| table | mode | size | pair | " + " | ".join(
        f"run {i + 1}" for i in range(len(runs))) + " | spread |")
    out.append("|---|---|---|---|" + "---:|" * (len(runs) + 1))
    for test, qos, title in TABLES:
        keys = []
        for _, _, rs in runs:
            for k in rs[(test, qos)]:
                if k not in keys:
                    keys.append(k)
        for k in keys:
            vals = [rs[(test, qos)].get(k) for _, _, rs in runs]
            good = [v for v in vals if v is not None]
            spread = f"{max(good) - min(good):.2f}" if len(good) > 1 else "-"
            out.append(f"| {title} | {k[0]} | {size_name(k[1])} | {k[2]} | " + " | ".join(
                ratio_text(v) for v in vals) + f" | {spread} |")
    print("\n".join(out))


def main(argv):
    if len(argv) >= 3 and argv[0] == "ddsperf-latency":
        print(ddsperf_latency(argv[1], int(argv[2])))
    elif len(argv) >= 4 and argv[0] == "ddsperf-throughput":
        print(ddsperf_throughput(argv[1], int(argv[2]), argv[3]))
    elif len(argv) >= 4 and argv[0] == "report":
        report(argv[1], argv[2], argv[3])
    elif len(argv) >= 2 and argv[0] == "compare":
        compare(argv[1:])
    else:
        sys.stderr.write(__doc__)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

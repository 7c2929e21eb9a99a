#!/usr/bin/env bash
# Middleware benchmark: round-trip latency and throughput through our layer (auv_dds_bench) on
# each vendor and across vendors, each figure printed beside anchors measured in the same run:
# ddsperf (Cyclone's own tool), raw_cyclonedds_bench and raw_fastdds_bench (the vendors' plain
# APIs on our message type, QoS and transport). Both dispatch modes of our layer, each beside
# its like-for-like anchor: executor (default) vs raw thread, middleware vs raw listener.
# All traffic stays on loopback: our layer and the raw programs bind 127.0.0.1/lo by default,
# ddsperf gets cyclonedds_loopback.xml. To prove it, wrap the run:
#   ../shared/tools/no-external-traffic interfaces/bench/run_bench.sh
#
# Usage: run_bench.sh [--full] [--sizes "64 1k 16k 256k 4M"] [--only latency|throughput]
#                     [--modes both|executor|middleware] [--build-dir DIR] [--out DIR]
#                     [--skip-build] [--no-pin]
# Default: a short run of both modes (about 11 minutes on 2 cores; one mode about 6);
# --full: 10x the samples and durations.
# The two processes of a pair are pinned to CPUs 0 and 1 (taskset) unless --no-pin: on a
# 2-core machine this cuts the run-to-run spread of the throughput figures from about +-50 %
# to about +-10 %.
# Results: <workspace>/bench_results/dds_bench_<stamp>.{raw,csv,md} plus logs/; the markdown
# tables are printed at the end with the ratio ours/anchor per row.
set -uo pipefail

BENCH_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
WS="$(cd "$BENCH_DIR/../.." && pwd)"
BUILD_DIR="${TMPDIR:-/tmp}/auv_bench_build"
OUT_DIR="$WS/bench_results"
FULL=0
SKIP_BUILD=0
PIN=1
ONLY=""
SIZES_ARG="64 1k 16k 256k 4M"
MODES="both"

usage() { sed -n '2,20p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }

while [ $# -gt 0 ]; do
  case "$1" in
    --full) FULL=1 ;;
    --sizes) SIZES_ARG="$2"; shift ;;
    --only) ONLY="$2"; shift ;;
    --modes) MODES="$2"; shift ;;
    --build-dir) BUILD_DIR="$2"; shift ;;
    --out) OUT_DIR="$2"; shift ;;
    --skip-build) SKIP_BUILD=1 ;;
    --no-pin) PIN=0 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run_bench: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
  shift
done
case "$ONLY" in ""|latency|throughput) ;; *) echo "run_bench: --only '$ONLY': latency or throughput" >&2; exit 2 ;; esac
case "$MODES" in both|executor|middleware) ;; *) echo "run_bench: --modes '$MODES': both, executor or middleware" >&2; exit 2 ;; esac

to_bytes() {  # 64 | 1k | 16KiB | 4M -> bytes
  local s="$1" n unit
  n="${s%%[!0-9]*}"; unit="${s#"$n"}"
  case "$unit" in
    ""|B) echo "$n" ;;
    k|K|KiB) echo $((n * 1024)) ;;
    M|MiB) echo $((n * 1024 * 1024)) ;;
    *) echo "run_bench: size '$s': use a number with k or M" >&2; exit 2 ;;
  esac
}
SIZES=()
for s in $SIZES_ARG; do SIZES+=("$(to_bytes "$s")") || exit 2; done

# Iterations: fewer at big sizes. Ping: measured round trips (capped at PING_CAP seconds of
# measuring); pub and ddsperf: seconds.
if [ $FULL -eq 1 ]; then
  PING_CAP=20; PUB_SECS=10; DDSPERF_PING_SECS=15; PROC_TIMEOUT=300; SCALE=10
else
  PING_CAP=3; PUB_SECS=2; DDSPERF_PING_SECS=3; PROC_TIMEOUT=60; SCALE=1
fi
ping_count() {
  local base
  case "$1" in
    64|1024) base=2000 ;;
    16384) base=1000 ;;
    262144) base=200 ;;
    *) base=100 ;;
  esac
  echo $((base * SCALE))
}

# Server (pong/sub) on CPU 1, client (ping/pub) on CPU 0.
PIN_SERVER=(); PIN_CLIENT=()
if [ $PIN -eq 1 ] && [ "$(nproc)" -ge 2 ] && command -v taskset >/dev/null; then
  PIN_SERVER=(taskset -c 1); PIN_CLIENT=(taskset -c 0)
else
  PIN=0
fi

# Our layer and the raw programs use their built-in loopback settings: no user configuration.
unset CYCLONEDDS_URI FASTRTPS_DEFAULT_PROFILES_FILE AUV_DDS AUV_DOMAIN_ID
DDSPERF_URI="file://$BENCH_DIR/cyclonedds_loopback.xml"

# ---------------------------------------------------------------------------------------
# Build (in a scratch directory, against the installed workspace).
if [ ! -f "$WS/install/share/auv_interfaces/cmake/auv_interfacesConfig.cmake" ]; then
  echo "run_bench: $WS/install has no auv_interfaces; run ./scripts/build.sh --packages-up-to auv_interfaces" >&2
  exit 1
fi
if [ $SKIP_BUILD -eq 0 ]; then
  echo "run_bench: building in $BUILD_DIR" >&2
  cmake -S "$BENCH_DIR" -B "$BUILD_DIR" -DCMAKE_PREFIX_PATH="$WS/install" >"${BUILD_DIR}.configure.log" 2>&1 \
    || { cat "${BUILD_DIR}.configure.log" >&2; exit 1; }
  cmake --build "$BUILD_DIR" -j "$(nproc)" >"${BUILD_DIR}.build.log" 2>&1 \
    || { tail -40 "${BUILD_DIR}.build.log" >&2; exit 1; }
fi
OURS="$BUILD_DIR/auv_dds_bench"
RAW_FASTDDS="$BUILD_DIR/raw_fastdds_bench"
RAW_CYCLONE="$BUILD_DIR/raw_cyclonedds_bench"
for b in "$OURS" "$RAW_FASTDDS" "$RAW_CYCLONE"; do
  [ -x "$b" ] || { echo "run_bench: $b missing (build failed?)" >&2; exit 1; }
done
HAVE_DDSPERF=1
command -v ddsperf >/dev/null || { HAVE_DDSPERF=0; echo "run_bench: ddsperf not found: no ddsperf rows" >&2; }

# ---------------------------------------------------------------------------------------
# Output.
STAMP="$(date +%Y%m%d_%H%M%S)"
mkdir -p "$OUT_DIR/logs_$STAMP"
LOG_DIR="$OUT_DIR/logs_$STAMP"
RAW="$OUT_DIR/dds_bench_$STAMP.raw"
CSV="$OUT_DIR/dds_bench_$STAMP.csv"
MD="$OUT_DIR/dds_bench_$STAMP.md"
{
  echo "# date: $(date -Iseconds)"
  echo "# host: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), Linux $(uname -r)"
  echo "# versions: Fast DDS $(dpkg-query -W -f='${Version}' libfastrtps2.9 2>/dev/null || echo '?'), Cyclone DDS $(dpkg-query -W -f='${Version}' libddsc0debian 2>/dev/null || echo '?')"
  echo "# workspace commit: $(git -C "$WS" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$WS" diff --quiet 2>/dev/null || echo ' (modified)')"
  echo "# mode: $([ $FULL -eq 1 ] && echo full || echo default) (ping cap ${PING_CAP} s, pub ${PUB_SECS} s, ddsperf ping ${DDSPERF_PING_SECS} s), $([ $PIN -eq 1 ] && echo 'pinned: client CPU 0, server CPU 1' || echo 'not pinned'), dispatch modes: $MODES"
  echo "# load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
} >"$RAW"

START=$(date +%s)
RUN=0
record() {  # record <tags> <RESULT line or empty> <fallback fields>
  local tags="$1" line="$2" fallback="$3"
  if [ -n "$line" ]; then
    echo "RESULT $tags ${line#RESULT }" >>"$RAW"
  else
    echo "RESULT $tags $fallback" >>"$RAW"
  fi
  local summary
  summary="$(tail -1 "$RAW" | tr ' ' '\n' | grep -E '^(status|oneway_median_us|msgs_per_s|mb_per_s|loss_pct)=' | tr '\n' ' ')"
  echo "[$(($(date +%s) - START)) s] $tags: $summary" >&2
}

# run_pair TEST IMPL PAIR DISPATCH QOS SIZE; commands in the arrays SERVER and CLIENT.
# Latency: the server is the pong, the client the ping (which reports). Throughput: the server
# is the sub (which reports), the client the pub.
run_pair() {
  local test="$1" impl="$2" pair="$3" dispatch="$4" qos="$5" size="$6"
  RUN=$((RUN + 1))
  local log="$LOG_DIR/$(printf %03d $RUN)_${test}_${impl}_${pair/->/_to_}_${dispatch}_${qos}_${size}"
  "${PIN_SERVER[@]}" timeout "$PROC_TIMEOUT" "${SERVER[@]}" >"$log.server.out" 2>"$log.server.err" &
  local server_pid=$!
  "${PIN_CLIENT[@]}" timeout "$PROC_TIMEOUT" "${CLIENT[@]}" >"$log.client.out" 2>"$log.client.err"
  local client_rc=$?
  wait "$server_pid"
  local server_rc=$?
  local tags="test=$test impl=$impl pair=$pair dispatch=$dispatch"
  local line
  if [ "$test" = latency ]; then
    line="$(grep -m1 '^RESULT' "$log.client.out")"
  else
    line="$(grep -m1 '^RESULT' "$log.server.out")"
    local sent
    sent="$(grep -m1 '^RESULT' "$log.client.out" | tr ' ' '\n' | grep -E '^sent=' || true)"
    [ -n "$line" ] && line="$line ${sent}"
  fi
  record "$tags" "$line" "qos=$qos size=$size status=failed_rc${client_rc}_${server_rc}"
}

run_ddsperf_latency() {  # SIZE DOMAIN
  local size="$1" domain="$2"
  RUN=$((RUN + 1))
  local log="$LOG_DIR/$(printf %03d $RUN)_latency_ddsperf_${size}"
  CYCLONEDDS_URI="$DDSPERF_URI" "${PIN_SERVER[@]}" timeout "$PROC_TIMEOUT" \
    ddsperf -i "$domain" -D $((DDSPERF_PING_SECS + 2)) pong >"$log.server.out" 2>&1 &
  local server_pid=$!
  CYCLONEDDS_URI="$DDSPERF_URI" "${PIN_CLIENT[@]}" timeout "$PROC_TIMEOUT" \
    ddsperf -i "$domain" -D "$DDSPERF_PING_SECS" ping size "$size" >"$log.client.out" 2>&1
  kill "$server_pid" 2>/dev/null; wait "$server_pid" 2>/dev/null
  record "test=latency impl=ddsperf pair=cyclonedds->cyclonedds dispatch=listener" \
    "$(python3 "$BENCH_DIR/bench_report.py" ddsperf-latency "$log.client.out" "$size")" ""
}

run_ddsperf_throughput() {  # SIZE DOMAIN QOS
  local size="$1" domain="$2" qos="$3" flags
  RUN=$((RUN + 1))
  local log="$LOG_DIR/$(printf %03d $RUN)_throughput_ddsperf_${qos}_${size}"
  if [ "$qos" = command ]; then flags=(-k 10); else flags=(-u -k 5); fi
  # One second more publishing than ours: ddsperf reports whole seconds and the first one
  # is dropped as partial (ramp-up).
  local pub_secs=$((PUB_SECS + 1))
  CYCLONEDDS_URI="$DDSPERF_URI" "${PIN_SERVER[@]}" timeout "$PROC_TIMEOUT" \
    ddsperf -i "$domain" -D $((pub_secs + 10)) "${flags[@]}" sub >"$log.server.out" 2>&1 &
  local server_pid=$!
  sleep 0.2
  CYCLONEDDS_URI="$DDSPERF_URI" "${PIN_CLIENT[@]}" timeout "$PROC_TIMEOUT" \
    ddsperf -i "$domain" -D "$pub_secs" "${flags[@]}" pub size "$size" >"$log.client.out" 2>&1
  sleep 1.2  # the sub prints its last interval and notices the publisher leave
  kill -TERM "$server_pid" 2>/dev/null
  wait "$server_pid" 2>/dev/null
  record "test=throughput impl=ddsperf pair=cyclonedds->cyclonedds dispatch=listener" \
    "$(python3 "$BENCH_DIR/bench_report.py" ddsperf-throughput "$log.server.out" "$size" "$qos")" ""
}

bin_of() {  # IMPL VENDOR DISPATCH -> command words
  if [ "$1" = ours ]; then echo "$OURS --vendor $2 --dispatch $3"
  elif [ "$2" = fastdds ]; then echo "$RAW_FASTDDS --dispatch $3"
  else echo "$RAW_CYCLONE --dispatch $3"; fi
}

# ---------------------------------------------------------------------------------------
# Every vendor pair in both modes of our layer, each next to its like-for-like anchor so the
# two are measured seconds apart: ours executor / raw thread, ours middleware / raw listener.
PAIRS=("cyclonedds cyclonedds" "fastdds fastdds" "fastdds cyclonedds" "cyclonedds fastdds")
CONFIGS=()  # impl client-vendor server-vendor dispatch
for p in "${PAIRS[@]}"; do
  if [ "$MODES" != middleware ]; then CONFIGS+=("ours $p executor" "raw $p thread"); fi
  if [ "$MODES" != executor ]; then CONFIGS+=("ours $p middleware" "raw $p listener"); fi
done
# ddsperf answers in its listener: it belongs to the middleware comparison.
RUN_DDSPERF=$HAVE_DDSPERF
[ "$MODES" = executor ] && RUN_DDSPERF=0

# Pairs run strictly one after another (both processes have exited before the next starts);
# within one size each pair still gets its own domain: latency 200-216, throughput 212-228.

# Latency: command profile (reliable).
if [ "$ONLY" != throughput ]; then
  for size in "${SIZES[@]}"; do
    count=$(ping_count "$size")
    warmup=$((count / 10 > 5 ? count / 10 : 5))
    i=0
    for c in "${CONFIGS[@]}"; do
      read -r impl a b dispatch <<<"$c"
      domain=$((200 + i)); i=$((i + 1))
      common=(--qos command --size "$size" --domain "$domain" --timeout $((PROC_TIMEOUT - 5)))
      read -r -a SERVER <<<"$(bin_of "$impl" "$b" "$dispatch")"
      SERVER+=(--role pong "${common[@]}")
      read -r -a CLIENT <<<"$(bin_of "$impl" "$a" "$dispatch")"
      CLIENT+=(--role ping "${common[@]}" --count "$count" --warmup "$warmup"
               --duration "$PING_CAP")
      run_pair latency "$impl" "$a->$b" "$dispatch" command "$size"
    done
    [ $RUN_DDSPERF -eq 1 ] && run_ddsperf_latency "$size" 216
  done
fi

# Throughput: command (reliable) and sensor_data (best effort), publisher unthrottled.
if [ "$ONLY" != latency ]; then
  for size in "${SIZES[@]}"; do
    for qos in command sensor_data; do
      i=0
      for c in "${CONFIGS[@]}"; do
        read -r impl a b dispatch <<<"$c"
        domain=$((212 + i)); i=$((i + 1))
        common=(--qos "$qos" --size "$size" --domain "$domain" --timeout $((PROC_TIMEOUT - 5)))
        read -r -a SERVER <<<"$(bin_of "$impl" "$b" "$dispatch")"
        SERVER+=(--role sub "${common[@]}")
        read -r -a CLIENT <<<"$(bin_of "$impl" "$a" "$dispatch")"
        CLIENT+=(--role pub "${common[@]}" --duration "$PUB_SECS")
        run_pair throughput "$impl" "$a->$b" "$dispatch" "$qos" "$size"
      done
      [ $RUN_DDSPERF -eq 1 ] && run_ddsperf_throughput "$size" 228 "$qos"
    done
  done
fi

echo "# elapsed: $(($(date +%s) - START)) s; load average at end: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$RAW"
python3 "$BENCH_DIR/bench_report.py" report "$RAW" "$CSV" "$MD"
echo "run_bench: $(($(date +%s) - START)) s; results in $CSV and $MD (raw: $RAW, logs: $LOG_DIR)" >&2

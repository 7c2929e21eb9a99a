#!/usr/bin/env bash
# Runs every fuzz harness with libFuzzer for a bounded time over its corpus (docs/reliability.md,
# "Fuzzing"). The harnesses are built by the sanitizer build (scripts/sanitize.sh, clang,
# ASan + UBSan, -DAUV_FUZZ=ON) into install-asan/lib/auv_fuzz.
#
#   scripts/fuzz.sh [--seconds N] [--runs N] [--only NAME[,NAME...]] [--no-build]
#
#   --seconds N   per harness (default 30; a nightly run gives e.g. 3600)
#   --runs N      per harness, stop after N executions if that comes first (default: no limit)
#   --only        these harnesses only (names: install-asan/lib/auv_fuzz/fuzz_<name>)
#   --no-build    use install-asan as it is
#
# Each harness's corpus lives in fuzz-corpus/<name>/ and grows across runs: seeded with the
# installed seeds (project files), the harness's own seeds (the project's writers) and the
# regressions. A crash, leak, sanitizer report or timeout leaves the input in
# fuzz-crashes/<name>/ and fails the script; copy it into the package's
# fuzz/regressions/<name>/ once fixed, so every build replays it. Figures per harness go to
# fuzz-results.tsv.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=30
runs=-1
only=""
build=true
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="${2:?--seconds needs a number}"; shift ;;
    --runs) runs="${2:?--runs needs a number}"; shift ;;
    --only) only="${2:?--only needs names}"; shift ;;
    --no-build) build=false ;;
    *) echo "fuzz: unknown argument '$1' (--seconds N, --runs N, --only NAMES, --no-build)" >&2; exit 2 ;;
  esac
  shift
done
[[ "$seconds" =~ ^[0-9]+$ ]] || { echo "fuzz: --seconds '$seconds' is not a whole number" >&2; exit 2; }
[[ "$runs" =~ ^(-1|[0-9]+)$ ]] || { echo "fuzz: --runs '$runs' is not a whole number" >&2; exit 2; }
$build && ./scripts/sanitize.sh --build-only
fuzzers=install-asan/lib/auv_fuzz
[ -d "$fuzzers" ] || { echo "fuzz: no $fuzzers (run without --no-build)" >&2; exit 1; }
set +u; source install-asan/setup.bash; set -u
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export LSAN_OPTIONS="suppressions=$PWD/scripts/sanitizer-suppressions/lsan.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

names=()
for binary in "$fuzzers"/fuzz_*; do
  name=$(basename "$binary"); name=${name#fuzz_}
  [[ "$name" == *_replay ]] && continue
  if [ -n "$only" ] && [[ ",$only," != *",$name,"* ]]; then continue; fi
  names+=("$name")
done
[ ${#names[@]} -gt 0 ] || { echo "fuzz: no harness matches '${only}' in $fuzzers" >&2; exit 1; }

results=fuzz-results.tsv
[ -f "$results" ] || printf "time\tharness\tseconds\texecs\texecs_per_s\tcoverage\tcorpus\tresult\n" > "$results"
failed=()
for name in "${names[@]}"; do
  corpus="fuzz-corpus/$name" crashes="fuzz-crashes/$name"
  mkdir -p "$corpus" "$crashes"
  share="install-asan/share/auv_fuzz/$name"
  for part in seeds regressions; do
    [ -d "$share/$part" ] && cp -n "$share/$part"/* "$corpus"/ 2>/dev/null || true
  done
  "$fuzzers/fuzz_${name}_replay" --write-seeds "$corpus" >/dev/null
  log="fuzz-crashes/$name.log"
  status=0
  started=$SECONDS
  # -timeout: an input the normal build reads in 0.2 s (a parameter file whose aliases stand
  # for 18 000 parameters) takes ~25 s with ASan and the coverage instrumentation.
  "$fuzzers/fuzz_$name" -max_total_time="$seconds" -runs="$runs" -timeout=60 -rss_limit_mb=3072 \
    -print_final_stats=1 -artifact_prefix="$crashes/" "$corpus" >"$log" 2>&1 || status=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  # -a: a parser's own messages may put binary bytes in the log (OctoMap prints what it read).
  coverage=$(grep -ao 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  size=$(find "$corpus" -type f | wc -l)
  result=ok
  if [ $status -ne 0 ]; then result="FAILED (exit $status, $log)"; failed+=("$name"); fi
  printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$(date -u +%FT%TZ)" "$name" "$((SECONDS - started))" "${execs:-0}" \
    "${rate:-0}" "${coverage:-0}" "$size" "$result" >> "$results"
  printf "fuzz: %-18s %8s execs %6s/s  cov %6s  corpus %5s  %s\n" "$name" "${execs:-0}" \
    "${rate:-0}" "${coverage:-0}" "$size" "$result"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]} (inputs in fuzz-crashes/, logs beside them)" >&2
  exit 1
fi
echo "fuzz: ${#names[@]} harnesses, at most ${seconds} s each, no failure (figures in $results)"

#!/usr/bin/env bash
# auv view on a large textured model in headless Chromium (software GL): time to first frame
# and frames per second at the default level of detail ("auto" at the fitted view) and at every
# level, beside the same page with nothing drawn (the anchor), in one run (bench/README.md).
#
#   components/view/bench/run_view_bench.sh [--survey DIR] [--triangles N] [--size WxH]
#                                           [--seconds S] [--results FILE]
#
# Without --survey: auv_runs/survey-canyon when its textured/model.obj exists, else a generated
# terrain of N (default 1500000) triangles with a 2048² texture. Needs the workspace built and
# installed (install/), js/node_modules and /usr/bin/chromium (scripts/install-deps.sh).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
survey="" triangles=1500000 size=1024x768 seconds=5
results="$root/bench_results/view_bench.json"
while [ $# -gt 0 ]; do
  case "$1" in
    --survey) survey="$2"; shift 2 ;;
    --triangles) triangles="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --results) results="$2"; shift 2 ;;
    *) echo "run_view_bench.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
set +u; source "$root/install/setup.bash"; set -u
work="$(mktemp -d /tmp/auv_view_bench.XXXXXX)"
view_pid=""
cleanup() { [ -n "$view_pid" ] && kill "$view_pid" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT
if [ -z "$survey" ]; then
  if [ -f "$root/auv_runs/survey-canyon/textured/model.obj" ]; then
    survey="$root/auv_runs/survey-canyon"
  else
    survey="$work/terrain"
    "$root/install/lib/auv_view/view_bench_model" "$survey" "$triangles" >/dev/null
  fi
fi
"$root/install/bin/auv-view" "$survey" --port 0 >"$work/view.out" 2>"$work/view.err" &
view_pid=$!
for _ in $(seq 600); do grep -q "open http" "$work/view.out" 2>/dev/null && break; sleep 0.5; done
url="$(grep -o 'http://[^ ]*' "$work/view.out")"
prepared_ms="$(grep -o 'prepared in [0-9]*' "$work/view.out" | grep -o '[0-9]*$')"
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
node "$here/../test/js/view_check.mjs" "$url" "${AUV_VIEW_CHROMIUM:-/usr/bin/chromium}" \
  --benchmark "$seconds" --all-levels --zoom 8 --size "$size" >"$work/check.json"
load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
mkdir -p "$(dirname "$results")"
python3 - "$work/check.json" "$results" "$survey" "$prepared_ms" "$size" "$load_before" \
  "$load_after" "$(git -C "$root" rev-parse --short HEAD)" <<'PY'
import json, sys
check, out, survey, prepared, size, before, after, commit = sys.argv[1:]
r = json.load(open(check))
v = r.get("view", {})
res = {
    "survey": survey, "commit": commit, "viewport": size,
    "load_average_before": before, "load_average_after": after,
    "server_prepare_ms": int(prepared),
    "page_ready_ms": r.get("readyMs"),
    "first_frame_ms": v.get("firstFrameMs"),
    "default_level_on_screen_ms": v.get("defaultLevelMs"),
    "default_level": r.get("defaultLevel"),
    "default_triangles": v.get("counts", {}).get("model"),
    "fps_default_level": r.get("fps"), "fps_empty_anchor": r.get("fpsEmpty"),
    "fps_default_level_rounds": r.get("fpsRounds"), "fps_empty_anchor_rounds": r.get("fpsEmptyRounds"),
    "levels": r.get("levels"),
    "zoomed_8x": {"level": r.get("levelAfterZoom"), "level_triangles": r.get("trianglesAfterZoom"),
                  "fps": r.get("fpsZoomed"), "fps_moving_half_resolution": r.get("fpsZoomedMoving")},
    "errors": r.get("errors"),
}
json.dump(res, open(out, "w"), indent=2)
print(json.dumps(res, indent=2))
PY

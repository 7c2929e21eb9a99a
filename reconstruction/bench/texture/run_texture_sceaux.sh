#!/usr/bin/env bash
# Sceaux castle textured model (bench/texture/README.md): the survey up to the dense cloud as
# bench/dense/run_dense_sceaux.sh makes it (COLMAP sparse model of the 11 photos + `auv recon
# dense`, cached in the work folder), then `auv recon mesh` and `auv recon texture`, then
# render_model at every photo's pose and turned about the castle. Writes
# bench_results/texture_sceaux_<time>.md, ..._registered.png (photo | render) and
# ..._oblique.png (photo | novel view).
#
#   reconstruction/bench/texture/run_texture_sceaux.sh [--work DIR] [--max-image-size PX]
#       [--yaw-deg D] [--scale F]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../../.." && pwd)"
work="${TMPDIR:-/tmp}/auv_dense_sceaux"  # shared with run_dense_sceaux.sh: reuses its cache
size=1000
yaw=35
scale=0.5
while [[ $# -gt 0 ]]; do
  case "$1" in
    --work) work="$2"; shift 2 ;;
    --max-image-size) size="$2"; shift 2 ;;
    --yaw-deg) yaw="$2"; shift 2 ;;
    --scale) scale="$2"; shift 2 ;;
    *) echo "usage: $0 [--work DIR] [--max-image-size PX] [--yaw-deg D] [--scale F]" >&2; exit 2 ;;
  esac
done
# The workspace's installed tools (./scripts/build.sh), never a developer's build folder.
if [[ -f "$repo/install/setup.bash" ]]; then set +u; source "$repo/install/setup.bash"; set -u; fi
tool="$repo/install/bin/auv-recon"
render="$repo/install/lib/auv_reconstruction/render_model"
[[ -x "$tool" && -x "$render" ]] || { echo "$0: $tool or $render not found: run ./scripts/build.sh first" >&2; exit 1; }

# Sparse model and dense cloud: run_dense_sceaux.sh's (it caches the COLMAP model in --work);
# run again only when the work folder has no fused cloud yet.
if [[ ! -f "$work/dense/fused.ply" ]]; then
  "$repo/reconstruction/bench/dense/run_dense_sceaux.sh" --work "$work" --max-image-size "$size"
fi

stamp="$(date +%Y%m%d_%H%M%S)"
results="$repo/bench_results"
mkdir -p "$results"
log="$results/texture_sceaux_$stamp.md"
timed() {  # timed <name> <command...>: wall/CPU/peak memory of one stage into $work/<name>_time.txt
  local name="$1"; shift
  /usr/bin/time -v "$@" 2> >(tee "$work/${name}_time.txt" >&2) | tee "$work/$name.txt"
}
timed mesh "$tool" mesh "$work"
timed texture "$tool" texture "$work"
out="$work/render_$stamp"
"$render" --survey "$work" --out "$out" --yaw-deg "$yaw" --scale "$scale" | tee "$work/render.txt"

# One registered view beside its photo and one turned view: 100_7105 faces the castle.
cp "$out/100_7105.png" "$results/texture_sceaux_${stamp}_registered.png"
cp "$out/100_7105_yaw${yaw}.png" "$results/texture_sceaux_${stamp}_oblique.png"
stats() { grep -E "Elapsed|User time|System time|Maximum resident" "$1" | sed 's/^\s*/    /'; }
section() {
  python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['stages'][sys.argv[2]]; r.pop('options',None); print(json.dumps(r, indent=1))" \
    "$work/report.json" "$1"
}
{
  echo "# Sceaux castle textured model, $stamp"
  echo
  echo "11 photos 2832x2128; dense depth maps at max_image_size $size; mesh and texture with the"
  echo "default options; renderings at $scale x the photos' resolution. 2-core machine shared with"
  echo "other jobs (times noisy)."
  echo
  echo "## auv recon mesh"
  echo
  stats "$work/mesh_time.txt"
  echo
  echo '```'
  section mesh
  echo '```'
  echo
  echo "## auv recon texture"
  echo
  stats "$work/texture_time.txt"
  echo
  echo '```'
  section texture
  echo '```'
  echo
  echo "## render_model (PSNR of the model rendered at each photo's pose, over covered pixels)"
  echo
  cat "$out/render_model.md"
  echo
  echo "Pictures: texture_sceaux_${stamp}_registered.png (100_7105: photo | render),"
  echo "texture_sceaux_${stamp}_oblique.png (100_7105 turned by $yaw deg: photo | novel view);"
  echo "every view in $out."
} > "$log"
echo "written $log"

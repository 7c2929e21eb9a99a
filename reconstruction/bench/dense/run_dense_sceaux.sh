#!/usr/bin/env bash
# Sceaux castle dense cloud (bench/dense/README.md): a COLMAP sparse model of the 11 photos
# (cached in the work folder: ~3 min on 2 cores), `auv recon dense` at reduced resolution, and
# two renderings of the cloud to look at. Writes bench_results/dense_sceaux_<time>.{md,png}.
#
#   reconstruction/bench/dense/run_dense_sceaux.sh [--work DIR] [--max-image-size PX]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../../.." && pwd)"
data="$repo/../shared/data/sceaux_castle/images"
work="${TMPDIR:-/tmp}/auv_dense_sceaux"
size=1000
while [[ $# -gt 0 ]]; do
  case "$1" in
    --work) work="$2"; shift 2 ;;
    --max-image-size) size="$2"; shift 2 ;;
    *) echo "usage: $0 [--work DIR] [--max-image-size PX]" >&2; exit 2 ;;
  esac
done
# The workspace's installed tools (./scripts/build.sh), never a developer's build folder.
if [[ -f "$repo/install/setup.bash" ]]; then set +u; source "$repo/install/setup.bash"; set -u; fi
tool="$repo/install/bin/auv-recon"
bench="$repo/install/lib/auv_reconstruction/dense_bench"
[[ -x "$tool" && -x "$bench" ]] || { echo "$0: $tool or $bench not found: run ./scripts/build.sh first" >&2; exit 1; }
[[ -d "$data" ]] || { echo "$0: $data not found" >&2; exit 1; }
read -r fx _ cx < <(sed -n 1p "$data/K.txt")
read -r _ fy cy < <(sed -n 2p "$data/K.txt")

mkdir -p "$work"
if [[ ! -f "$work/sparse/images.txt" ]]; then
  echo "COLMAP sparse model (cached in $work)..."
  rm -rf "$work/db.db" "$work/colmap" && mkdir -p "$work/colmap" "$work/sparse"
  colmap feature_extractor --database_path "$work/db.db" --image_path "$data" \
    --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1 \
    --ImageReader.camera_params "$fx,$fy,$cx,$cy" --SiftExtraction.use_gpu 0 > "$work/colmap.log" 2>&1
  colmap exhaustive_matcher --database_path "$work/db.db" --SiftMatching.use_gpu 0 >> "$work/colmap.log" 2>&1
  colmap mapper --database_path "$work/db.db" --image_path "$data" --output_path "$work/colmap" \
    >> "$work/colmap.log" 2>&1
  colmap model_converter --input_path "$work/colmap/0" --output_path "$work/sparse" --output_type TXT \
    >> "$work/colmap.log" 2>&1
fi
ln -sfn "$data" "$work/corrected"  # the photos are the "corrected" images (no distortion model)

stamp="$(date +%Y%m%d_%H%M%S)"
results="$repo/bench_results"
mkdir -p "$results"
log="$results/dense_sceaux_$stamp.md"
start=$(date +%s.%N)
/usr/bin/time -v "$tool" dense "$work" --max-image-size "$size" 2> "$work/time.txt" | tee "$work/dense.txt"
end=$(date +%s.%N)
"$bench" render "$work/dense/fused.ply" "$work/sparse" 100_7105.JPG "$results/dense_sceaux_${stamp}_front.png" --scale 0.3
"$bench" render "$work/dense/fused.ply" "$work/sparse" 100_7105.JPG "$results/dense_sceaux_${stamp}_oblique.png" --scale 0.3 --yaw 50 --back 3
{
  echo "# Sceaux castle dense cloud, $stamp"
  echo
  echo "11 photos 2832x2128, depth maps at max_image_size $size; 2-core machine shared with other jobs (times noisy)."
  echo
  cat "$work/dense.txt"
  echo
  grep -E "Elapsed|User time|System time|Maximum resident" "$work/time.txt" | sed 's/^\s*/    /'
  echo
  echo "report.json dense section:"
  echo
  echo '```'
  python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['stages']['dense']; r.pop('options',None); print(json.dumps(r, indent=1))" "$work/report.json"
  echo '```'
  echo
  echo "Renderings: dense_sceaux_${stamp}_front.png (from 100_7105), dense_sceaux_${stamp}_oblique.png (50 deg around)."
} > "$log"
echo "written $log (wall $(echo "$end - $start" | bc) s)"

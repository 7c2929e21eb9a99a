#!/usr/bin/env bash
# Pull throughput across a veth pair between two network namespaces (vehicle and shore), next
# to rsync of the same files from an rsync daemon in the vehicle namespace, in the same run.
# The vehicle's recorder runs on Cyclone DDS (bringup/config/cyclonedds-deploy.xml); the shore
# pulls once per vendor (fastdds-deploy.xml, cyclonedds-deploy.xml). Needs root (namespaces).
# Results: printed and written to bench_results/two_host_bench_<date>.md. README.md next to
# this script has the figures. DDS domain 7 (inside the namespaces only).
#
# Options (environment): AUV_BENCH_FILE_MB (size of each of 3 recordings, 32), AUV_BENCH_RUNS
# (repetitions, median reported, 3), AUV_BENCH_IN_FLIGHT (8), AUV_BENCH_CHUNK_BYTES (1048576),
# AUV_BENCH_RATE (tc rate of the vehicle -> shore link, e.g. 100mbit; empty = the bare veth),
# AUV_BENCH_DOMAIN (DDS domain inside the namespaces, 7), AUV_BENCH_NS_PREFIX (namespace names,
# auvtest-bench).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
file_mb=${AUV_BENCH_FILE_MB:-32}
runs=${AUV_BENCH_RUNS:-3}
in_flight=${AUV_BENCH_IN_FLIGHT:-8}
chunk_bytes=${AUV_BENCH_CHUNK_BYTES:-1048576}
rate=${AUV_BENCH_RATE:-}
domain=${AUV_BENCH_DOMAIN:-7}
ns_prefix=${AUV_BENCH_NS_PREFIX:-auvtest-bench}
command -v auv-recon > /dev/null || { echo "bench: auv-recon not on PATH (source install/setup.bash)" >&2; exit 2; }
command -v rsync > /dev/null || { echo "bench: rsync missing (scripts/install-deps.sh)" >&2; exit 2; }
[ "$(id -u)" = 0 ] || { echo "bench: needs root for network namespaces" >&2; exit 2; }

id=$$
veh=$ns_prefix-$id-veh
sho=$ns_prefix-$id-shore
vv=auvb${id}v
vs=auvb${id}s
net=10.231.$((id % 256))
work=$(mktemp -d /tmp/auv-two-host-bench.XXXXXX)
cleanup() {
  disown -a 2> /dev/null || true  # no "Killed" notices for the background servers
  for ns in $veh $sho; do
    for pid in $(ip netns pids $ns 2> /dev/null); do kill -9 "$pid" 2> /dev/null || true; done
    ip netns del $ns 2> /dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT

ip netns add $veh
ip netns add $sho
ip link add $vv type veth peer name $vs
ip link set $vv netns $veh
ip link set $vs netns $sho
ip -n $veh addr add $net.1/30 dev $vv
ip -n $sho addr add $net.2/30 dev $vs
for ns in $veh $sho; do ip -n $ns link set lo up; done
ip -n $veh link set $vv up
ip -n $sho link set $vs up
[ -n "$rate" ] && ip netns exec $veh tc qdisc replace dev $vv root tbf rate "$rate" burst 256kb latency 50ms

# DDS configurations from the deployment templates, as docs/deployment.md makes them.
sed -e "s/\"eth0\"/\"$vv\"/" -e "s/192.0.2.10/$net.1/" -e "s/192.0.2.20/$net.2/" \
  "$repo/bringup/config/cyclonedds-deploy.xml" > "$work/vehicle-cyclonedds.xml"
sed -e "s/\"eth0\"/\"$vs\"/" -e "s/192.0.2.10/$net.2/" -e "s/192.0.2.20/$net.1/" \
  "$repo/bringup/config/cyclonedds-deploy.xml" > "$work/shore-cyclonedds.xml"
sed -e "s/192.0.2.10/$net.2/" -e "s/192.0.2.20/$net.1/" \
  "$repo/bringup/config/fastdds-deploy.xml" > "$work/shore-fastdds.xml"

# Three recordings of random bytes (the transfer does not look inside; random defeats any
# compression on either side) with small sidecars.
rec=$work/recordings
for cam in left right forward; do
  mkdir -p "$rec/$cam"
  head -c $((file_mb * 1024 * 1024)) /dev/urandom > "$rec/$cam/${cam}_0001.mp4"
  { echo "frame,camera_time_s,sim_time_s"; for i in $(seq 0 99); do echo "$i,$i.0,$i.0"; done; } \
    > "$rec/$cam/${cam}_0001.mp4.frames.csv"
done
total_bytes=$(du -sb "$rec" | cut -f1)

export AUV_DOMAIN_ID=$domain
ip netns exec $veh env AUV_DDS=cyclonedds CYCLONEDDS_URI="file://$work/vehicle-cyclonedds.xml" \
  auv run recorder -p root:="$rec" -p vehicle_name:=bench > "$work/recorder.log" 2>&1 &
cat > "$work/rsyncd.conf" << EOF
use chroot = no
[recordings]
  path = $rec
  read only = yes
EOF
ip netns exec $veh rsync --daemon --no-detach --config="$work/rsyncd.conf" --address=$net.1 \
  --port=8730 > "$work/rsyncd.log" 2>&1 &

now() { date +%s.%N; }
mbps() { awk -v b="$1" -v t0="$2" -v t1="$3" 'BEGIN { printf "%.1f", b / (t1 - t0) / 1e6 }'; }
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

# Warm-up: the recorder has hashed the files and is discoverable; rsync answers.
ip netns exec $sho env AUV_DDS=fastdds FASTRTPS_DEFAULT_PROFILES_FILE="$work/shore-fastdds.xml" \
  auv recon pull --vehicle bench --into "$work/warmup" --timeout 120 > "$work/warmup.log" 2>&1 \
  || { cat "$work/warmup.log" "$work/recorder.log"; echo "bench: warm-up pull failed" >&2; exit 1; }
rm -rf "$work/warmup"
for i in $(seq 1 50); do
  ip netns exec $sho rsync --list-only rsync://$net.1:8730/recordings/ > /dev/null 2>&1 && break
  sleep 0.2
done

declare -A results summaries
for run in $(seq 1 "$runs"); do
  # The anchor: rsync of the same files over the same link, fresh destination each time.
  rm -rf "$work/rsync-dest"
  t0=$(now)
  ip netns exec $sho rsync -a rsync://$net.1:8730/recordings/ "$work/rsync-dest/"
  t1=$(now)
  results[rsync]+="$(mbps "$total_bytes" "$t0" "$t1") "
  for vendor in fastdds cyclonedds; do
    rm -rf "$work/survey"
    if [ $vendor = fastdds ]; then
      env=(AUV_DDS=fastdds FASTRTPS_DEFAULT_PROFILES_FILE="$work/shore-fastdds.xml")
    else
      env=(AUV_DDS=cyclonedds CYCLONEDDS_URI="file://$work/shore-cyclonedds.xml")
    fi
    t0=$(now)
    ip netns exec $sho env "${env[@]}" auv recon pull --vehicle bench --into "$work/survey" \
      --in-flight "$in_flight" --chunk-bytes "$chunk_bytes" --timeout 60 > "$work/pull.log" 2>&1 \
      || { cat "$work/pull.log"; echo "bench: pull failed" >&2; exit 1; }
    t1=$(now)
    results[$vendor]+="$(mbps "$total_bytes" "$t0" "$t1") "
    summaries[$vendor]=$(grep "^pull: " "$work/pull.log" | tail -1)
    # Byte-identical, or the figure means nothing.
    (cd "$rec" && sha256sum */*) > "$work/expected.sha"
    (cd "$work/survey/recordings" && sha256sum -c --quiet "$work/expected.sha") \
      || { echo "bench: pulled files differ" >&2; exit 1; }
  done
done

med() { echo "${results[$1]}" | tr ' ' '\n' | grep -v '^$' | median; }
rsync_med=$(med rsync)
stamp=$(date +%Y%m%d_%H%M%S)
mkdir -p "$repo/bench_results"
out="$repo/bench_results/two_host_bench_$stamp.md"
{
  echo "# two_host_bench_$stamp"
  echo
  echo "Vehicle recorder on Cyclone DDS in one network namespace, shore in another, one veth"
  echo "pair${rate:+ limited to $rate}; 3 recordings of $file_mb MiB + sidecars ($total_bytes bytes);"
  echo "pull --in-flight $in_flight --chunk-bytes $chunk_bytes; median of $runs runs, wall clock of"
  echo "the whole command (pull: discovery of the vehicle + catalogue + transfer + SHA-256 checks;"
  echo "rsync: connection + transfer). $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)."
  echo
  echo "| transfer | runs (MB/s) | median MB/s | ÷ rsync |"
  echo "|---|---|---:|---:|"
  echo "| rsync daemon (anchor) | ${results[rsync]}| $rsync_med | 1.00 |"
  for vendor in fastdds cyclonedds; do
    m=$(med $vendor)
    echo "| auv recon pull, shore on $vendor | ${results[$vendor]}| $m | $(awk -v a="$m" -v b="$rsync_med" 'BEGIN { printf "%.2f", a / b }') |"
  done
  echo
  echo "Last pull summaries (the tool's own rate counts from its first request, not from start-up):"
  echo
  for vendor in fastdds cyclonedds; do echo "* $vendor: \`${summaries[$vendor]}\`"; done
} | tee "$out"
echo
echo "bench: results in $out"

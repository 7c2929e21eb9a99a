#!/usr/bin/env bash
# Runs a command in a network namespace of its own (loopback only) in which the DDS ports of
# every domain id are kept out of the kernel's ephemeral port range.
#
# Why: both vendors map domain d to the UDP ports 7400 + 250 d + ... (discovery multicast on
# the first). For d >= 102 those ports lie inside Linux's ephemeral range (32768-60999), so any
# socket bound to port 0 (a Cyclone participant's unicast socket, a Fast DDS send socket, a
# browser) can be given a discovery port of another domain. A Fast DDS participant created
# after that discovers nothing, silently (a CI run failed so; reproduced by holding port
# 7400 + 250 d). The tests use ids up to 232; ROS 2 advises ids 0-101 for the same reason.
#
# Without the right to create a namespace (not root, no CAP_SYS_ADMIN), runs the command as
# is and says so.
set -euo pipefail

if [ $# -eq 0 ]; then
  echo "usage: $0 COMMAND [ARG...]" >&2
  exit 2
fi

if [ "${AUV_ISOLATED_NETWORK:-}" != 1 ]; then
  if unshare --net true 2>/dev/null; then
    AUV_ISOLATED_NETWORK=1 exec unshare --net -- "$0" "$@"
  fi
  echo "isolated-network: cannot create a network namespace (needs root or CAP_SYS_ADMIN);" \
       "running in this one, where a DDS test can rarely lose its discovery port to another" \
       "socket" >&2
  exec "$@"
fi

# Per domain: discovery and user multicast, then unicast ports of participant ids 0-19. Python
# writes the list in one write(): the kernel rejects it split in parts, as bash's echo does.
python3 - <<'PY'
ranges = ",".join(f"{7400 + 250 * d}-{7400 + 250 * d + 10 + 2 * 19 + 1}" for d in range(233))
with open("/proc/sys/net/ipv4/ip_local_reserved_ports", "w") as f:
    f.write(ranges + "\n")
PY
ip link set lo up
exec "$@"

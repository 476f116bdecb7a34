#!/usr/bin/env bash
# ctest driver: start keepless_node on a test-only udpm port (ttl=0: this host
# only), run an example publisher against it, stop the node.
#   run_with_node.sh NODE PORT CLIENT [ARGS...]   (the client gets the URL last)
set -euo pipefail
node=$1 port=$2; shift 2
url="udpm://239.255.76.67:${port}?ttl=0"
"$node" --url "$url" --latency-target-ms 0 --status-period-ms 100 --quiet &
pid=$!
trap 'kill -INT $pid 2>/dev/null || true; wait $pid 2>/dev/null || true' EXIT
"$@" "$url"

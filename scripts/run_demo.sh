#!/usr/bin/env bash
# The main job: keepless_node and keepless_vo_sim as two processes on the real
# LCM bus (UDP multicast, ttl=0: this host only). The simulator publishes a
# few hundred keyframes of a built-in street scene, applies every decision to
# its own map (closed loop), prints a live progress line and a summary table,
# and writes the report folder. lcm-logger records the whole bus meanwhile;
# the recording is then replayed with lcm-logplayer into a fresh node, whose
# decisions must equal the recorded ones byte for byte.
#
#   scripts/run_demo.sh [BUILD_DIR]        (default: build)
#
# Environment: KEEPLESS_DEMO_KEYFRAMES (300), KEEPLESS_DEMO_REPORT (report),
# KEEPLESS_DEMO_PORT (7667; the replay uses PORT+1), KEEPLESS_DEMO_SCENE
# (street|room), KEEPLESS_DEMO_REPLAY (1; 0 skips the replay check).
set -euo pipefail

BUILD=${1:-build}
KEYFRAMES=${KEEPLESS_DEMO_KEYFRAMES:-300}
REPORT=${KEEPLESS_DEMO_REPORT:-report}
PORT=${KEEPLESS_DEMO_PORT:-7667}
SCENE=${KEEPLESS_DEMO_SCENE:-street}
REPLAY=${KEEPLESS_DEMO_REPLAY:-1}
URL="udpm://239.255.76.67:${PORT}?ttl=0"
REPLAY_URL="udpm://239.255.76.67:$((PORT + 1))?ttl=0"

NODE="$BUILD/bin/keepless_node"
SIM="$BUILD/bin/keepless_vo_sim"
COMPARE="$BUILD/bin/keepless_log_compare"
for b in "$NODE" "$SIM" "$COMPARE"; do
  [ -x "$b" ] || { echo "run_demo: $b not built (cmake --build $BUILD)" >&2; exit 2; }
done
mkdir -p "$REPORT"

PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

# stop PID: SIGINT if it still runs, up to 5 s to finish; returns its exit status.
stop() {
  kill -INT "$1" 2>/dev/null || true
  for _ in $(seq 50); do kill -0 "$1" 2>/dev/null || break; sleep 0.1; done
  local rc=0
  wait "$1" 2>/dev/null || rc=$?
  return "$rc"
}

have_logger=0
if command -v lcm-logger >/dev/null && command -v lcm-logplayer >/dev/null; then have_logger=1; fi
if [ "$REPLAY" = 1 ] && [ "$have_logger" = 0 ]; then
  echo "run_demo: lcm-logger / lcm-logplayer not found (Debian: liblcm-bin): the replay cannot be checked;" \
    "install them or set KEEPLESS_DEMO_REPLAY=0" >&2
  exit 2
fi

echo "== keepless demo: keepless_node + keepless_vo_sim over $URL"
if [ "$have_logger" = 1 ]; then
  lcm-logger -q -f --lcm-url="$URL" "$REPORT/bus.lcmlog" >"$REPORT/logger.log" 2>&1 &
  LOGGER=$!; PIDS+=("$LOGGER")
fi
"$NODE" --latency-target-ms 0 --url "$URL" --max-keyframes "$KEYFRAMES" --status-period-ms 200 2>"$REPORT/node.log" &
NODE_PID=$!; PIDS+=("$NODE_PID")
sleep 0.5  # let the logger subscribe; the simulator itself waits for the node's status

set +e
"$SIM" --url "$URL" --scene "$SCENE" --keyframes "$KEYFRAMES" --report "$REPORT"
SIM_RC=$?
set -e
# The node exits after its last decision; a simulator that failed (or a lost
# keyframe) leaves it waiting for more: stop it then instead of waiting forever.
if [ "$SIM_RC" = 0 ]; then
  for _ in $(seq 50); do kill -0 "$NODE_PID" 2>/dev/null || break; sleep 0.1; done
fi
NODE_RC=0
stop "$NODE_PID" || NODE_RC=$?
sed -n '$p' "$REPORT/node.log"
if [ "$have_logger" = 1 ]; then
  sleep 0.3
  stop "$LOGGER" || true
fi
if [ "$SIM_RC" != 0 ]; then
  echo "run_demo: keepless_vo_sim failed ($SIM_RC); node log: $REPORT/node.log" >&2
  exit "$SIM_RC"
fi
if [ "$NODE_RC" != 0 ]; then  # e.g. a failure at exit: the demo does not pass over it
  echo "run_demo: keepless_node exited with $NODE_RC; its log: $REPORT/node.log" >&2
  exit 1
fi

if [ "$REPLAY" = 1 ] && [ "$have_logger" = 1 ]; then
  echo "== replay: lcm-logplayer $REPORT/bus.lcmlog -> a fresh keepless_node on $REPLAY_URL"
  lcm-logger -q -f --channel=KEEPLESS_DECISION --lcm-url="$REPLAY_URL" "$REPORT/replay.lcmlog" >>"$REPORT/logger.log" 2>&1 &
  RLOGGER=$!; PIDS+=("$RLOGGER")
  # The player does not wait for decisions: give the fresh node room to queue.
  "$NODE" --latency-target-ms 0 --url "$REPLAY_URL&recv_buf_size=4194304" --queue 4096 --max-keyframes "$KEYFRAMES" --quiet \
    2>"$REPORT/replay_node.log" &
  RNODE=$!; PIDS+=("$RNODE")
  # The node prints its start line once it has allocated and subscribed; on a
  # loaded machine that takes longer than the log's first keyframes.
  for _ in $(seq 300); do [ -s "$REPORT/replay_node.log" ] && break; sleep 0.1; done
  sleep 0.2  # the logger, too
  lcm-logplayer --lcm-url="$REPLAY_URL" --regexp="^KEEPLESS_(KEYFRAME|MAP_EVENT)$" "$REPORT/bus.lcmlog" >/dev/null
  for _ in $(seq 600); do kill -0 "$RNODE" 2>/dev/null || break; sleep 0.1; done
  RNODE_RC=0
  stop "$RNODE" || RNODE_RC=$?
  sleep 0.3
  stop "$RLOGGER" || true
  if [ "$RNODE_RC" != 0 ]; then
    echo "run_demo: the replaying keepless_node exited with $RNODE_RC; its log: $REPORT/replay_node.log" >&2
    exit 1
  fi
  echo -n "replay: KEEPLESS_DECISION, recorded vs replayed: "
  "$COMPARE" "$REPORT/bus.lcmlog" KEEPLESS_DECISION "$REPORT/replay.lcmlog" KEEPLESS_DECISION
fi
echo "report: $REPORT/ (summary.txt, keyframes.csv, points.csv, map_topdown.svg, keyframe_*.svg, bus.lcmlog)"

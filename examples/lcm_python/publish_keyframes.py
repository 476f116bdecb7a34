#!/usr/bin/env python3
"""A VO's side of the bus in Python: publish keyframe_t, read decision_t.

    publish_keyframes.py TYPES_DIR [URL]

TYPES_DIR holds the `keepless` package that `lcm-gen -p lcm_types/*.lcm` writes
(the build does this into build/examples/lcm_python/types). Uses LCM's Python
module (`import lcm`) where it is installed, else lcm_ctypes.py beside this
script, which calls the C library (Debian packages no Python module).
"""
import sys
import time

try:
    import lcm
except ImportError:
    import lcm_ctypes as lcm

sys.path.insert(0, sys.argv[1])
from keepless import decision_t, keyframe_t, status_t  # noqa: E402  (generated types)

URL = sys.argv[2] if len(sys.argv) > 2 else "udpm://239.255.76.67:7667?ttl=0"
KEYFRAMES, POINTS, STEP = 6, 300, 60

bus = lcm.LCM(URL)
state = {"up": False, "decisions": 0, "culled": 0}


def on_status(channel, data):
    status_t.decode(data)
    state["up"] = True


def on_decision(channel, data):
    d = decision_t.decode(data)
    print(f"decision for keyframe {d.keyframe_id}: status {d.status}, {d.points} points, "
          f"kept {d.kept}, culled {d.culled}")
    state["decisions"] += 1
    state["culled"] += d.num_culled


bus.subscribe("KEEPLESS_STATUS", on_status)
bus.subscribe("KEEPLESS_DECISION", on_decision)
deadline = time.time() + 10
while not state["up"] and time.time() < deadline:
    bus.handle_timeout(100)
if not state["up"]:
    sys.exit(f"lcm_python: no keepless_node status on {URL} within 10 s")

# snippet-begin: publish
for k in range(KEYFRAMES):
    kf = keyframe_t()
    kf.sequence = k + 1              # strictly increasing per publisher
    kf.utime = 1_000_000 + 100_000 * k
    kf.keyframe_id = k
    kf.centre = [0.2 * k, 0.0, 0.0]  # camera centre, metres
    kf.orientation = [1.0, 0.0, 0.0, 0.0]  # world-from-camera quaternion w, x, y, z
    kf.image_width, kf.image_height = 640, 480
    ids = [k * STEP + i for i in range(POINTS)]  # your VO's map point ids
    kf.point_id = ids
    kf.u = [float((i * 37) % 620 + 10) for i in ids]
    kf.v = [float((i * 53) % 460 + 10) for i in ids]
    kf.num_observations = POINTS
    kf.publisher_id = 43
    bus.publish("KEEPLESS_KEYFRAME", kf.encode())
    before, deadline = state["decisions"], time.time() + 5
    while state["decisions"] == before and time.time() < deadline:
        bus.handle_timeout(100)  # one decision_t per keyframe_t
# snippet-end: publish

print(f"lcm_python: {state['decisions']} decisions for {KEYFRAMES} keyframes, {state['culled']} points culled")
sys.exit(0 if state["decisions"] == KEYFRAMES and state["culled"] > 0 else 1)

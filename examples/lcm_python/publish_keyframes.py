#!/usr/bin/env python3
"""A VO's side of the bus in Python: publish keyframe_t, read decision_t.

    publish_keyframes.py TYPES_DIR [URL]

TYPES_DIR holds the `keepless` package that `lcm-gen -p lcm_types/*.lcm` writes
(the build does this into build/examples/lcm_python/types). Uses LCM's Python
module (`import lcm`) where it is installed, else lcm_ctypes.py beside this
script, which calls the C library (Debian packages no Python module).
"""
import os
import sys
import time

if len(sys.argv) < 2 or not os.path.isfile(os.path.join(sys.argv[1], "keepless", "decision_t.py")):
    sys.exit("usage: publish_keyframes.py TYPES_DIR [URL]\n"
             "TYPES_DIR: the folder `lcm-gen -p --ppath TYPES_DIR lcm_types/*.lcm` wrote keepless/ into"
             + (f" (no keepless/decision_t.py in {sys.argv[1]!r})" if len(sys.argv) > 1 else ""))

try:
    import lcm
except ImportError:
    import lcm_ctypes as lcm

sys.path.insert(0, sys.argv[1])
from keepless import decision_t, keyframe_t, status_t  # noqa: E402  (generated types)

URL = sys.argv[2] if len(sys.argv) > 2 else "udpm://239.255.76.67:7667?ttl=0"
KEYFRAMES, POINTS, STEP = 6, 300, 60

bus = lcm.LCM(URL)
state = {"up": False, "decisions": 0, "refused": 0, "culled": 0}
kf = None  # the keyframe_t last published: decisions for any other are not ours


def on_status(channel, data):
    status_t.decode(data)
    state["up"] = True


def on_decision(channel, data):
    d = decision_t.decode(data)
    # Every VO on the bus gets its decisions on this channel: answer only ours.
    if kf is None or d.publisher_id != kf.publisher_id or d.sequence != kf.sequence:
        return
    print(f"decision for keyframe {d.keyframe_id}: status {d.status}, {d.points} points, "
          f"kept {d.kept}, culled {d.culled}")
    state["decisions"] += 1
    if d.status in (decision_t.STATUS_REJECTED_INPUT, decision_t.STATUS_CAPACITY_EXCEEDED):
        print(f"lcm_python: keyframe {d.keyframe_id} refused: status {d.status}, "
              f"reject_reason {d.reject_reason} (status_t.REJECT_*)", file=sys.stderr)
        state["refused"] += 1
    state["culled"] += d.num_culled  # culled_point_id: delete these map points


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

print(f"lcm_python: {state['decisions']} decisions for {KEYFRAMES} keyframes, {state['refused']} refused, "
      f"{state['culled']} points culled")
sys.exit(0 if state["decisions"] == KEYFRAMES and state["refused"] == 0 and state["culled"] > 0 else 1)

#!/usr/bin/env python3
"""A scripted stand-in for keepless_node, for the examples' tests: it takes the
node's command line (only --url is used), sends status_t every 100 ms and answers
each keyframe_t with a decision_t that culls its first point. Two scripts
(KEEPLESS_SCRIPTED_MODE), as the real node's bus can look to a VO:

  foreign  before each answer, a decision for another publisher (another VO on
           the same bus); the example must not count it as its own
  reject   the keyframe of sequence 4 is refused (STATUS_REJECTED_INPUT); the
           example must say so and exit 1

KEEPLESS_PY_TYPES: the folder holding the lcm-gen -p `keepless` package.
"""
import os
import signal
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lcm_python"))
sys.path.insert(0, os.environ["KEEPLESS_PY_TYPES"])
try:
    import lcm
except ImportError:
    import lcm_ctypes as lcm
from keepless import decision_t, keyframe_t, status_t  # noqa: E402

mode = os.environ.get("KEEPLESS_SCRIPTED_MODE", "foreign")
url = sys.argv[sys.argv.index("--url") + 1]
bus = lcm.LCM(url)


def decision(kf, publisher_id, status, culled):
    d = decision_t()
    d.sequence, d.keyframe_id, d.utime, d.publisher_id = kf.sequence, kf.keyframe_id, kf.utime, publisher_id
    d.status = status
    d.reject_reason = 4 if status == decision_t.STATUS_REJECTED_INPUT else -1
    d.points = kf.num_observations
    d.culled = d.num_culled = len(culled)
    d.culled_point_id = culled
    d.kept = d.points - d.culled
    return d.encode()


def on_keyframe(channel, data):
    kf = keyframe_t.decode(data)
    if mode == "foreign":  # another VO's answer first, same sequence, culling a point of ours
        bus.publish("KEEPLESS_DECISION", decision(kf, kf.publisher_id + 1000, decision_t.STATUS_OPTIMAL,
                                                  [kf.point_id[1]]))
    if mode == "reject" and kf.sequence == 4:
        bus.publish("KEEPLESS_DECISION", decision(kf, kf.publisher_id, decision_t.STATUS_REJECTED_INPUT, []))
    else:
        bus.publish("KEEPLESS_DECISION", decision(kf, kf.publisher_id, decision_t.STATUS_OPTIMAL,
                                                  [kf.point_id[0]]))


bus.subscribe("KEEPLESS_KEYFRAME", on_keyframe)
# A background job of a script starts with SIGINT ignored: take it back, as the node does.
# The handler only sets a flag: an exception raised in it while a keyframe's callback runs
# would be swallowed by ctypes (lcm_ctypes calls back from C) and the loop would never end.
stop = False


def on_signal(signum, frame):
    global stop
    stop = True


signal.signal(signal.SIGINT, on_signal)
signal.signal(signal.SIGTERM, on_signal)
next_status = 0.0
while not stop:
    if time.time() >= next_status:
        bus.publish("KEEPLESS_STATUS", status_t().encode())
        next_status = time.time() + 0.1
    bus.handle_timeout(20)

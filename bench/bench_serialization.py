"""ROS 1 wire format: orchestra's generated codecs (node/serialization.py) against rosbags'.

Issue 16 asks whether rosbags' serializer should replace ours unless ours is faster. Each
side runs in a process of its own (interleaved rounds, medians) and times serialize and
deserialize of the same messages: a geometry_msgs/Twist (small, fixed size: the common
control-loop message) and a 640x480 rgb8 sensor_msgs/Image (large array).

Run:  python bench/bench_serialization.py [--repeat N]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CHILD = r"""
import json, sys, time
side = sys.argv[1]
SIZE = 640 * 480 * 3
if side == "orchestra":
    from orchestra.node.msg import get_message_class
    Twist = get_message_class("geometry_msgs/Twist")
    Image = get_message_class("sensor_msgs/Image")
    twist = Twist(); twist.linear.x = 1.0; twist.angular.z = 0.5
    image = Image(height=480, width=640, encoding="rgb8", step=640 * 3, data=bytes(SIZE))
    cases = {"twist": (lambda: twist.serialize_bytes(), Twist.deserialize_bytes),
             "image": (lambda: image.serialize_bytes(), Image.deserialize_bytes)}
else:
    import numpy
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    twist = T["geometry_msgs/msg/Twist"](linear=T["geometry_msgs/msg/Vector3"](x=1.0, y=0.0, z=0.0),
                                          angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.5))
    header = T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                      frame_id="")
    image = T["sensor_msgs/msg/Image"](header=header, height=480, width=640, encoding="rgb8",
                                       is_bigendian=0, step=640 * 3,
                                       data=numpy.zeros(SIZE, dtype=numpy.uint8))
    def codec(msg, name):
        return (lambda: ts.serialize_ros1(msg, name), lambda b: ts.deserialize_ros1(b, name))
    cases = {"twist": codec(twist, "geometry_msgs/msg/Twist"),
             "image": codec(image, "sensor_msgs/msg/Image")}
out = {}
for name, (ser, deser) in cases.items():
    n = 20000 if name == "twist" else 200
    data = bytes(ser())  # as received from a socket
    t0 = time.perf_counter()
    for _ in range(n):
        ser()
    t1 = time.perf_counter()
    for _ in range(n):
        deser(data)
    t2 = time.perf_counter()
    out[name] = {"ser_us": (t1 - t0) / n * 1e6, "deser_us": (t2 - t1) / n * 1e6, "bytes": len(data)}
print(json.dumps(out))
"""


def run(side: str) -> dict:
    env = dict(os.environ, PYTHONPATH=REPO + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", CHILD, side], env=env, capture_output=True,
                         text=True, check=True).stdout
    return json.loads(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    options = parser.parse_args()
    rows: dict[str, list[dict]] = {"orchestra": [], "rosbags": []}
    for _ in range(options.repeat):
        for side in rows:  # interleaved
            rows[side].append(run(side))
    print(f"{options.repeat} rounds, medians (microseconds per message)")
    for case in ("twist", "image"):
        med = {side: {k: statistics.median(r[case][k] for r in rs) for k in ("ser_us", "deser_us")}
               for side, rs in rows.items()}
        o, r = med["orchestra"], med["rosbags"]
        print(f"  {case:6} serialize   orchestra {o['ser_us']:9.2f}  rosbags {r['ser_us']:9.2f}"
              f"  rosbags/orchestra x{r['ser_us'] / o['ser_us']:.2f}")
        print(f"  {case:6} deserialize orchestra {o['deser_us']:9.2f}  rosbags {r['deser_us']:9.2f}"
              f"  rosbags/orchestra x{r['deser_us'] / o['deser_us']:.2f}")


if __name__ == "__main__":
    main()

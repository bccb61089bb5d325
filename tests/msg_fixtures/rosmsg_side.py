"""rosmsg's and rossrv's answers for many types in one process (run by /usr/bin/python3).

stdin: nothing; stdout: JSON {"msg"|"srv": {type: {"show", "raw", "md5"}}, "packages":
{mode: {pkg: [types]}}} for every type rosmsg/rossrv list on ROS_PACKAGE_PATH. The texts
are what ``rosmsg show`` passes to print().
"""
import json
import sys

import rosmsg
import rospkg


def main():
    rospack = rospkg.RosPack()
    out = {"msg": {}, "srv": {}, "packages": {}}
    for mode, kind in ((rosmsg.MODE_MSG, "msg"), (rosmsg.MODE_SRV, "srv")):
        text_of = rosmsg.get_msg_text if kind == "msg" else rosmsg.get_srv_text
        listing = {}
        for pkg, _ in sorted(rosmsg.iterate_packages(rospack, mode)):
            listing[pkg] = rosmsg.list_types(pkg, mode=mode, rospack=rospack)
            for type_name in listing[pkg]:
                try:
                    out[kind][type_name] = {
                        "show": text_of(type_name, raw=False, rospack=rospack),
                        "raw": text_of(type_name, raw=True, rospack=rospack),
                        "md5": rosmsg.rosmsg_md5(mode, type_name)}
                except Exception as exc:  # noqa: BLE001 - reported, the test skips the type
                    out[kind][type_name] = {"error": str(exc)}
        out["packages"][kind] = listing
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()

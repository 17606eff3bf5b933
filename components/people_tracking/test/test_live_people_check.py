#!/usr/bin/env python3
"""Test of tools/live_people_check.py's scoring (ctest people_tracking_test_live_people_check).

Scripted `cairn topic echo` recordings (the text format the CLI prints) of three scans: the odometry frame is the
map frame moved by (1, -2) and turned by 0.5 rad, so tracks (odometry frame) must be put into the map frame with
the true and odometry poses of their stamp. Person 7 is tracked in scans 1 and 2 and missed in scan 3, person 8
stands 9 m from the robot (not counted), and one track in every scan is 1 m from everybody (a phantom).
"""
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import live_people_check  # noqa: E402

ODOM_IN_MAP = (1.0, -2.0, 0.5)  # pose of the odometry frame in the map frame


def header(t, frame):
    sec = int(t)
    return ("header:\n  stamp:\n    sec: %d\n    nanosec: %d\n  frame_id: \"%s\"\n" %
            (sec, round((t - sec) * 1e9), frame))


def odometry(t, frame, x, y, yaw):
    return (header(t, frame) + "child_frame_id: \"base_link\"\npose:\n  pose:\n    position:\n      x: %r\n      y: %r\n"
            "      z: 0\n    orientation:\n      x: 0\n      y: 0\n      z: %r\n      w: %r\n  covariance: [0, 0]\n"
            % (x, y, math.sin(yaw / 2), math.cos(yaw / 2)))


def to_odom(p):
    """A map-frame point in the odometry frame."""
    x, y, a = ODOM_IN_MAP
    dx, dy = p[0] - x, p[1] - y
    return (math.cos(a) * dx + math.sin(a) * dy, -math.sin(a) * dx + math.cos(a) * dy)


def main():
    d = tempfile.mkdtemp(prefix="cairn_live_check_test_")
    stamps = [1.0, 1.1, 1.2]
    robot_map = [(2.0, 3.0, 0.1), (2.1, 3.0, 0.1), (2.2, 3.0, 0.1)]
    person7 = [(4.0, 3.5), (4.1, 3.5), (4.2, 3.5)]
    person8 = (11.5, 3.0)
    with open(os.path.join(d, "ground_truth.txt"), "w") as g, open(os.path.join(d, "odom.txt"), "w") as o:
        for t, r in zip(stamps, robot_map):
            g.write(odometry(t, "map", *r) + "---\n")
            # The robot's odometry pose: the map pose seen from the odometry frame.
            ox, oy = to_odom(r[:2])
            o.write(odometry(t, "odom", ox, oy, r[2] - ODOM_IN_MAP[2]) + "---\n")
    with open(os.path.join(d, "people_ground_truth.txt"), "w") as f:
        f.write(header(0.9, "map") + "people: []\n---\n")
        for t, p in zip(stamps, person7):
            f.write(header(t, "map") + "people:\n")
            for pid, q in ((7, p), (8, person8)):
                f.write("-\n  id: %d\n  position:\n    x: %r\n    y: %r\n    z: 0\n  heading: 0\n" % (pid, q[0], q[1]))
            f.write("---\n")
    with open(os.path.join(d, "people_tracks.txt"), "w") as f:
        for k, (t, p) in enumerate(zip(stamps, person7)):
            tracks = [(1, (p[0] + 0.1, p[1]))] if k < 2 else [(1, (p[0] + 0.8, p[1]))]  # scan 3: 0.8 m off
            tracks.append((2, (p[0], p[1] + 1.0)))  # 1 m from person 7: a phantom
            f.write(header(t, "odom") + "tracks:\n")
            for tid, q in tracks:
                x, y = to_odom(q)
                f.write("-\n  track_id: %d\n  position:\n    x: %r\n    y: %r\n    z: 0\n  covariance: [0.1, 0, 0, 0.1]\n"
                        "  stamp:\n    sec: 1\n    nanosec: 0\n" % (tid, x, y))
            f.write("---\n")
    r = live_people_check.score(d)
    expect = {"scans": 3, "track_scans": 6, "phantom_track_scans": 4, "person_scans_within_8m": 3,
              "person_scans_missed": 1, "missed_by_person": {"7": [1, 3]}, "tracks_per_scan_median": 2}
    for key, value in expect.items():
        assert r[key] == value, (key, r[key], value, r)
    # The parser reads the echo format's nested lists, inline lists and an empty list.
    parsed = live_people_check.load(os.path.join(d, "people_tracks.txt"))
    assert len(parsed) == 3 and parsed[0]["tracks"][1]["track_id"] == 2.0, parsed[0]
    assert parsed[0]["tracks"][0]["covariance"] == [0.1, 0.0, 0.0, 0.1], parsed[0]
    assert live_people_check.load(os.path.join(d, "people_ground_truth.txt"))[0]["people"] == []
    # No scan with everything at one stamp: a clear error, not a division by zero.
    os.remove(os.path.join(d, "odom.txt"))
    open(os.path.join(d, "odom.txt"), "w").close()
    try:
        live_people_check.score(d)
        raise AssertionError("scoring without odometry must fail")
    except SystemExit as e:
        assert "no scans" in str(e), e
    print("ok")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Test of tools/live_people_check.py's scoring (ctest people_tracking_test_live_people_check).

Scripted `cairn topic echo` recordings (the text format the CLI prints) of three scans: the odometry frame is the
map frame moved by (1, -2) and turned by 0.5 rad, so tracks (odometry frame) must be put into the map frame with
the true and odometry poses of their stamp. Person 7 is tracked in scans 1 and 2 and missed in scan 3, person 8
stands 9 m from the robot (not counted), and one track in every scan is 1 m from everybody (a phantom). The scans
(laser 0.2 m ahead of and 0.1 m beside base_link, turned by 0.3 rad; base_link 0.5 m off the base, so the whole
/tf_static chain counts) see person 7 in scans 1 and 2 and end 0.5 m from the laser in scan 3: the miss there is of
a hidden person.
"""
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import live_people_check  # noqa: E402

ODOM_IN_MAP = (1.0, -2.0, 0.5)  # pose of the odometry frame in the map frame
BASE_LINK, LASER = (-0.4, 0.3, 0.0), (0.2, 0.1, 0.3)  # base_footprint <- base_link <- laser (0.5 m apart: a test)


def header(t, frame):
    sec = int(t)
    return ("header:\n  stamp:\n    sec: %d\n    nanosec: %d\n  frame_id: \"%s\"\n" %
            (sec, round((t - sec) * 1e9), frame))


def odometry(t, frame, x, y, yaw):
    return (header(t, frame) + "child_frame_id: \"base_link\"\npose:\n  pose:\n    position:\n      x: %r\n      y: %r\n"
            "      z: 0\n    orientation:\n      x: 0\n      y: 0\n      z: %r\n      w: %r\n  covariance: [0, 0]\n"
            % (x, y, math.sin(yaw / 2), math.cos(yaw / 2)))


def transform(parent, child, p):
    return ("-\n  header:\n    stamp:\n      sec: 0\n      nanosec: 0\n    frame_id: \"%s\"\n  child_frame_id: \"%s\"\n"
            "  transform:\n    translation:\n      x: %r\n      y: %r\n      z: 0.1\n    rotation:\n      x: 0\n"
            "      y: 0\n      z: %r\n      w: %r\n" % (parent, child, p[0], p[1], math.sin(p[2] / 2), math.cos(p[2] / 2)))


def laser_scan(t, laser, person, hidden):
    """360 beams over the full turn from the laser pose `laser` (map frame): on a 0.1 m circle around `person`,
    else no return (.inf, as the echo prints it); all 0.5 m when `hidden`."""
    beams, ranges = 360, []
    for k in range(beams):
        a = laser[2] - math.pi + k * 2 * math.pi / beams
        c, s = math.cos(a), math.sin(a)
        dx, dy = person[0] - laser[0], person[1] - laser[1]
        along = c * dx + s * dy
        off2 = dx * dx + dy * dy - along * along
        r = along - math.sqrt(0.01 - off2) if along > 0 and off2 < 0.01 else math.inf
        ranges.append(0.5 if hidden else r)
    return (header(t, "laser") + "angle_min: %r\nangle_max: %r\nangle_increment: %r\nrange_min: 0.05\n"
            "range_max: 20\nranges: [%s]\nintensities: []\n" % (-math.pi, math.pi - 2 * math.pi / beams,
                                                                 2 * math.pi / beams, ", ".join("%r" % r if r < math.inf else ".inf" for r in ranges)))


def compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


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
    assert "person_scans_visible" not in r, r  # no /scan recorded: no visibility fields
    with open(os.path.join(d, "tf_static.txt"), "w") as f:
        f.write(header(0.0, "") + "transforms:\n" + transform("base_link", "laser", LASER) +
                transform("base_footprint", "base_link", BASE_LINK) + "---\n")
    with open(os.path.join(d, "scan.txt"), "w") as f:
        for k, (t, rb, p) in enumerate(zip(stamps, robot_map, person7)):
            f.write(laser_scan(t, compose(compose(rb, BASE_LINK), LASER), p, hidden=k == 2) + "---\n")
    r = live_people_check.score(d)
    expect.update({"person_scans_visible": 2, "person_scans_visible_missed": 0, "missed_visible_by_person": {"7": [0, 2]}})
    for key, value in expect.items():
        assert r[key] == value, (key, r[key], value, r)
    # The laser's pose needs the whole chain: without base_link's offset the beams miss person 7 in scan 1.
    assert live_people_check.beams_near(live_people_check.load(os.path.join(d, "scan.txt"))[0],
                                        compose(robot_map[0], LASER), *person7[0]) < 3
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

#!/usr/bin/env python3
"""Score a running simulation's people tracks against the simulator's ground truth, over DDS.

  live_people_check.py SPEC SECONDS [--cairn PATH] [--out DIR]

Launches SPEC (a launch spec with cairn_sim::Simulator and cairn_people_tracking::PeopleTracker) for SECONDS of
wall time, records /people/tracks, /people/ground_truth, /odom, /ground_truth, /scan and /tf_static with `cairn topic
echo` (as any DDS tool could), and prints one JSON line: scans, tracks per scan (mean, median, max), phantom
track-scans (a published track with no simulated person within 0.5 m; tracks are in the odometry frame and are put
into the simulator's map frame with the true and odometry poses of the same stamp), and per simulated person within
8 m of the robot the scans in which no track was within 0.5 m — all of them (person_scans_within_8m,
person_scans_missed, missed_by_person: a person behind a wall counts as missed) and those in which the person was in
the laser's line of sight (person_scans_visible, person_scans_visible_missed, missed_visible_by_person: at least 3
beams of the scan of that stamp end within 0.35 m of the person, as the people bench counts people; the laser's
pose is the true pose composed with the /tf_static chain up to the scan's frame). The visibility fields are left
out of recordings without /scan and /tf_static.
Used for docs/benchmarks.md "Corridor walls" and "The demo's SLAM range and weak legs" (the demo's simulator container).
"""
import argparse
import bisect
import collections
import json
import math
import os
import subprocess
import sys
import tempfile
import time

TOPICS = ["/people/tracks", "/people/ground_truth", "/odom", "/ground_truth", "/scan", "/tf_static"]
VISIBLE_RADIUS, VISIBLE_BEAMS = 0.35, 3  # a person is in sight when this many beams end this close to them


YAML_SPECIAL = {".inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}  # how the echo prints non-finite numbers


def scalar(text):
    text = text.strip()
    if text.startswith("[") and text.endswith("]"):
        return [scalar(x) for x in text[1:-1].split(",") if x.strip()]
    if text.startswith('"') and text.endswith('"'):
        return text[1:-1]
    if text in YAML_SPECIAL:
        return YAML_SPECIAL[text]
    try:
        return float(text)
    except ValueError:
        return text


def block(lines, i, indent):
    """The mapping or list of `cairn topic echo` text starting at lines[i] (all at `indent`); returns (value, next i)."""
    if lines[i][1].startswith("-"):
        items = []
        while i < len(lines) and lines[i][0] == indent and lines[i][1].startswith("-"):
            i += 1
            if i < len(lines) and lines[i][0] > indent:
                item, i = block(lines, i, lines[i][0])
            else:
                item = {}
            items.append(item)
        return items, i
    out = {}
    while i < len(lines) and lines[i][0] == indent and not lines[i][1].startswith("-"):
        key, _, rest = lines[i][1].partition(":")
        i += 1
        if rest.strip():
            out[key] = scalar(rest)
        elif i < len(lines) and (lines[i][0] > indent or (lines[i][0] == indent and lines[i][1].startswith("-"))):
            out[key], i = block(lines, i, lines[i][0])
        else:
            out[key] = None
    return out, i


def load(path):
    """The messages of a `cairn topic echo` output (YAML-like text, documents separated by ---)."""
    messages, current = [], []
    with open(path) as f:
        for raw in list(f) + ["---\n"]:
            line = raw.rstrip("\n")
            if line.strip() == "---":
                if current:
                    messages.append(block(current, 0, current[0][0])[0])
                current = []
            elif line.strip():
                current.append((len(line) - len(line.lstrip(" ")), line.strip()))
    return messages


def stamp(m):
    h = m["header"]["stamp"]
    return round(int(h["sec"]) + int(h["nanosec"]) * 1e-9, 3)


def yaw_of(q):
    """Heading of a quaternion that turns about z only."""
    return math.atan2(2 * q["w"] * q["z"], 1 - 2 * q["z"] ** 2)


def pose(m):
    p = m["pose"]["pose"]
    return (p["position"]["x"], p["position"]["y"], yaw_of(p["orientation"]))


def compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


def inverse(a):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-(c * a[0] + s * a[1]), -(-s * a[0] + c * a[1]), -a[2])


def mount(tf_static, frame):
    """Planar pose of `frame` in the root of its /tf_static chain (the robot's base, whose pose /ground_truth gives)."""
    links = {}
    for m in tf_static:
        for tr in m.get("transforms") or []:
            t = tr["transform"]
            links[tr["child_frame_id"]] = (tr["header"]["frame_id"],
                                           (t["translation"]["x"], t["translation"]["y"], yaw_of(t["rotation"])))
    p, seen = (0.0, 0.0, 0.0), set()
    while frame in links and frame not in seen:
        seen.add(frame)
        frame, up = links[frame]
        p = compose(up, p)
    return p


def beams_near(scan, laser, x, y):
    """How many beams of `scan` (laser at `laser` in the map frame) end within VISIBLE_RADIUS of (x, y)."""
    dx, dy = x - laser[0], y - laser[1]
    dist = math.hypot(dx, dy)
    if dist <= VISIBLE_RADIUS:
        return VISIBLE_BEAMS
    inc, ranges = scan["angle_increment"], scan["ranges"]
    if not inc > 0 or not isinstance(ranges, list):
        return 0
    bearing = math.atan2(dy, dx) - laser[2] - scan["angle_min"]
    half = math.asin(VISIBLE_RADIUS / dist)
    n = 0
    for k in range(math.floor((bearing - half) / inc), math.ceil((bearing + half) / inc) + 1):
        i = k % len(ranges) if abs(len(ranges) * inc - 2 * math.pi) < 2 * inc else k
        if not 0 <= i < len(ranges) or not isinstance(ranges[i], float) or not math.isfinite(ranges[i]):
            continue
        a = laser[2] + scan["angle_min"] + k * inc
        ex, ey = laser[0] + ranges[i] * math.cos(a), laser[1] + ranges[i] * math.sin(a)
        n += math.hypot(ex - x, ey - y) <= VISIBLE_RADIUS
    return n


def score(d, match=0.5, field=8.0):
    odom = {stamp(m): pose(m) for m in load(os.path.join(d, "odom.txt"))}
    truth = {stamp(m): pose(m) for m in load(os.path.join(d, "ground_truth.txt"))}
    people = {round(stamp(m), 2): [(int(p["id"]), p["position"]["x"], p["position"]["y"]) for p in (m["people"] or [])]
              for m in load(os.path.join(d, "people_ground_truth.txt"))}
    keys = sorted(people)
    scans, laser_mount = None, None
    if os.path.exists(os.path.join(d, "scan.txt")) and os.path.exists(os.path.join(d, "tf_static.txt")):
        scans = {stamp(m): m for m in load(os.path.join(d, "scan.txt"))}
        for m in scans.values():
            if not isinstance(m.get("ranges"), list) or any(not isinstance(r, float) for r in m["ranges"]):
                raise SystemExit("live_people_check: %s/scan.txt: the scan at %.3f s has ranges that are not numbers "
                                 "(recorded without `cairn topic echo --full-length`?)" % (d, stamp(m)))
        frames = {m["header"]["frame_id"] for m in scans.values()}
        if len(frames) > 1:
            raise SystemExit("live_people_check: scans in several frames %s in %s/scan.txt" % (sorted(frames), d))
        laser_mount = mount(load(os.path.join(d, "tf_static.txt")), frames.pop() if frames else "")
    per_scan, phantoms, missed, seen = [], 0, collections.Counter(), collections.Counter()
    vis_missed, vis_seen = collections.Counter(), collections.Counter()
    for m in load(os.path.join(d, "people_tracks.txt")):
        t = stamp(m)
        i = bisect.bisect_left(keys, t - 0.001)
        if t not in odom or t not in truth or i >= len(keys) or abs(keys[i] - t) > 0.051:
            continue
        map_from_odom = compose(truth[t], inverse(odom[t]))
        tracks = [compose(map_from_odom, (tr["position"]["x"], tr["position"]["y"], 0.0)) for tr in (m["tracks"] or [])]
        persons = people[keys[i]]
        per_scan.append(len(tracks))
        phantoms += sum(1 for x, y, _ in tracks if all(math.hypot(x - px, y - py) > match for _, px, py in persons))
        robot = truth[t]
        scan = scans.get(t) if scans is not None else None
        for pid, px, py in persons:
            if math.hypot(px - robot[0], py - robot[1]) <= field:
                miss = all(math.hypot(x - px, y - py) > match for x, y, _ in tracks)
                seen[pid] += 1
                missed[pid] += miss
                if scan is not None and beams_near(scan, compose(robot, laser_mount), px, py) >= VISIBLE_BEAMS:
                    vis_seen[pid] += 1
                    vis_missed[pid] += miss
    if not per_scan:
        raise SystemExit("live_people_check: no scans with tracks, odometry and ground truth at the same stamp in " + d)
    ordered = sorted(per_scan)
    visible = {}
    if scans is not None:
        visible = {"person_scans_visible": sum(vis_seen.values()), "person_scans_visible_missed": sum(vis_missed.values()),
                   "missed_visible_by_person": {str(k): [vis_missed[k], vis_seen[k]] for k in sorted(vis_seen)}}
    return {"scans": len(per_scan), "tracks_per_scan_mean": round(sum(per_scan) / len(per_scan), 3),
            "tracks_per_scan_median": ordered[len(ordered) // 2], "tracks_per_scan_max": ordered[-1],
            "track_scans": sum(per_scan), "phantom_track_scans": phantoms,
            "person_scans_within_8m": sum(seen.values()), "person_scans_missed": sum(missed.values()),
            "missed_by_person": {str(k): [missed[k], seen[k]] for k in sorted(seen)}, **visible}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec")
    ap.add_argument("seconds", type=float)
    ap.add_argument("--cairn", default="cairn")
    ap.add_argument("--out", default=None, help="keep the recordings here (default: a temporary directory)")
    a = ap.parse_args()
    if not (a.seconds > 5):
        raise SystemExit("live_people_check: SECONDS must be > 5, got %g" % a.seconds)
    out = a.out or tempfile.mkdtemp(prefix="cairn_live_people_")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "launch.log"), "w") as log:
        launch = subprocess.Popen([a.cairn, "launch", a.spec, "--duration", str(a.seconds)], stdout=log, stderr=log)
        time.sleep(2)
        echoes = []
        for topic in TOPICS:
            f = open(os.path.join(out, topic.strip("/").replace("/", "_") + ".txt"), "w")
            echoes.append((subprocess.Popen([a.cairn, "topic", "echo", topic, "--wait", "10", "--full-length"], stdout=f,
                                            stderr=subprocess.DEVNULL), f))
        rc = launch.wait()
        for p, f in echoes:
            p.terminate()
            p.wait()
            f.close()
    if rc != 0:
        raise SystemExit("live_people_check: cairn launch %s exited with %d (see %s/launch.log)" % (a.spec, rc, out))
    print(json.dumps(score(out)))


if __name__ == "__main__":
    main()

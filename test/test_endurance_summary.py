#!/usr/bin/env python3
"""scripts/endurance_summary.py on a made-up samples.csv: RSS in MB, CPU share of one core between rows, one row
per window plus the last sample, a respawned container under its own pid, and a malformed row -> file:line, exit 2."""
import os
import subprocess
import sys
import tempfile

SCRIPT = sys.argv[1]
HEADER = "t,pid,name,rss_kb,cpu_ticks,threads,fds\n"
ROWS = [
    '0,10,"cairn launch demo.yaml",5000,0,1,5',
    '0,11,"/b/cairn container --name sim_container --threads 1",10240,0,8,17',
    '150,11,"/b/cairn container --name sim_container --threads 1",20480,1500,9,17',   # skipped: inside the window
    '300,11,"/b/cairn container --name sim_container --threads 1",30720,3000,9,17',   # 30 s CPU in 300 s = 10 %
    '400,11,"/b/cairn container --name sim_container --threads 1",30720,5000,9,18',   # last: 20 s in 100 s = 20 %
    '300,12,"/b/cairn container --name demo_container --threads 1",12288,0,8,17',     # respawned: new pid
    '600,12,"/b/cairn container --name demo_container --threads 1",12288,300,8,17',
]


def run(text):
    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
        f.write(text)
    return subprocess.run([sys.executable, SCRIPT, f.name, "300"], capture_output=True, text=True), f.name


def main():
    r, path = run(HEADER + "\n".join(ROWS) + "\n")
    os.unlink(path)
    assert r.returncode == 0, r.stderr
    lines = [l.split() for l in r.stdout.splitlines()]
    assert ["sim_container", "(pid", "11)"] == lines[0], lines
    rows = [l for l in lines if l and l[0].isdigit()]
    assert rows[0][:2] == ["0", "10.0"], rows          # first sample: no CPU share
    assert rows[1][:3] == ["300", "30.0", "10.0"], rows
    assert rows[2][:3] == ["400", "30.0", "20.0"], rows
    assert rows[2][3:] == ["9", "18"], rows
    assert ["demo_container", "(pid", "12)"] in lines, lines
    assert rows[4][:3] == ["600", "12.0", "1.0"], rows  # 3 s CPU in 300 s
    assert not any("launch" in " ".join(l) for l in lines), "only containers are listed"
    r, path = run(HEADER + ROWS[1] + "\n" + '5,11,"/b/cairn container --name sim_container",lots,1,1,1\n')
    os.unlink(path)
    assert r.returncode == 2 and f"{path}:3: malformed row" in r.stderr, (r.returncode, r.stderr)
    print("ok")


if __name__ == "__main__":
    main()

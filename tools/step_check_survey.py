#!/usr/bin/env python3
"""`mjtether run --check-step` over the scene fuzzer's scenes (docs/step_check.md, "Measured").

Dumps the MJCF of seeds FIRST..FIRST+COUNT-1 (MJTETHER_SCENE_FUZZ_XML=1), runs each for 1 s with
`--check-step 10` (and `--check-from` if given) on every core, and prints the exit codes; with
--fuzz-log (a verbose long-run log of tests/scene_fuzz_test, MJTETHER_SCENE_FUZZ_VERBOSE=1) it
tabulates them against the fuzzer's own outcome for each seed, and counts what the check said
of each stop (the smaller step cures it, or not).

  python3 tools/step_check_survey.py --build build --first 201 --count 500 \
      --fuzz-log /path/to/longrun.log [--check-from 0.2]
"""
import argparse
import collections
import concurrent.futures
import os
import re
import subprocess
import sys
import tempfile


def dump_scenes(build, first, count, out_dir):
    env = dict(os.environ, MJTETHER_SCENE_FUZZ_XML="1", MJTETHER_SCENE_FUZZ_FIRST=str(first),
               MJTETHER_SCENE_FUZZ_COUNT=str(count))
    text = subprocess.run([os.path.join(build, "tests", "scene_fuzz_test"),
                           "--gtest_filter=SceneFuzz.Every*"], env=env, capture_output=True,
                          text=True, check=True).stdout
    parts = re.split(r"^seed (\S+):\n", text, flags=re.M)
    seeds = []
    for i in range(1, len(parts), 2):
        if not parts[i].isdigit() or not first <= int(parts[i]) < first + count:
            continue  # regression seeds of another draw, outside the range
        xml = re.search(r"<mujoco>.*?</mujoco>", parts[i + 1], re.S)
        if xml:
            path = os.path.join(out_dir, "s%s.xml" % parts[i])
            with open(path, "w") as f:
                f.write(xml.group(0))
            seeds.append(int(parts[i]))
    return seeds


def check(cli, path, check_from):
    args = [cli, "run", path, "--duration", "1", "--check-step", "10"]
    if check_from > 0:
        args += ["--check-from", str(check_from)]
    try:
        r = subprocess.run(args, capture_output=True, text=True, timeout=900)
    except subprocess.TimeoutExpired:
        return -1, "timeout"
    return r.returncode, r.stderr


def fuzz_outcomes(path):
    """seed -> (outcome, detail): "agrees", "diverged", ... and, for a stop, its checked cause."""
    out = {}
    for line in open(path, errors="replace"):
        m = re.match(r"seed (\d+) \[[^\]]*\]: (\w+): (.*)", line)
        if m:
            fields = m.group(3).split(":")
            outcome = ("fails" if m.group(2) != "pass" else
                       fields[0].split(" with")[0].strip())
            out[int(m.group(1))] = (outcome, fields[1].strip() if len(fields) > 1 else "")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--first", type=int, default=201)
    ap.add_argument("--count", type=int, default=500)
    ap.add_argument("--check-from", type=float, default=0)
    ap.add_argument("--fuzz-log", help="verbose scene fuzzer log, for the outcome of each seed")
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    a = ap.parse_args()
    cli = os.path.join(a.build, "mjtether")
    with tempfile.TemporaryDirectory() as tmp:
        seeds = dump_scenes(a.build, a.first, a.count, tmp)
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            runs = dict(zip(seeds, pool.map(
                lambda s: check(cli, os.path.join(tmp, "s%d.xml" % s), a.check_from), seeds)))
    codes = collections.Counter(rc for rc, _ in runs.values())
    print("%d scenes; exit codes: %s" % (len(runs), dict(sorted(codes.items()))))
    if not a.fuzz_log:
        return
    fuzz = fuzz_outcomes(a.fuzz_log)
    table = collections.defaultdict(collections.Counter)
    first_off = collections.Counter()
    stops = collections.Counter()
    for s, (rc, err) in runs.items():
        outcome, cause = fuzz.get(s, ("not in the log", ""))
        table[outcome][rc] += 1
        if rc == 6 and outcome == "agrees":
            line = next((l for l in err.splitlines() if "DISAGREES" in l), "")
            first_off["position" if "position" in line else "peak" if "peak" in line
                      else "window mean" if "mean" in line else "other"] += 1
        if rc == 1:
            stops[("cured by h/10" if "the step is the cause" in err else
                   "stops at h/10 too" if "stopped too" in err else "other", cause)] += 1
    print("| fuzzer outcome | scenes | exit 0 | exit 6 | exit 1 | exit 2 | other |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for outcome, c in sorted(table.items()):
        other = sum(v for k, v in c.items() if k not in (0, 1, 2, 6))
        print("| %s | %d | %d | %d | %d | %d | %d |" % (outcome, sum(c.values()), c[0], c[6],
                                                      c[1], c[2], other))
    print("fuzzer-agreeing scenes flagged, by the first quantity off:", dict(first_off))
    print("stops, by what the check said and the fuzzer's checked cause:")
    for (said, cause), n in sorted(stops.items()):
        print("  %3d  %s: %s" % (n, said, cause))


if __name__ == "__main__":
    sys.exit(main())

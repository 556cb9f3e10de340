#!/usr/bin/env python3
"""Classify the failing scenes of a verbose scene-fuzzer log (docs/scene_fuzzer.md).

  MJTETHER_SCENE_FUZZ_VERBOSE=1 build/tests/scene_fuzz_test > fuzz.log
  python3 tools/scene_fuzz_classify.py fuzz.log            # known-list lines, by class
  python3 tools/scene_fuzz_classify.py --counts fuzz.log   # outcome and class counts
  python3 tools/scene_fuzz_classify.py --bands [--seeds A-B] fuzz.log
      # per integrator and coupling omega h band: runs that went to their end, how many of
      # them failed, refused, diverged with a checked cause (docs/coupling.md, session 29), and
      # of the runs that went to their end, those whose disagreement was warned (session 33)

Outcomes are counted as the test printed them, with one exception: a log from before session
11 (s11trans) printed a stretched start that disagreed, but whose same scene started
unstretched agreed, as "FAIL disagrees ... started unstretched: agrees"; the test now gives it
its own outcome, "pass warned: starts stretched, its outcome depends on the step as the warning
says" (the warning was emitted: the test judged the stretch only where Attach warned), and this
tool counts such old lines so too, marked "(old log)", whatever omega h is. A stretched start
that disagrees also unstretched stays a failure in its class below.

The test's passing outcomes include, since session 11 (s11trans), "agrees within a window moved
by up to a tenth": a snap train whose snaps fall a few ms apart at 2 ms and at 0.2 ms, moving
the 0.2 s mean beyond the tolerance (the test checks the position, the snap at the window's
edge, and both references). A log from before counts such scenes as open-transient failures.

Classes, first that applies (the labels of tests/scene_fuzz_known.txt):
  coupling          omega h >= 1 at the vehicle, omega = sqrt(EA / (L0 (m + a_min)))
  open-energy       the tether gains energy beyond the work of its ends (no current)
  open-one-two-segments   a tether of 1 or 2 segments
  open-thrust-qacc  MuJoCo's bad-qacc warning with a thrust scheduled
  open-stretched-start  (none since session 11: now the warned outcome above)
  open-transient    disagrees with the 0.2 ms run (and with the 0.02 ms run beyond the two
                    refinements' spread, and not only by a snap's phase; omega h < 1)
  open-other        anything else (a bad qacc without thrust, a step blamed that 0.2 ms
                    does not cure)
"""
import re
import sys
from collections import Counter, OrderedDict

LINE = re.compile(r"^seed (\d+)( draw=(\d+))? \[(\w+), N=(\d+), EA=([^,]+), m=([^ ]+) kg, "
                  r"omega\*h=([^,]+), seabed kind (\d), thrust/holds=([^\]]+)\]: (pass|FAIL): "
                  r"([^:]+): ?(.*)$")
# The advisor's refusal limit on a free vehicle at end B with end A fixed (the fuzzer's scenes):
# implicit2 has none there since session 10 (its consistent coupling from omega h 0.5), explicit
# keeps 2 with its consistent coupling from 0.5, rk4 0.5 since session 29 (docs/coupling.md).
LIMITS = {"explicit": "2", "rk4": "0.5", "implicit2": "none", "implicit": "none", "bdf2": "none"}
CLASSES = ["coupling", "open-energy", "open-one-two-segments", "open-thrust-qacc",
           "open-stretched-start", "open-transient", "open-other"]


WARNED = "warned: starts stretched, its outcome depends on the step as the warning says"


def warned_stretched(passed, kind, detail):
    """The test's warned outcome, or an old log's failure that the test now gives it."""
    if passed:
        return kind == WARNED
    return kind.startswith("disagrees") and "started unstretched: agrees" in detail


def classify(integ, n, omega_h, thrust, kind, detail=""):
    if omega_h >= 1:
        return "coupling"
    if kind.startswith("tether gains energy"):
        return "open-energy"
    if n <= 2:
        return "open-one-two-segments"
    if kind == "MuJoCo warning" and thrust > 0:
        return "open-thrust-qacc"
    if kind.startswith("disagrees") and "started unstretched: agrees" in detail:
        return "open-stretched-start"
    if kind.startswith("disagrees"):
        return "open-transient"
    return "open-other"


BANDS = [0, 0.1, 0.25, 0.5, 1, 2, 5, float("inf")]


def print_bands(seen):
    """Rates by integrator and omega h band, as the refusal limits and warnings quote them."""
    table = {}
    for (seed, draw), m in seen.items():
        integ, omega_h = m.group(4), float(m.group(8))
        passed, kind = m.group(11) == "pass", m.group(12)
        band = max(i for i in range(len(BANDS) - 1) if omega_h >= BANDS[i])
        if passed and kind.startswith("refused"):
            cat = "refused"
        elif passed and kind.startswith("diverged"):
            cat = "diverged"
        else:
            cat = "ran" if passed else "failed"
        table.setdefault((integ, band), Counter())[cat] += 1
        # A run that disagreed with its fine step and warned of the cause (the fuzzer's warned
        # outcomes: a stretched start, thrust beyond what the tether holds, a start inside a
        # geom, a snap ringing the undamped segment mode) is counted as ran, and here too.
        if passed and kind.startswith("warned"):
            table[(integ, band)]["warned"] += 1
    print("integrator  omega h     ran  failed           refused  diverged  (warned)")
    for integ in LIMITS:
        for band in range(len(BANDS) - 1):
            c = table.get((integ, band))
            if not c:
                continue
            ran = c["ran"] + c["failed"]
            share = f"({100 * c['failed'] / ran:4.1f}%)" if ran else ""
            label = f"{BANDS[band]:g}-{BANDS[band + 1]:g}"
            print(f"{integ:10s}  {label:10s}  {ran:4d}  {c['failed']:4d} {share:9s}  "
                  f"{c['refused']:7d}  {c['diverged']:8d}  {c['warned']:8d}")


def read_log(path, lo=0, hi=float("inf")):
    """(seed, draw) -> the LINE match of its first line in a verbose log, seeds lo..hi (the
    known list's summary at the end repeats some lines). Also tools/scene_fuzz_compare.py's."""
    seen = OrderedDict()
    for raw in open(path, errors="replace"):
        m = LINE.match(raw.strip())
        if not m:
            continue
        seed, draw = int(m.group(1)), int(m.group(3) or 2)
        if (seed, draw) in seen or not lo <= seed <= hi:
            continue
        seen[(seed, draw)] = m
    return seen


def main():
    counts_only = "--counts" in sys.argv
    bands = "--bands" in sys.argv
    lo, hi = 0, float("inf")
    args = sys.argv[1:]
    if "--seeds" in args:
        i = args.index("--seeds")
        lo, hi = (int(x) for x in args[i + 1].split("-"))
        del args[i:i + 2]
    path = [a for a in args if not a.startswith("--")][0]
    seen = read_log(path, lo, hi)
    if bands:
        print_bands(seen)
        return
    outcomes, classes = Counter(), Counter()
    lines = {c: [] for c in CLASSES}
    for (seed, draw), m in seen.items():
        integ, n, ea, mass = m.group(4), int(m.group(5)), float(m.group(6)), float(m.group(7))
        omega_h, sb, thrust = float(m.group(8)), m.group(9), float(m.group(10))
        passed, kind, detail = m.group(11) == "pass", m.group(12), m.group(13)
        if not passed and warned_stretched(passed, kind, detail):
            outcomes["pass  " + WARNED + " (old log)"] += 1
            continue
        outcomes[("pass  " if passed else "FAIL  ") + kind] += 1
        if passed:
            continue
        c = classify(integ, n, omega_h, thrust, kind, detail)
        classes[c] += 1
        detail = re.sub(r"Nan, Inf or huge value in QACC", "bad qacc", detail)
        detail = re.sub(r" The simulation is unstable\.", "", detail)
        tag = f"{seed:<5} " + ("draw=1  " if draw == 1 else "")
        lines[c].append(f"{tag}{c} omega*h={omega_h:.2g} {integ} (limit {LIMITS[integ]}), N={n}, "
                        f"EA={ea:.3g}, {mass:.3g} kg, seabed kind {sb}, thrust {thrust:.2f} EA: "
                        f"{kind}: {detail}"[:230])
    if counts_only:
        print(f"{len(seen)} scenes")
        for k, v in sorted(outcomes.items()):
            print(f"  {v:5d}  {k}")
        print("failures by class:")
        for c in CLASSES:
            print(f"  {classes[c]:5d}  {c}")
        return
    for c in CLASSES:
        for l in lines[c]:
            print(l)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Compares two verbose scene fuzzer logs seed by seed (a change's effect on the long runs).

  tools/scene_fuzz_compare.py BEFORE.log AFTER.log [--first F --last L]

The logs are MJTETHER_SCENE_FUZZ_VERBOSE=1 runs of build/tests/scene_fuzz_test (the commands are
in docs/scene_fuzzer.md, "Long runs"). Printed:
  - the failures in each log and the seeds fixed and new (in the seed range given, draw 0);
  - the passes whose outcome changed kind (e.g. "diverged" to "agrees");
  - per integrator, with and without thrust: how many scenes' figures moved, how many came
    closer to their fine-step self and how many went further. A scene's figure is the larger of
    position error/tolerance and tension error/tolerance against its 10x smaller step; the median
    position error/tolerance of the moved scenes, before and after.
The failure count hides most of a coupling change: sessions 34 and 35 moved hundreds of scenes
well inside their tolerance for one or three seeds fixed (docs/coupling.md).
"""
import argparse
import collections
import re
import statistics

from scene_fuzz_classify import read_log  # the log's line format, read once (same directory)

FIGURES = re.compile(r"position ([\d.e+-]+) m \(tol ([\d.e+-]+)\), tension ([\d.e+-]+) vs "
                     r"([\d.e+-]+) N \(tol ([\d.e+-]+)\)")


def load(path, first, last):
  """Seed -> (integrator, outcome, kind, thrust, figures) of the current draw (2), seeds
  first..last; figures: (position error/tolerance, tension error/tolerance) or None."""
  scenes = {}
  for (seed, draw), m in read_log(path, first, last).items():
    if draw != 2:
      continue
    f = FIGURES.search(m.group(13))
    figures = None
    if f:
      pos, pos_tol, t, t_ref, t_tol = map(float, f.groups())
      figures = (pos / pos_tol, abs(t - t_ref) / t_tol)
    scenes[seed] = (m.group(4), m.group(11), m.group(12).strip(), float(m.group(10)), figures)
  return scenes


def moved(x, y):
  return any(abs(a - b) > 1e-6 * max(abs(a), 1e-12) for a, b in zip(x, y))


def main():
  ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
  ap.add_argument("before")
  ap.add_argument("after")
  ap.add_argument("--first", type=int, default=0, help="first seed counted (default: all)")
  ap.add_argument("--last", type=int, default=1 << 62, help="last seed counted")
  args = ap.parse_args()
  a, b = load(args.before, args.first, args.last), load(args.after, args.first, args.last)
  seeds = sorted(s for s in a if s in b)
  fa = [s for s in seeds if a[s][1] == "FAIL"]
  fb = [s for s in seeds if b[s][1] == "FAIL"]
  print(f"{len(seeds)} seeds in both logs; failures before {len(fa)}, after {len(fb)}")
  print("fixed:", ", ".join(f"{s} ({a[s][0]})" for s in fa if s not in fb) or "none")
  print("new:  ", ", ".join(f"{s} ({b[s][0]}: {b[s][2][:40]})" for s in fb if s not in fa)
        or "none")
  kinds = collections.Counter(
      (a[s][2][:40], b[s][2][:40]) for s in seeds
      if a[s][1] == b[s][1] == "pass" and a[s][2] != b[s][2])
  print(f"passes whose outcome changed kind: {sum(kinds.values())}")
  for (x, y), n in kinds.most_common(10):
    print(f"  {n:4d}  {x} -> {y}")
  print(f"{'':24s} {'scenes':>6s} {'moved':>6s} {'closer':>6s} {'further':>7s}  "
        "median position err/tol of the moved")
  for integrator in ("implicit", "bdf2", "implicit2", "explicit", "rk4"):
    for thrust in (True, False):
      pairs = [(a[s][4], b[s][4]) for s in seeds
               if a[s][0] == integrator and (a[s][3] > 0) == thrust and a[s][4] and b[s][4]]
      if not pairs:
        continue
      changed = [(x, y) for x, y in pairs if moved(x, y)]
      closer = sum(1 for x, y in changed if max(y) < max(x))
      median = ("%.3f -> %.3f" % (statistics.median(x[0] for x, _ in changed),
                                  statistics.median(y[0] for _, y in changed))
                if changed else "-")
      name = f"{integrator} {'thrust' if thrust else 'no thrust'}"
      print(f"{name:24s} {len(pairs):6d} {len(changed):6d} {closer:6d} "
            f"{len(changed) - closer:7d}  {median}")


if __name__ == "__main__":
  main()
